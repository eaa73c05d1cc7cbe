#!/usr/bin/env python3
"""Prediction's gain over whole recordings, a fresh loop every segment: `bench latency` pooled.

`foveal bench latency` judges each saccade's landing → converged fovea on one segment of each
recording. A loop that has run for a while has converged most places the eye returns to, so most
landings find their fovea converged and the median is 0 ms with or without prediction; on a single
10-s segment, where landings still wait, the median rests on six to eight saccades. This script
runs the bench on consecutive segments of each recording (each segment a fresh loop: the first
seconds of a session, a fresh view), pools every judged saccade per recording and loop, and gives
the pooled median landing → converged fovea per loop, what prediction (and a perfect predictor,
with `deadline+oracle`) gains over the loop without it, beside a third of the pooled median
saccade, and how many saccades each made better or worse. A saccade whose fovea did not converge
within its segment counts as the longest, as in the bench.

How far the median's gain can be trusted: the landings of a segment share one loop, so the
interval resamples whole segments (a cluster bootstrap, Davison & Hinkley 1997, "Bootstrap Methods
and their Application", section 3.8), 2,000 times with a fixed seed, and gives the 2.5th and 97.5th
percentiles of the gain in the median (`gain_interval_ms` in the JSON). Landing → converged times
cluster at 0 ms (a place already converged) and at hundreds of ms (a fresh fovea), so the median
can sit in a sparse middle where one landing decides it: the interval says how far it could move.

    .venv/bin/python bench/latency_segments.py [--recording REC ...] [--segment 10] [--first 2]
        [--count N] [--loops deadline,deadline+prediction] [--clock model] [--model-rays-per-ms 25000]
        [--model-fixed-ms 4] [--size 840x525] [--scene scenes/dragon-box.json] [--landing NAME=VALUE,…]
        [--periphery-share S] [--no-rays-ahead] [--json F] [--markdown F]

The defaults are BENCHMARKS.md's: the EyeLink recording and IRF S1 and S2, the model clock (the
same figures on any machine), 10-s segments from 2 s on, as many as each recording holds.
"""
import argparse
import json
import math
import os
import random
import statistics
import sys
import time
from pathlib import Path

import foveal
from outputs import check_outputs, refuse_by_option, write_output



def as_ms(value):
    """A landing → converged time, with a saccade never converged (None) as the longest, as the bench counts it."""
    return math.inf if value is None else value


def pooled_median(values):
    """The median with a saccade never converged (None) counted as the longest, as the bench counts it."""
    if not values:
        return None
    m = statistics.median(as_ms(v) for v in values)
    return None if math.isinf(m) else m


def bootstrap_gain(base, other, segment_of, resamples=2000, seed=1):
    """The 2.5th and 97.5th percentiles of median(base) − median(other) over resamples of whole segments.

    base and other: each saccade's landing → converged ms in the two loops (None: never converged);
    segment_of: each saccade's segment. Segments are drawn with replacement, as many as there are,
    and each draw takes every saccade of its segment in both loops (paired). None, or an interval
    of ±inf where a resample's median is a saccade never converged in one loop only.
    """
    segments = sorted(set(segment_of))
    if not segments:
        return None
    members = {g: [i for i, s in enumerate(segment_of) if s == g] for g in segments}
    rng = random.Random(seed)
    gains = []
    for _ in range(resamples):
        picked = [i for g in (rng.choice(segments) for _ in segments) for i in members[g]]
        a = statistics.median(as_ms(base[i]) for i in picked)
        b = statistics.median(as_ms(other[i]) for i in picked)
        gains.append(0.0 if a == b else a - b)  # (two medians never converged: no gain either way)
    gains.sort()
    return [gains[int(0.025 * (resamples - 1))], gains[int(math.ceil(0.975 * (resamples - 1)))]]


def interval_text(interval):
    if interval is None:
        return ""
    show = lambda v: "∞" if v == math.inf else "−∞" if v == -math.inf else f"{v:.0f}".replace("-", "−")
    return f" (95 %: {show(interval[0])} to {show(interval[1])})"


