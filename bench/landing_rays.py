#!/usr/bin/env python3
"""How much of a landed fovea's rays a saccade's flight puts there: landing predictors, compared cheaply.

While a saccade flies, the real-time loop places the fovea at the predicted landing
(docs/realtime.md); whatever rays it casts there that fall inside the fovea where the eye then
lands are rays that fovea no longer waits for. `bench latency` judges the result (landing →
converged fovea), but a landing's gain is whole frames, most landings gain none, and a run takes
minutes. This script measures the quantity underneath, on expert-labelled saccades: for each
labelled saccade it replays the predictor over the recording (`foveal.gaze.predict_landings`, the
loop's own), lays frames at the display's refresh from the flight's onset (at several phases),
gives each frame the rays of the loop's model clock, cast as the loop casts a fovea's (rounds of
16, 16, 32, … a pixel, n_max = 400, out from the centre), into the fovea each strategy places with
what it knows a tracker latency (one sample period + 2 ms) before the frame, and reports the share
of the landed fovea's rays (its pixels × n_max) cast before the landing.

Strategies: `eye` (the fovea where the eye is: the loop without prediction), `prediction` (at the
predicted landing), `region:R` (before the peak, the fovea stretched along the flight from the
prediction out to R times its amplitude; the tried idea of docs/realtime.md), `oracle` (at the
labelled landing: the most any predictor could put there), `oracle-pre` and `oracle-post` (at the
labelled landing only where the prediction in force was made before the velocity peak was passed,
or only after it; the prediction otherwise: where the gap to the oracle lies). Before the onset is
detected every strategy's fovea is where the eye is.

`--sample-hz` replays each recording as a slower tracker would have delivered it (every k-th
sample; its latency then one of its sample periods + 2 ms): what prediction is worth with a 60-Hz
or 120-Hz tracker, where a saccade holds a few samples.

The default recordings are Lund 2013's training part (Andersson et al. 2017; 500 Hz, 1024×768 px on
38×30 cm at 67 cm), where any constant of a predictor is chosen; the IRF recordings are test data.

    .venv/bin/python bench/landing_rays.py [--recording CSV ...] [--min-amplitude 5] [--refresh-hz 60]
        [--sample-hz HZ] [--rays-per-frame 316667] [--fovea-deg 5.7,3.7] [--px-per-deg 19.4] [--phases 3] [--seed 1]
        [--strategies eye,prediction,region:2,oracle] [--landing NAME=VALUE,...] [--json F] [--markdown F]
"""
import argparse
import json
import math
import os
import sys
from pathlib import Path

import numpy as np

import foveal
from outputs import check_outputs, write_output

N_MAX = 400
FIRST_ROUND = 16
LUND_SCREEN_PX = (1024, 768)
LUND_SCREEN_CM = (38.0, 30.0)
LUND_DISTANCE_CM = 67.0
SACCADE = 2  # Lund's label of a saccade


def read_lund(path):
    """A Lund 2013 labelled recording (t, x, y px, label): times, positions in degrees (NaN where lost), labels."""
    rows = []
    with open(path, encoding="utf-8") as f:
        header = f.readline().strip().split(",")
        if header[:3] != ["t", "x", "y"] or header[-1] != "label":
            raise ValueError(f"{path}: line 1: expected the header t,x,y,…,label of a Lund 2013 recording, got {','.join(header)}")
        for number, line in enumerate(f, start=2):
            cells = line.strip().split(",")
            if cells == [""]:
                continue
            if len(cells) != len(header):
                raise ValueError(f"{path}: line {number}: {len(cells)} cells where the header has {len(header)}")
            try:
                t, label = float(cells[0]), int(cells[-1])
                x, y = (float(c) if c else math.nan for c in cells[1:3])  # an empty cell: a lost sample
            except ValueError:
                raise ValueError(f"{path}: line {number}: expected numbers t, x, y and a whole label, got {line.strip()}") from None
            if not math.isfinite(t) or (rows and t <= rows[-1][0]):
                raise ValueError(f"{path}: line {number}: the time {cells[0]} does not rise")
            rows.append((t, x, y, label))
    if len(rows) < 2:
        raise ValueError(f"{path}: fewer than two samples")
    data = np.array(rows)
    t, x, y, label = data[:, 0], data[:, 1], data[:, 2], data[:, 3].astype(int)
    lost = ((x == 0) & (y == 0)) | ~np.isfinite(x) | ~np.isfinite(y)
    deg = np.stack([np.degrees(np.arctan((x / LUND_SCREEN_PX[0] - 0.5) * LUND_SCREEN_CM[0] / LUND_DISTANCE_CM)),
                    np.degrees(np.arctan((y / LUND_SCREEN_PX[1] - 0.5) * LUND_SCREEN_CM[1] / LUND_DISTANCE_CM))], 1)
    deg[lost] = np.nan
    return t, deg, label


