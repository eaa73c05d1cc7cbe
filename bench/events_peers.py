#!/usr/bin/env python3
"""foveal's event detectors against REMoDNaV and pymovements, on two hand-labelled data sets.

  IRF   Zemblys et al. 2018: six 1000 Hz EyeLink recordings of a looking-at-points task, one coder.
  Lund  Andersson et al. 2017, training part: eleven 500 Hz SMI recordings of free viewing of
        images, moving dots and video, each labelled by two coders (MN and RA).

Every detector labels the same samples; every labelling is scored by the same code (foveal gaze
--events file:LABELS --evaluate CODER: sample-level Cohen's kappa per class, event F1 with Hooge et
al. 2018 matching). On Lund each labelling is scored against both coders, and the coders against
each other (the ceiling: how well two experts agree). The peers are installed by this benchmark
into their own virtual environment (never a dependency of foveal), pinned, and run with their
documented defaults; on IRF also REMoDNaV without pursuit (a looking-at-points task). A peer that
fails on a recording is listed, and the means are given twice: over the recordings each method
completed, and over the recordings every method completed.

foveal's detectors: nhr (the recommended, = auto), nhp, nh, ek, ivt, idt, and ivvt (the causal
filter replay and view follow the eye with).

    python3 bench/events_peers.py [--foveal build/foveal] [--shared ../shared] [--quick] [--out DIR]
                                  [--picture PNG]

Writes OUT/events_peers.json and OUT/events_peers.md (the tables for BENCHMARKS.md). --quick: two
recordings per data set. Run times are per 10^6 samples of the detection alone (no file reading), on
one core, on the IRF recordings.
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

PEERS = ["remodnav==1.1.2", "pymovements==0.28.0", "matplotlib==3.10.7"]
FOVEAL = ["nhr", "nhp", "nh", "ek", "ivt", "idt", "ivvt"]
CLASSES = ["fixation", "saccade", "pso", "pursuit", "blink"]
DATASETS = {
    # name: display (W_CM,H_CM,DIST_CM,RES_X,RES_Y), extra CLI options, coders
    "irf": {"display": "53.3,30.1,56.5,1920,1080", "options": [], "coders": ["expert"]},
    "lund": {"display": "38,30,67,1024,768", "options": ["--coords", "px"], "coders": ["MN", "RA"]},
}


def recordings(shared, quick):
    """[(dataset, stimulus, stem, samples file, {coder: labels file})]"""
    out = []
    irf = shared / "data/eye-movements/irf"
    files = sorted(irf.glob("lookAtPoint_EL_S*.csv"))
    for f in files[:2] if quick else files:
        out.append(("irf", "points", f.stem, f, {"expert": f}))
    lund = shared / "data/eye-movements/lund2013-train"
    for stimulus in ["img", "dots", "video"]:
        files = sorted((lund / stimulus).glob("*_MN.csv"))
        for f in files[:1] if quick else files:
            ra = f.with_name(f.name.replace("_MN.csv", "_RA.csv"))
            out.append(("lund", stimulus, f.stem.replace("_labelled_MN", ""), f, {"MN": f, "RA": ra}))
    return out


def degrees(dataset, row):
    """A sample's position in degrees from the screen centre (NaN where lost)."""
    if dataset == "irf":
        return (float(row["x_deg"]) if row["x_deg"] else math.nan, float(row["y_deg"]) if row["y_deg"] else math.nan)
    w, h, d, rx, ry = [float(v) for v in DATASETS["lund"]["display"].split(",")]
    if not row["x"]:
        return (math.nan, math.nan)
    x = (float(row["x"]) + 0.5 - rx / 2) * w / rx
    y = (float(row["y"]) + 0.5 - ry / 2) * h / ry
    return (math.degrees(math.atan2(x, d)), -math.degrees(math.atan2(y, d)))