def main():
    here = Path(__file__).resolve().parent.parent
    data = here.parent / "shared" / "data"
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--recording", action="append", help="a recording (repeatable; default: the EyeLink recording, IRF S1 and S2)")
    p.add_argument("--segment", type=float, default=10.0, help="seconds per segment (10)")
    p.add_argument("--first", type=float, default=2.0, help="the first segment's start, seconds (2)")
    p.add_argument("--count", type=int, default=0, help="at most this many segments per recording (0: as many as it holds)")
    p.add_argument("--loops", default="deadline,deadline+prediction", help="the loops, as bench latency's --loops; deadline among them")
    p.add_argument("--clock", default="model", choices=["model", "wall"], help="the bench's clock (model)")
    p.add_argument("--model-rays-per-ms", type=float, default=25000.0, help="the model clock's tracing rate (25000)")
    p.add_argument("--model-fixed-ms", type=float, default=4.0, help="the model clock's fixed part of each frame (4)")
    p.add_argument("--size", default="840x525", help="render size WxH (840x525)")
    p.add_argument("--scene", default=str(here / "scenes" / "dragon-box.json"), help="the scene (the dragon box)")
    p.add_argument("--landing", default="", help="the prediction loops' landing predictor's parameters, NAME=VALUE,… (as bench latency's)")
    p.add_argument("--periphery-share", type=float, default=None,
                   help="the deadline loops' periphery: its rays until the frame has spent this share of its budget (as bench latency's; the loop's 1)")
    p.add_argument("--no-rays-ahead", action="store_true",
                   help="the deadline loops cast nothing once every pixel has its n(E) (as bench latency's)")
    p.add_argument("--json", help="write the pooled figures and every saccade as JSON")
    p.add_argument("--markdown", help="write the table as Markdown")
    a = p.parse_args()
    recordings = a.recording or [str(data / "gaze/eyelink/monoRemote500.asc"),
                                 str(data / "eye-movements/irf/lookAtPoint_EL_S1.csv"),
                                 str(data / "eye-movements/irf/lookAtPoint_EL_S2.csv")]
    for r in recordings:
        if not Path(r).is_file():
            p.error(f"--recording: {r} does not exist")
    loops = [l.strip() for l in a.loops.split(",") if l.strip()]
    if "deadline" not in loops or len(loops) < 2:
        p.error("--loops: give deadline and at least one loop to compare with it")
    if not (a.segment > 0 and a.first >= 0):
        p.error("--segment must be > 0 and --first >= 0")
    if a.count < 0:
        p.error(f"--count: must be 0 (every segment) or more, got {a.count}")
    try:
        width, height = (int(v) for v in a.size.lower().split("x"))
    except ValueError:
        p.error(f"--size: {a.size} is not WxH")
    check_outputs(p, [("--json", a.json), ("--markdown", a.markdown)], recordings + [a.scene])
    try:
        landing = foveal.gaze.landing_params(a.landing)
    except ValueError as error:
        p.error(f"--landing: {error}")
    try:
        scene = foveal.Scene(a.scene)
    except (OSError, ValueError) as error:
        p.error(f"--scene: {error}")
    read = {}
    for r in recordings:
        try:
            read[r] = foveal.gaze.read(r)
        except (OSError, ValueError) as error:
            p.error(f"--recording: {error}")
    length = {r: float(rec.samples["t_s"][-1] - rec.samples["t_s"][0]) for r, rec in read.items()}
    model = dict(model_rays_per_ms=a.model_rays_per_ms, model_fixed_ms=a.model_fixed_ms) if a.clock == "model" else {}
    short = [r for r in recordings if a.first + a.segment > length[r]]
    if len(short) == len(recordings):
        p.error(f"--segment: no {a.segment:g}-s segment from {a.first:g} s fits in any recording (the longest is {max(length.values()):.1f} s)")
    for r in short:
        print(f"{r}: {length[r]:.1f} s, shorter than one segment from {a.first:g} s; left out", file=sys.stderr)
    recordings = [r for r in recordings if r not in short]
    pooled = {r: {l: [] for l in loops} for r in recordings}
    durations = {r: [] for r in recordings}
    segments = {r: 0 for r in recordings}
    start = a.first
    began = time.perf_counter()
    while True:
        these = [r for r in recordings if start + a.segment <= length[r] and (a.count <= 0 or segments[r] < a.count)]
        if not these:
            break
        print(f"segment {start:g}–{start + a.segment:g} s: {len(these)} recording(s) ({time.perf_counter() - began:.0f} s so far)",
              file=sys.stderr, flush=True)
        try:  # (its arguments are checked before any tracing: a bad one stops the first segment at once)
            report = foveal.bench_latency(these, scene, size=(width, height), start_s=start, duration_s=a.segment, clock=a.clock,
                                          loops=loops, landing=landing, periphery_share=a.periphery_share,
                                          rays_ahead=not a.no_rays_ahead, **model)
        except ValueError as error:
            refuse_by_option(p, error, {"size": "--size", "loops": "--loops", "model_rays_per_ms": "--model-rays-per-ms",
                                        "model_fixed_ms": "--model-fixed-ms", "duration_s": "--segment", "start_s": "--first",
                                        "periphery_share": "--periphery-share"})
        for r, rec in zip(these, report["recordings"]):
            segments[r] += 1
            for l in loops:
                for s in rec[l]["saccades"]:
                    pooled[r][l].append({"segment_start_s": start, **{k: s[k] for k in (
                        "amplitude_deg", "duration_ms", "landing_s", "landing_to_converged_ms", "fixation_ms")}})
            durations[r] += [s["duration_ms"] for s in rec["deadline"]["saccades"]]
        start += a.segment
    out = {"clock": a.clock, "segment_s": a.segment, "first_s": a.first, "size": [width, height], "scene": a.scene,
           "loops": loops, "landing": landing, "periphery_share": a.periphery_share, "rays_ahead": not a.no_rays_ahead,
           "recordings": []}
    if a.clock == "model":
        out["model"] = {"rays_per_ms": a.model_rays_per_ms, "fixed_ms": a.model_fixed_ms}
    header = "| recording (segments, saccades) | " + " | ".join(f"`{l}` median ms" for l in loops) + \
             " | gained in the median | a third of the median saccade | saccades better / worse |"
    rows = [header, "|---|" + "---:|" * (len(loops) + 3)]
    for r in recordings:
        base = [s["landing_to_converged_ms"] for s in pooled[r]["deadline"]]
        medians = {l: pooled_median([s["landing_to_converged_ms"] for s in pooled[r][l]]) for l in loops}
        third = statistics.median(durations[r]) / 3 if durations[r] else None
        entry = {"recording": r, "segments": segments[r], "saccades": len(base), "median_landing_to_converged_ms": medians,
                 "third_of_median_saccade_ms": third, "gain_ms": {}, "gain_interval_ms": {}, "better": {}, "worse": {},
                 "saccade_list": pooled[r]}
        segment_of = [s["segment_start_s"] for s in pooled[r]["deadline"]]
        gains, counts = [], []
        for l in loops[1:] if loops[0] == "deadline" else [x for x in loops if x != "deadline"]:
            gain = None if medians["deadline"] is None or medians[l] is None else medians["deadline"] - medians[l]
            other = [s["landing_to_converged_ms"] for s in pooled[r][l]]
            better = sum(as_ms(o) < as_ms(b) - 0.5 for b, o in zip(base, other))
            worse = sum(as_ms(o) > as_ms(b) + 0.5 for b, o in zip(base, other))
            interval = bootstrap_gain(base, other, segment_of)
            entry["gain_ms"][l], entry["better"][l], entry["worse"][l] = gain, better, worse
            entry["gain_interval_ms"][l] = None if interval is None else [v if math.isfinite(v) else None for v in interval]
            gains.append(f"{l}: {'—' if gain is None else f'{gain:.0f} ms'}{interval_text(interval)}")
            counts.append(f"{l}: {better} / {worse}")
        out["recordings"].append(entry)
        cells = " | ".join("—" if medians[l] is None else f"{medians[l]:.0f}" for l in loops)
        rows.append(f"| {Path(r).name} ({segments[r]}, {len(base)}) | {cells} | {'; '.join(gains)} | "
                    f"{'—' if third is None else f'{third:.0f} ms'} | {'; '.join(counts)} |")
    table = "\n".join(rows) + "\n"
    print(table)
    if a.markdown:
        write_output(a.markdown, table)
    if a.json:
        write_output(a.json, json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