def every_kth(path, t, deg, label, sample_hz):
    """The samples a tracker at `sample_hz` would have delivered: every k-th, k the recording's rate over `sample_hz`,
    rounded. A label is that of the sample kept, so a saccade keeps the samples that fall inside it."""
    native = 1.0 / float(np.median(np.diff(t)))
    if sample_hz > native * 1.01:
        raise ValueError(f"{sample_hz:g} Hz is faster than {os.path.basename(path)}'s own {native:.0f} Hz")
    k = max(1, int(round(native / sample_hz)))
    return t[::k], deg[::k], label[::k]


def labelled_saccades(t, deg, label, min_amplitude):
    """(first, last) sample of each labelled saccade at least min_amplitude degrees long (from the sample before it)."""
    out = []
    i = 0
    while i < len(label):
        if label[i] != SACCADE:
            i += 1
            continue
        j = i
        while j + 1 < len(label) and label[j + 1] == SACCADE:
            j += 1
        start = deg[max(i - 1, 0)]
        amplitude = float(np.hypot(*(deg[j] - start)))
        if math.isfinite(amplitude) and amplitude >= min_amplitude:
            out.append((i, j))
        i = j + 1
    return out


def segment_distance(px, py, a, b):
    """Distance of points (px, py) from the segment a → b (degrees)."""
    d = b - a
    length2 = float(d @ d)
    if length2 == 0:
        return np.hypot(px - a[0], py - a[1])
    s = np.clip(((px - a[0]) * d[0] + (py - a[1]) * d[1]) / length2, 0, 1)
    return np.hypot(px - a[0] - s * d[0], py - a[1] - s * d[1])


def inside(px, py, a, b, axes):
    """Points within the fovea's ellipse (semi-axes `axes`, degrees) of some point of the segment a → b."""
    sx, sy = axes
    return segment_distance(px / sx, py / sy, a / np.array([sx, sy]), b / np.array([sx, sy])) < 1


def cast_frame(cast, order, budget):
    """Cast `budget` rays into the pixels `order` (flat indices) in the loop's rounds: each pass gives every
    pixel short of n_max min(n_max − c, max(16, c)) more, in order, until the budget is spent."""
    c = cast.reshape(-1)
    while budget > 0 and len(order):
        need = np.minimum(N_MAX - c[order], np.maximum(FIRST_ROUND, c[order]))
        open_ = need > 0
        order, need = order[open_], need[open_]
        if not len(order):
            break
        total = np.cumsum(need)
        k = int(np.searchsorted(total, budget, side="right"))
        c[order[:k]] += need[:k]
        budget -= int(total[k - 1]) if k else 0
        if k < len(order):
            c[order[k]] += budget
            budget = 0


def flight_start(flight, t, deg):
    """Where the eye was at the flight's onset (a sample's time)."""
    return deg[int(np.searchsorted(t, flight["onset_s"]))]