def peer_worker(out_dir, jobs):
    """Inside the peers' environment: per-sample labels of every peer configuration, per recording."""
    import logging
    import numpy as np
    import pymovements as pm
    from pymovements.transforms.numpy import pos2vel
    from remodnav.clf import EyegazeClassifier
    for name in ["remodnav", "remodnav.clf"]:  # its per-saccade warnings would bury the report
        logging.getLogger(name).setLevel(logging.ERROR)
    report = {"timings": {}, "failures": {}}

    def save(name, stem, t, labels):
        with open(Path(out_dir) / f"{stem}.{name}.csv", "w") as f:
            f.write("t_s,label\n")
            for ti, li in zip(t, labels):
                f.write(f"{ti:.6f},{li}\n")

    remodnav_map = {"FIXA": "fixation", "PURS": "pursuit", "SACC": "saccade", "ISAC": "saccade", "HPSO": "pso", "IHPS": "pso",
                    "LPSO": "pso", "ILPS": "pso"}
    for job in jobs:
        dataset, stem, path = job.split("|")
        rows = list(csv.DictReader(open(path)))
        t = np.array([float(r.get("t_s") or r.get("t")) for r in rows])
        pos = np.array([degrees(dataset, r) for r in rows])
        x, y = pos[:, 0], pos[:, 1]
        lost = np.isnan(x) | np.isnan(y)
        n = len(t)
        rate = 1.0 / np.median(np.diff(t))
        # REMoDNaV (Dar, Wagner & Hanke 2021): positions in units of 0.01° with px2deg 0.01, so its
        # angles are the recording's degrees (Lund: the same as its pixels with px2deg from the
        # geometry, to within the screen's curvature)
        configs = [("remodnav", {})] + ([("remodnav-nopursuit", {"pursuit_velthresh": 1000.0})] if dataset == "irf" else [])
        for name, kwargs in configs:
            data = np.rec.fromarrays([x / 0.01, y / 0.01], names="x,y")
            start = time.perf_counter()
            try:
                clf = EyegazeClassifier(px2deg=0.01, sampling_rate=rate, **kwargs)
                events = clf(clf.preproc(data), classify_isp=True, sort_events=True)
            except Exception as e:  # a peer's failure is a result: listed, not hidden
                report["failures"].setdefault(name, {})[stem] = f"{type(e).__name__}: {e}"
                continue
            elapsed = time.perf_counter() - start
            labels = np.array(["undefined"] * n, dtype=object)
            for ev in events:
                a, b = int(round(ev["start_time"] * rate)), int(round(ev["end_time"] * rate))
                labels[a:b] = remodnav_map.get(ev["label"], "undefined")
            labels[lost] = "blink"  # the same loss rule as foveal's ivt/idt baseline
            save(name, stem, t, labels)
            report["timings"].setdefault(name, []).append((elapsed, n))
        # pymovements: I-VT and I-DT (fixations; the other valid samples saccades) and Engbert's
        # microsaccades (saccades; the rest fixations), defaults; timesteps in ms
        ms = np.round(t * 1000).astype(np.int64)
        for name, method in [("pymovements-ivt", "ivt"), ("pymovements-idt", "idt"), ("pymovements-microsaccades", "microsaccades")]:
            start = time.perf_counter()
            try:
                if method == "idt":
                    events = pm.events.idt(positions=pos, timesteps=ms)
                else:
                    vel = pos2vel(pos, sampling_rate=rate, method="smooth")
                    fn = pm.events.ivt if method == "ivt" else pm.events.microsaccades
                    events = fn(velocities=vel, timesteps=ms)
            except Exception as e:
                report["failures"].setdefault(name, {})[stem] = f"{type(e).__name__}: {e}"
                continue
            elapsed = time.perf_counter() - start
            inside = np.zeros(n, dtype=bool)
            for onset, offset in zip(events.frame["onset"].to_list(), events.frame["offset"].to_list()):
                inside[(ms >= onset) & (ms <= offset)] = True
            inner, outer = ("saccade", "fixation") if method == "microsaccades" else ("fixation", "saccade")
            labels = np.where(inside, inner, outer).astype(object)
            labels[lost] = "blink"
            save(name, stem, t, labels)
            report["timings"].setdefault(name, []).append((elapsed, n))
    json.dump(report, open(Path(out_dir) / "peers.json", "w"))


COLOURS = {"fixation": "#4c72b0", "saccade": "#dd8452", "pso": "#c44e52", "pursuit": "#55a868", "blink": "#8c8c8c",
           "undefined": "#ffffff"}