def simulate(flight, t, deg, first, last, strategy, phase, a):
    """The share of the landed fovea's rays that frames at `phase` after the flight's onset cast before the landing."""
    end = deg[last]
    onset = flight["onset_s"]
    start = flight_start(flight, t, deg)
    pred_t = np.asarray(flight["prediction_s"])
    pred = np.stack([np.asarray(flight["prediction_x_deg"]), np.asarray(flight["prediction_y_deg"])], 1)
    points = np.vstack([pred, start, end, deg[first:last + 1]])
    points = points[np.all(np.isfinite(points), axis=1)]
    reach = 1.0
    if strategy.startswith("region:"):
        reach = float(strategy.split(":")[1])
        points = np.vstack([points, start + reach * (pred - start)])
    margin = np.array(a.fovea) + 1.0
    lo, hi = points.min(0) - margin, points.max(0) + margin
    step = 1.0 / a.px_per_deg
    xs = np.arange(lo[0], hi[0], step) + step / 2
    ys = np.arange(lo[1], hi[1], step) + step / 2
    X, Y = np.meshgrid(xs, ys)
    cast = np.zeros(X.shape, np.int64)
    sample_period = float(np.median(np.diff(t)))
    latency = sample_period + 0.002
    landed = t[last]
    frame = onset + phase
    while frame < landed:
        known = frame - latency
        k = int(np.searchsorted(pred_t, known, side="right")) - 1  # the latest prediction by then
        s = int(np.searchsorted(t, known, side="right")) - 1       # … and the latest sample
        centre_out = True
        if k < 0 or strategy == "eye":
            a_pt = deg[max(s, 0)]
            if not np.all(np.isfinite(a_pt)):
                frame += 1.0 / a.refresh_hz
                continue
            b_pt = a_pt
            centre_out = False  # the loop's fovea at a measured gaze goes in pixel order
        elif strategy == "oracle" or strategy == ("oracle-pre" if pred_t[k] < flight["first_prediction_s"] else "oracle-post"):
            a_pt = b_pt = end
        else:
            a_pt = b_pt = pred[k]
            if reach != 1.0 and pred_t[k] < flight["first_prediction_s"]:
                b_pt = start + reach * (pred[k] - start)
        mask = inside(X, Y, a_pt, b_pt, a.fovea)
        flat = np.flatnonzero(mask.reshape(-1))
        if centre_out:
            distance = segment_distance(X.reshape(-1)[flat], Y.reshape(-1)[flat], a_pt, b_pt)
            flat = flat[np.argsort(distance, kind="stable")]
        cast_frame(cast, flat, a.rays_per_frame)
        frame += 1.0 / a.refresh_hz
    landed_fovea = inside(X, Y, end, end, a.fovea)
    return float(np.minimum(cast, N_MAX)[landed_fovea].sum()) / (landed_fovea.sum() * N_MAX)


def prediction_errors(flight, t, deg, last):
    """Each prediction's distance from the labelled landing along the flight (onset → prediction) and across it,
    with whether it was made before the peak was passed."""
    start, end = flight_start(flight, t, deg), deg[last]
    out = []
    for ts, x, y in zip(flight["prediction_s"], flight["prediction_x_deg"], flight["prediction_y_deg"]):
        pred = np.array([x, y])
        d = pred - start
        length = float(np.hypot(*d))
        if not length >= 0.5:
            continue
        u = d / length
        e = end - pred
        out.append((bool(ts < flight["first_prediction_s"]), abs(float(e @ u)), abs(float(e @ np.array([-u[1], u[0]])))))
    return out


def pre_peak_features(flight, t, deg, last):
    """For each prediction made before the velocity peak was passed: the flight so far (distance from its start, velocity
    over the latest interval, time since the onset) and the labelled amplitude, to ask how much the flight then says of it."""
    start, end = flight_start(flight, t, deg), deg[last]
    amplitude = float(np.hypot(*(end - start)))
    out = []
    for ts in flight["prediction_s"]:
        if ts >= flight["first_prediction_s"]:
            continue
        k = int(np.searchsorted(t, ts, side="right")) - 1
        if k < 1:
            continue
        distance = float(np.hypot(*(deg[k] - start)))
        velocity = float(np.hypot(*(deg[k] - deg[k - 1]))) / float(t[k] - t[k - 1])
        since = ts - flight["onset_s"]
        if distance > 0.1 and velocity > 1 and since > 0 and amplitude > 0:
            out.append((distance, velocity, since, amplitude))
    return out


def amplitude_regression(features, groups):
    """log amplitude ~ 1 + log distance + log velocity + log time, least squares: the share of its variance the flight before
    the peak explains (R²), and the error of the fitted amplitude left out one recording at a time (degrees, median and p90)."""
    f = np.asarray(features, float)
    groups = np.asarray(groups)
    design = np.column_stack([np.ones(len(f)), np.log(f[:, 0]), np.log(f[:, 1]), np.log(f[:, 2])])
    y = np.log(f[:, 3])
    coef, *_ = np.linalg.lstsq(design, y, rcond=None)
    r2 = 1 - float(np.var(y - design @ coef)) / float(np.var(y))
    error = np.full(len(f), np.nan)
    constant = np.full(len(f), np.nan)  # the same, from the other recordings' median amplitude alone
    for g in np.unique(groups):
        held = groups == g
        if held.all():
            continue
        c, *_ = np.linalg.lstsq(design[~held], y[~held], rcond=None)
        error[held] = np.abs(np.exp(design[held] @ c) - f[held, 3])
        constant[held] = np.abs(np.median(f[~held, 3]) - f[held, 3])
    error, constant = error[np.isfinite(error)], constant[np.isfinite(constant)]
    return {"predictions": int(len(f)), "r2": r2, "slopes": [float(v) for v in coef[1:]],
            "held_out_error_deg_median": float(np.median(error)) if len(error) else None,
            "held_out_error_deg_p90": float(np.percentile(error, 90)) if len(error) else None,
            "constant_error_deg_median": float(np.median(constant)) if len(constant) else None,
            "constant_error_deg_p90": float(np.percentile(constant, 90)) if len(constant) else None}


def main():
    here = Path(__file__).resolve().parent.parent
    lund = here.parent / "shared" / "data" / "eye-movements" / "lund2013-train"
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--recording", action="append",
                   help="a Lund 2013 labelled recording (repeatable; default: the eleven *_MN.csv of the training part)")
    p.add_argument("--min-amplitude", type=float, default=5.0, help="labelled saccades at least this long, degrees (5)")
    p.add_argument("--refresh-hz", type=float, default=60.0, help="the display's refresh rate (60)")
    p.add_argument("--sample-hz", type=float,
                   help="replay each recording as a slower tracker would deliver it: every k-th sample, k the recording's "
                        "rate over this one, rounded (default: every sample)")
    p.add_argument("--rays-per-frame", type=int, default=316667,
                   help="AO rays a frame (316667: the model clock's 25,000 rays/ms over a 16.7-ms frame less 4 ms)")
    p.add_argument("--fovea-deg", default="5.7,3.7",
                   help="the fovea's semi-axes, degrees (5.7,3.7: the q = 1 region of the default display and foveation)")
    p.add_argument("--px-per-deg", type=float, default=19.4, help="render pixels a degree (19.4: 840 px on the default display)")
    p.add_argument("--phases", type=int, default=3, help="frame phases per saccade, drawn at random (3)")
    p.add_argument("--seed", type=int, default=1, help="the phases' seed (1)")
    p.add_argument("--strategies", default="eye,prediction,region:2,oracle",
                   help="eye, prediction, region:R, oracle, oracle-pre, oracle-post (comma-separated)")
    p.add_argument("--landing", default="", metavar="NAME=VALUE,…",
                   help="the landing predictor's parameters, as --landing of bench latency (default: its own)")
    p.add_argument("--json", help="write every saccade's share per strategy as JSON")
    p.add_argument("--markdown", help="write the table as Markdown")
    a = p.parse_args()
    recordings = a.recording or [str(f) for f in sorted(lund.glob("*/*_MN.csv"))]
    if not recordings:
        p.error(f"no recordings: give --recording, or place Lund 2013's training part at {lund}")
    for name, value in (("--refresh-hz", a.refresh_hz), ("--px-per-deg", a.px_per_deg)):
        if not (math.isfinite(value) and value > 0):
            p.error(f"{name}: must be a finite number > 0, got {value}")
    if a.sample_hz is not None and not (math.isfinite(a.sample_hz) and a.sample_hz > 0):
        p.error(f"--sample-hz: must be a finite number > 0, got {a.sample_hz}")
    if not (math.isfinite(a.min_amplitude) and a.min_amplitude >= 0):
        p.error(f"--min-amplitude: must be a finite number >= 0, got {a.min_amplitude}")
    if a.rays_per_frame <= 0:
        p.error(f"--rays-per-frame: must be > 0, got {a.rays_per_frame}")
    if a.phases <= 0:
        p.error(f"--phases: must be > 0, got {a.phases}")
    try:
        a.fovea = tuple(float(v) for v in a.fovea_deg.split(","))
        assert len(a.fovea) == 2 and all(math.isfinite(v) and v > 0 for v in a.fovea)
    except (ValueError, AssertionError):
        p.error(f"--fovea-deg: expected two semi-axes in degrees, X,Y > 0, got {a.fovea_deg}")
    strategies = [s.strip() for s in a.strategies.split(",") if s.strip()]
    for s in strategies:
        if s in ("eye", "prediction", "oracle", "oracle-pre", "oracle-post"):
            continue
        if s.startswith("region:"):
            try:
                if float(s.split(":")[1]) >= 1:
                    continue
            except ValueError:
                pass
        p.error(f"--strategies: {s}: expected eye, prediction, region:R (R >= 1), oracle, oracle-pre or oracle-post")
    try:
        landing = foveal.gaze.landing_params(a.landing)
    except ValueError as error:
        p.error(f"--landing: {error}")
    check_outputs(p, [("--json", a.json), ("--markdown", a.markdown)], recordings)

    rng = np.random.default_rng(a.seed)
    rows = []
    rates = []
    labelled = 0
    errors = []
    features, groups = [], []
    for path in recordings:
        try:
            t, deg, label = read_lund(path)
        except (OSError, ValueError) as error:
            sys.exit(f"landing_rays.py: error: {error}")
        if a.sample_hz is not None:
            try:
                t, deg, label = every_kth(path, t, deg, label, a.sample_hz)
            except ValueError as error:
                p.error(f"--sample-hz: {error}")
        rates.append(1.0 / float(np.median(np.diff(t))))
        try:
            flights = foveal.gaze.predict_landings(t, deg, **landing)
        except ValueError as error:  # samples under 20 Hz: no onset shows, so such a tracker sees no saccade
            if a.sample_hz is None:
                sys.exit(f"landing_rays.py: error: {path}: {error}")
            flights = []
        found = 0
        saccades = labelled_saccades(t, deg, label, a.min_amplitude)
        labelled += len(saccades)
        for first, last in saccades:
            flight = next((f for f in flights if t[first] - 0.02 <= f["onset_s"] <= t[last]), None)
            if flight is None or not len(flight["prediction_s"]):
                continue
            found += 1
            errors += prediction_errors(flight, t, deg, last)
            before_peak = pre_peak_features(flight, t, deg, last)
            features += before_peak
            groups += [path] * len(before_peak)
            phases = rng.uniform(0, 1.0 / a.refresh_hz, a.phases)
            share = {s: float(np.mean([simulate(flight, t, deg, first, last, s, ph, a) for ph in phases])) for s in strategies}
            rows.append({"recording": os.path.basename(path), "onset_s": float(t[first]), "landing_s": float(t[last]),
                         "amplitude_deg": float(np.hypot(*(deg[last] - deg[max(first - 1, 0)]))), "share": share})
        print(f"{os.path.basename(path)}: {len(saccades)} labelled saccades >= {a.min_amplitude:g} deg, {found} seen by the predictor",
              file=sys.stderr)
    if not rows:
        sys.exit("landing_rays.py: error: no labelled saccade the predictor saw")
    rate = f"{min(rates):.0f} Hz" if round(min(rates)) == round(max(rates)) else f"{min(rates):.0f}–{max(rates):.0f} Hz"
    lines = [f"{len(rows)} of {labelled} labelled saccades >= {a.min_amplitude:g} deg seen by the predictor (samples at {rate}), "
             f"display {a.refresh_hz:g} Hz, {a.rays_per_frame} rays a frame, "
             f"fovea {a.fovea[0]:g} x {a.fovea[1]:g} deg, {a.phases} phases each", "",
             "| strategy | share of the landed fovea's rays cast before the landing, mean | median |", "|---|---:|---:|"]
    for before, when in ((True, "before the peak was passed"), (False, "after")):
        e = np.array([(along, across) for b, along, across in errors if b == before]).reshape(-1, 2)
        if len(e):
            lines.insert(1, f"predictions made {when}: {len(e)}, the labelled landing a median {np.median(e[:, 0]):.2f} deg "
                            f"from them along the flight and {np.median(e[:, 1]):.2f} deg across it")
    regression = amplitude_regression(features, groups) if len(features) >= 8 else None
    if regression:
        held_out = (f"; fitted on the other recordings, the amplitude {regression['held_out_error_deg_median']:.2f} deg off "
                    f"(median; p90 {regression['held_out_error_deg_p90']:.2f}), their median amplitude alone "
                    f"{regression['constant_error_deg_median']:.2f} (p90 {regression['constant_error_deg_p90']:.2f})"
                    ) if regression["held_out_error_deg_median"] is not None else ""
        lines.insert(1, f"before the peak, the flight so far (log distance, velocity, time since the onset) explains "
                        f"{100 * regression['r2']:.0f} % of the variance of log amplitude over {regression['predictions']} predictions"
                        f"{held_out}")
    summary = {}
    for s in strategies:
        v = np.array([r["share"][s] for r in rows])
        summary[s] = {"mean": float(v.mean()), "median": float(np.median(v))}
        lines.append(f"| {s} | {100 * v.mean():.2f} % | {100 * np.median(v):.2f} % |")
    text = "\n".join(lines) + "\n"
    print(text)
    if a.markdown:
        write_output(a.markdown, text)
    if a.json:
        write_output(a.json, json.dumps({"recordings": [os.path.basename(r) for r in recordings], "refresh_hz": a.refresh_hz,
                                         "sample_hz": [float(r) for r in rates], "labelled_saccades": labelled,
                                         "rays_per_frame": a.rays_per_frame, "fovea_deg": list(a.fovea), "px_per_deg": a.px_per_deg,
                                         "phases": a.phases, "seed": a.seed, "landing": landing, "summary": summary,
                                         "pre_peak_amplitude_regression": regression,
                                         "saccades": rows}, indent=1) + "\n")


if __name__ == "__main__":
    main()