def picture_worker(out_png, dataset, recording, start_s, seconds, *streams):
    """Inside the peers' environment (matplotlib): a stretch of signal with label bands."""
    import matplotlib
    matplotlib.use("agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch
    codes = {"1": "fixation", "2": "saccade", "3": "pso", "4": "pursuit", "5": "blink", "0": "undefined"}

    def read_labels(path):
        rows = list(csv.DictReader(open(path)))
        return [codes.get(r["label"], r["label"]) for r in rows]

    rows = list(csv.DictReader(open(recording)))
    t = [float(r.get("t_s") or r.get("t")) for r in rows]
    pos = [degrees(dataset, r) for r in rows]
    a = next(i for i, ti in enumerate(t) if ti >= float(start_s))
    b = next((i for i, ti in enumerate(t) if ti >= float(start_s) + float(seconds)), len(t))
    fig, ax = plt.subplots(figsize=(10, 4.6), dpi=110)
    ts = t[a:b]
    ax.plot(ts, [p[0] for p in pos[a:b]], color="black", lw=0.9)
    ax.plot(ts, [p[1] for p in pos[a:b]], color="0.5", lw=0.9)
    low, high = ax.get_ylim()
    step = 0.07 * (high - low)
    names = []
    for k, stream in enumerate(streams):
        name, path = stream.split("=", 1)
        labels = read_labels(path)[a:b]
        band = low - (k + 1) * step
        i = 0
        while i < len(labels):
            j = i
            while j < len(labels) and labels[j] == labels[i]:
                j += 1
            ax.fill_between([ts[i], ts[j - 1] + (ts[1] - ts[0])], band, band + 0.8 * step, color=COLOURS[labels[i]], lw=0)
            i = j
        names.append((band + 0.4 * step, name))
    ticks = [v for v in ax.get_yticks() if low <= v <= high]
    ax.set_yticks([p for p, _ in names] + ticks)
    ax.set_yticklabels([n for _, n in names] + [f"{v:g}°" for v in ticks])
    ax.set_ylim(low - (len(streams) + 0.3) * step, high)
    ax.set_xlabel("time (s)")
    ax.set_title(f"{Path(recording).name}: gaze x (black) and y (grey), degrees; labels per sample")
    ax.legend(handles=[Patch(color=c, label=l) for l, c in COLOURS.items() if l != "undefined"], loc="upper right", ncol=5, fontsize=8)
    fig.tight_layout()
    fig.savefig(out_png)


def ensure_venv(venv):
    python = venv / "bin" / "python"
    if not python.exists():
        print(f"creating {venv} for the peers ({', '.join(PEERS)})", flush=True)
        subprocess.run([sys.executable if sys.prefix == sys.base_prefix else "/usr/bin/python3", "-m", "venv", str(venv)], check=True)
    check = subprocess.run([str(python), "-c", "import remodnav, pymovements, matplotlib"], capture_output=True)
    if check.returncode != 0:
        subprocess.run([str(python), "-m", "pip", "install", "-q", *PEERS], check=True)
    return python


def score(foveal, dataset, samples, events, coder_file, coder2_file, js, repeats=1):
    """foveal gaze --events EVENTS --evaluate CODER [--coder2 CODER2]: the "events" JSON (best time of repeats)."""
    best = None
    for _ in range(repeats):
        cmd = [foveal, "gaze", str(samples), "--display", DATASETS[dataset]["display"], *DATASETS[dataset]["options"], "--events", events,
               "--evaluate", str(coder_file), "--json", str(js), "--no-scanpath", "-q"]
        if coder2_file:
            cmd += ["--coder2", str(coder2_file)]
        subprocess.run(cmd, check=True)
        ev = json.load(open(js))["events"]
        best = ev if best is None or ev["detect_ms"] < best["detect_ms"] else best
    return best


def mean(values):
    values = [v for v in values if v is not None]
    return sum(values) / len(values) if values else None


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--foveal", default="build/foveal")
    ap.add_argument("--shared", default="../shared", help="the shared folder holding data/eye-movements/{irf,lund2013-train}")
    ap.add_argument("--venv", default="build/bench-events-venv", help="the peers' virtual environment (created if missing)")
    ap.add_argument("--out", default="build/bench-events")
    ap.add_argument("--quick", action="store_true", help="two recordings per data set")
    ap.add_argument("--picture", help="also draw a stretch of a Lund dots recording with both coders', nhr's and REMoDNaV's labels (PNG)")
    ap.add_argument("--peer-worker", nargs="+", help=argparse.SUPPRESS)
    ap.add_argument("--picture-worker", nargs="+", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.peer_worker:
        peer_worker(args.peer_worker[0], args.peer_worker[1:])
        return 0
    if args.picture_worker:
        picture_worker(*args.picture_worker)
        return 0

    recs = recordings(Path(args.shared), args.quick)
    if not recs:
        print(f"no hand-labelled recordings under {args.shared}/data/eye-movements: nothing to compare (skipped)")
        return 0
    out = Path(args.out)
    labels_dir = out / "labels"
    labels_dir.mkdir(parents=True, exist_ok=True)
    python = ensure_venv(Path(args.venv))
    print(f"peers on {len(recs)} recordings …", flush=True)
    subprocess.run([str(python), os.path.abspath(__file__), "--peer-worker", str(labels_dir),
                    *[f"{d}|{stem}|{path}" for d, _, stem, path, _ in recs]], check=True)
    peers = json.load(open(labels_dir / "peers.json"))
    peer_names = sorted(set(peers["timings"]) | set(peers["failures"]), key=lambda n: (not n.startswith("remodnav"), n))
    detectors = FOVEAL + peer_names
    stems_of = {ds: {stem for d, _, stem, _, _ in recs if d == ds} for ds in DATASETS}

    def applies(d, dataset):  # a peer configuration run on this data set (remodnav-nopursuit: IRF only)
        if d in FOVEAL:
            return True
        return any((labels_dir / f"{stem}.{d}.csv").exists() or stem in peers["failures"].get(d, {}) for stem in stems_of[dataset])

    # scores[dataset][stimulus][stem][detector][coder] = events JSON (None: the method failed)
    scores, ceilings, timings = {}, {}, {d: [0.0, 0] for d in FOVEAL}
    for dataset, stimulus, stem, path, coders in recs:
        per = scores.setdefault(dataset, {}).setdefault(stimulus, {}).setdefault(stem, {})
        names = list(coders)
        for d in detectors:
            if not applies(d, dataset):
                continue
            if d in FOVEAL:
                events = d
            elif stem in peers["failures"].get(d, {}):
                per[d] = None
                continue
            else:
                events = f"file:{labels_dir / f'{stem}.{d}.csv'}"
            per[d] = {}
            for k, coder in enumerate(names):
                other = coders[names[1 - k]] if len(names) == 2 else None
                repeats = 3 if d in FOVEAL and dataset == "irf" and k == 0 else 1
                ev = score(args.foveal, dataset, path, events, coders[coder], other, labels_dir / f"{stem}.{d}.{coder}.json", repeats)
                per[d][coder] = ev
                if other and d == "nhr":
                    ceilings.setdefault(stem, {})[coder] = ev["ceiling"]
                if repeats == 3:
                    timings[d][0] += ev["detect_ms"] / 1000
                    timings[d][1] += ev["samples"]
        print(f"  {dataset} {stem} scored", flush=True)

    # Means per data set, stimulus, coder and class over the recordings where the coder used the
    # class (reference events > 0); each method over what it completed, and over the common set
    def kappas(dataset, stimulus, d, coder, cls, stems=None):
        values = []
        for stem, per in scores[dataset][stimulus].items():
            if stems is not None and stem not in stems:
                continue
            ev = per.get(d)
            if ev is None:
                continue
            c = ev[coder]["classes"][cls]
            if c["reference_events"] > 0:
                values.append(c["kappa"] if c["kappa"] is not None else 0.0)
        return values

    def ceiling_kappas(stimulus, coder, cls, stems=None):
        values = []
        for stem in scores["lund"][stimulus]:
            if stems is not None and stem not in stems:
                continue
            c = ceilings[stem][coder]["classes"][cls]
            if c["reference_events"] > 0:
                values.append(c["kappa"] if c["kappa"] is not None else 0.0)
        return values

    fmt = lambda v: "—" if v is None else f"{v:.2f}"
    lines, summary = [], {"datasets": {}, "failures": peers["failures"]}
    common = {stem for ds_name, ds in scores.items() for st in ds.values() for stem, per in st.items()
              if all(per.get(d) is not None for d in detectors if applies(d, ds_name))}
    incomplete = sorted({stem for ds in scores.values() for st in ds.values() for stem in st} - common)
    for subset, title in [(None, "over the recordings each method completed"), (common, "over the recordings every method completed")]:
        if subset is not None and not incomplete:
            break
        lines.append(f"\n#### Means {title}\n")
        if "irf" in scores:
            lines.append("IRF (one coder; PSO without S3, which has no PSO labels):\n")
            lines.append("| detector | fixation κ | saccade κ | PSO κ | blink κ | κ all | saccade F1 | s per 10⁶ samples |")
            lines.append("|---|---:|---:|---:|---:|---:|---:|---:|")
            for d in [d for d in detectors if applies(d, "irf")]:
                row = [mean(kappas("irf", "points", d, "expert", c, subset)) for c in ["fixation", "saccade", "pso", "blink"]]
                per = [p[d]["expert"] for s, p in scores["irf"]["points"].items() if p.get(d) and (subset is None or s in subset)]
                k_all = mean([e["kappa"] for e in per])
                f1 = mean([e["classes"]["saccade"]["f1"] for e in per])
                if d in FOVEAL:
                    seconds, samples = timings[d]
                else:
                    seconds = sum(t for t, _ in peers["timings"].get(d, []))
                    samples = sum(n for _, n in peers["timings"].get(d, []))
                speed = f"{seconds / samples * 1e6:.3f}" if samples else "—"
                lines.append(f"| {d} | " + " | ".join(fmt(v) for v in row) + f" | {fmt(k_all)} | {fmt(f1)} | {speed} |")
                summary["datasets"].setdefault("irf" if subset is None else "irf-common", {})[d] = {
                    "fixation": row[0], "saccade": row[1], "pso": row[2], "blink": row[3], "kappa": k_all, "saccade_f1": f1,
                    "seconds_per_million": seconds / samples * 1e6 if samples else None}
        if "lund" in scores:
            for stimulus, classes in [("img", ["fixation", "saccade", "pso"]), ("dots", ["fixation", "saccade", "pso", "pursuit"]),
                                      ("video", ["fixation", "saccade", "pso", "pursuit"])]:
                if stimulus not in scores["lund"]:
                    continue
                n = len([s for s in scores["lund"][stimulus] if subset is None or s in subset])
                lines.append(f"\nLund {stimulus} ({n} recordings), κ against MN / RA; the last column the lowest saccade κ of a "
                             "recording (either coder):\n")
                lines.append("| detector | " + " | ".join(f"{c} κ" for c in classes) + " | lowest saccade κ |")
                lines.append("|---|" + "---:|" * (len(classes) + 1))
                rows = [("MN vs RA (ceiling)", None)] + [(d, d) for d in detectors if applies(d, "lund")]
                for label, d in rows:
                    cells = []
                    for c in classes:
                        if d is None:
                            mn, ra = mean(ceiling_kappas(stimulus, "MN", c, subset)), mean(ceiling_kappas(stimulus, "RA", c, subset))
                        else:
                            mn, ra = mean(kappas("lund", stimulus, d, "MN", c, subset)), mean(kappas("lund", stimulus, d, "RA", c, subset))
                        cells.append(f"{fmt(mn)} / {fmt(ra)}")
                        key = "lund-" + stimulus + ("" if subset is None else "-common")
                        summary["datasets"].setdefault(key, {}).setdefault(label, {})[c] = [mn, ra]
                    if d is None:
                        low = min([v for coder in ["MN", "RA"] for v in ceiling_kappas(stimulus, coder, "saccade", subset)] or [None])
                    else:
                        low = min([v for coder in ["MN", "RA"] for v in kappas("lund", stimulus, d, coder, "saccade", subset)] or [None])
                    lines.append(f"| {label} | " + " | ".join(cells) + f" | {fmt(low)} |")
    if peers["failures"]:
        lines.append("\nRecordings a peer failed on:\n")
        for name, failed in sorted(peers["failures"].items()):
            for stem, why in sorted(failed.items()):
                lines.append(f"- {name} on {stem}: {why.splitlines()[0][:160]}")
    table = "\n".join(lines).strip() + "\n"
    json.dump({"summary": summary, "scores": scores}, open(out / "events_peers.json", "w"), indent=1)
    (out / "events_peers.md").write_text(table)
    print(table)
    print(f"wrote {out / 'events_peers.json'} and {out / 'events_peers.md'}")
    if args.picture and "lund" in scores and "dots" in scores["lund"]:
        stem = sorted(scores["lund"]["dots"])[0]
        mn = next(p for d, s, st, p, _ in recs if st == stem)
        ra = mn.with_name(mn.name.replace("_MN.csv", "_RA.csv"))
        nhr = labels_dir / f"{stem}.nhr-samples.csv"
        subprocess.run([args.foveal, "gaze", str(mn), "--display", DATASETS["lund"]["display"], "--coords", "px", "--events", "nhr",
                        "--samples-out", str(nhr), "--no-scanpath", "-q"], check=True)
        streams = [f"MN={mn}", f"RA={ra}", f"nhr={nhr}"]
        if (labels_dir / f"{stem}.remodnav.csv").exists():
            streams.append(f"REMoDNaV={labels_dir / f'{stem}.remodnav.csv'}")
        subprocess.run([str(python), os.path.abspath(__file__), "--picture-worker", args.picture, "lund", str(mn), "0", "2.6", *streams],
                       check=True)
        print(f"wrote {args.picture}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
