#!/usr/bin/env python3
"""foveal's event detectors against REMoDNaV and pymovements on the hand-labelled IRF recordings.

Every detector labels the same samples; every labelling is scored by the same code (foveal gaze
--events file:LABELS --evaluate EXPERT: sample-level Cohen's kappa per class, event F1 with Hooge
et al. 2018 matching). The peers are installed by this benchmark into their own virtual
environment (never a dependency of foveal), pinned, and run with their documented defaults and a
second setting chosen for this task (a looking-at-points task: no pursuit).

    python3 bench/events_peers.py [--foveal build/foveal] [--data DIR] [--quick] [--out DIR] [--picture PNG]

Writes OUT/events_peers.json and OUT/events_peers.md (the table for BENCHMARKS.md). --quick: S1
and S2 only. Run times are per 10^6 samples of the detection alone (no file reading), on one core.
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import time
from pathlib import Path

PEERS = ["remodnav==1.1.2", "pymovements==0.28.0"]
DISPLAY = "53.3,30.1,56.5,1920,1080"  # irf/db_config.json: 533 x 301 mm, 1920 x 1080 px, 565 mm
CLASSES = ["fixation", "saccade", "pso", "pursuit", "blink"]


def peer_worker(files, out_dir):
    """Run inside the peers' environment: per-sample labels of every peer configuration."""
    import numpy as np
    from remodnav.clf import EyegazeClassifier
    import pymovements as pm
    from pymovements.transforms.numpy import pos2vel
    import logging
    logging.getLogger("remodnav").setLevel(logging.WARNING)

    timings = {}

    def save(name, stem, t, labels):
        path = Path(out_dir) / f"{stem}.{name}.csv"
        with open(path, "w") as f:
            f.write("t_s,label\n")
            for ti, li in zip(t, labels):
                f.write(f"{ti:.4f},{li}\n")

    for file in files:
        stem = Path(file).stem
        rows = list(csv.DictReader(open(file)))
        t = np.array([float(r["t_s"]) for r in rows])
        x = np.array([float(r["x_deg"]) if r["x_deg"] else np.nan for r in rows])
        y = np.array([float(r["y_deg"]) if r["y_deg"] else np.nan for r in rows])
        lost = np.isnan(x) | np.isnan(y)
        n = len(t)
        rate = 1.0 / np.median(np.diff(t))

        # REMoDNaV (Dar, Wagner & Hanke 2021): pixels with a linear px2deg; positions given as
        # degrees / 0.01 so its angles are the recording's degrees exactly
        remodnav_map = {"FIXA": "fixation", "PURS": "pursuit", "SACC": "saccade", "ISAC": "saccade",
                        "HPSO": "pso", "IHPS": "pso", "LPSO": "pso", "ILPS": "pso"}
        for name, kwargs in [("remodnav", {}), ("remodnav-nopursuit", {"pursuit_velthresh": 1000.0})]:
            data = np.rec.fromarrays([x / 0.01, y / 0.01], names="x,y")
            start = time.perf_counter()
            clf = EyegazeClassifier(px2deg=0.01, sampling_rate=rate, **kwargs)
            events = clf(clf.preproc(data), classify_isp=True, sort_events=True)
            elapsed = time.perf_counter() - start
            labels = np.array(["undefined"] * n, dtype=object)
            for ev in events:
                a = int(round(ev["start_time"] * rate))
                b = int(round(ev["end_time"] * rate))
                labels[a:b] = remodnav_map.get(ev["label"], "undefined")
            labels[lost] = "blink"  # the same loss rule as foveal's ivt/idt baseline
            save(name, stem, t, labels)
            timings.setdefault(name, []).append((elapsed, n))

        # pymovements: I-VT, I-DT (fixations; the other valid samples saccades) and Engbert's
        # microsaccades (saccades; the rest fixations); timesteps in ms
        pos = np.column_stack([x, y])
        ms = np.round(t * 1000).astype(np.int64)
        configs = [
            ("pymovements-ivt", "ivt", {}),
            ("pymovements-ivt-40ms", "ivt", {"minimum_duration": 40, "velocity_threshold": 30.0}),
            ("pymovements-idt", "idt", {}),
            ("pymovements-idt-40ms", "idt", {"minimum_duration": 40, "dispersion_threshold": 1.5}),
            ("pymovements-microsaccades", "microsaccades", {}),
        ]
        for name, method, kwargs in configs:
            start = time.perf_counter()
            if method == "idt":
                events = pm.events.idt(positions=pos, timesteps=ms, **kwargs)
            else:
                vel = pos2vel(pos, sampling_rate=rate, method="smooth")
                fn = pm.events.ivt if method == "ivt" else pm.events.microsaccades
                events = fn(velocities=vel, timesteps=ms, **kwargs)
            elapsed = time.perf_counter() - start
            frame = events.frame
            inside = np.zeros(n, dtype=bool)
            for onset, offset in zip(frame["onset"].to_list(), frame["offset"].to_list()):
                inside[(ms >= onset) & (ms <= offset)] = True
            if method == "microsaccades":
                labels = np.where(inside, "saccade", "fixation").astype(object)
            else:
                labels = np.where(inside, "fixation", "saccade").astype(object)
            labels[lost] = "blink"
            save(name, stem, t, labels)
            timings.setdefault(name, []).append((elapsed, n))
    json.dump({k: [list(x) for x in v] for k, v in timings.items()}, open(Path(out_dir) / "timings.json", "w"))


COLOURS = {"fixation": "#4c72b0", "saccade": "#dd8452", "pso": "#c44e52", "pursuit": "#55a868", "blink": "#8c8c8c",
           "undefined": "#ffffff"}


def picture_worker(out_png, recording, start_s, seconds, *streams):
    """Run inside the peers' environment (matplotlib): a stretch of signal with label bands."""
    import matplotlib
    matplotlib.use("agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch

    def read(path, column):
        rows = list(csv.DictReader(open(path)))
        return [float(r["t_s"]) for r in rows], [r[column] for r in rows]

    t, x = read(recording, "x_deg")
    _, y = read(recording, "y_deg")
    a = next(i for i, ti in enumerate(t) if ti >= float(start_s))
    b = next((i for i, ti in enumerate(t) if ti >= float(start_s) + float(seconds)), len(t))
    fig, ax = plt.subplots(figsize=(10, 4.2), dpi=110)
    ts = t[a:b]
    ax.plot(ts, [float(v) if v else float("nan") for v in x[a:b]], color="black", lw=0.9, label="x")
    ax.plot(ts, [float(v) if v else float("nan") for v in y[a:b]], color="0.5", lw=0.9, label="y")
    names = []
    low = ax.get_ylim()[0]
    for k, stream in enumerate(streams):
        name, path = stream.split("=", 1)
        _, labels = read(path, "label")
        codes = {"1": "fixation", "2": "saccade", "3": "pso", "4": "pursuit", "5": "blink", "0": "undefined"}
        labels = [codes.get(v, v) for v in labels[a:b]]
        band = low - (k + 1) * 1.6
        i = 0
        while i < len(labels):
            j = i
            while j < len(labels) and labels[j] == labels[i]:
                j += 1
            ax.fill_between([ts[i], ts[j - 1] + 0.001], band, band + 1.3, color=COLOURS[labels[i]], lw=0)
            i = j
        names.append((band + 0.65, name))
    ax.set_yticks([p for p, _ in names] + [v for v in ax.get_yticks() if v >= low])
    ax.set_yticklabels([n for _, n in names] + [f"{v:g}°" for v in ax.get_yticks()[len(names):]])
    ax.set_ylim(low - (len(streams) + 0.3) * 1.6, None)
    ax.set_xlabel("time (s)")
    ax.set_title(f"{Path(recording).name}: gaze x (black) and y (grey), degrees; labels per sample")
    ax.legend(handles=[Patch(color=c, label=l) for l, c in COLOURS.items() if l not in ("undefined", "pursuit")],
              loc="upper right", ncol=4, fontsize=8)
    fig.tight_layout()
    fig.savefig(out_png)


def ensure_venv(venv):
    python = venv / "bin" / "python"
    if not python.exists():
        print(f"creating {venv} for the peers ({', '.join(PEERS)})", flush=True)
        subprocess.run(["/usr/bin/python3", "-m", "venv", str(venv)], check=True)
    check = subprocess.run([str(python), "-c", "import remodnav, pymovements"], capture_output=True)
    if check.returncode != 0:
        subprocess.run([str(python), "-m", "pip", "install", "-q", *PEERS], check=True)
    return python


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--foveal", default="build/foveal")
    ap.add_argument("--data", default="../shared/data/eye-movements/irf")
    ap.add_argument("--venv", default="build/bench-events-venv", help="the peers' virtual environment (created if missing)")
    ap.add_argument("--out", default="build/bench-events")
    ap.add_argument("--quick", action="store_true", help="S1 and S2 only")
    ap.add_argument("--picture", help="also draw a stretch of S1 with the expert's, nhp's and REMoDNaV's labels (PNG)")
    ap.add_argument("--peer-worker", nargs="+", help=argparse.SUPPRESS)
    ap.add_argument("--picture-worker", nargs="+", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.peer_worker:
        peer_worker(args.peer_worker[1:], args.peer_worker[0])
        return 0
    if args.picture_worker:
        picture_worker(*args.picture_worker)
        return 0

    data = Path(args.data)
    files = sorted(data.glob("lookAtPoint_EL_S*.csv"))
    if not files:
        print(f"no IRF recordings in {data}: nothing to compare (skipped)")
        return 0
    if args.quick:
        files = files[:2]
    out = Path(args.out)
    labels_dir = out / "labels"
    labels_dir.mkdir(parents=True, exist_ok=True)

    python = ensure_venv(Path(args.venv))
    print(f"peers on {len(files)} recordings …", flush=True)
    subprocess.run([str(python), os.path.abspath(__file__), "--peer-worker", str(labels_dir), *map(str, files)], check=True)
    peer_timings = json.load(open(labels_dir / "timings.json"))

    detectors = ["nhp", "nh", "ek", "ivt", "idt"] + list(peer_timings)
    results = {d: {"files": {}} for d in detectors}
    for file in files:
        stem = file.stem
        for d in detectors:
            events = d if d in ("nhp", "nh", "ek", "ivt", "idt") else f"file:{labels_dir / f'{stem}.{d}.csv'}"
            js = labels_dir / f"{stem}.{d}.json"
            # The best of three runs for foveal's own detectors (the detection's time only)
            best = None
            for _ in range(3 if not events.startswith("file:") else 1):
                subprocess.run([args.foveal, "gaze", str(file), "--display", DISPLAY, "--events", events, "--evaluate", str(file),
                                "--json", str(js), "--no-scanpath", "-q"], check=True)
                ev = json.load(open(js))["events"]
                best = ev if best is None or ev["detect_ms"] < best["detect_ms"] else best
            results[d]["files"][stem] = best
        print(f"  {stem} scored", flush=True)

    def mean(values):
        values = [v for v in values if v is not None]
        return sum(values) / len(values) if values else None

    for d in detectors:
        per = results[d]["files"]
        summary = {"kappa": mean([e["kappa"] for e in per.values()])}
        for c in CLASSES:
            # S3's coder marked no PSO: it is left out of the PSO scores
            use = [e for s, e in per.items() if not (c == "pso" and s.endswith("S3"))]
            summary[f"{c}_kappa"] = mean([e["classes"][c]["kappa"] for e in use])
            summary[f"{c}_f1"] = mean([e["classes"][c]["f1"] for e in use])
        if d in peer_timings:
            seconds = sum(t for t, _ in peer_timings[d])
            samples = sum(n for _, n in peer_timings[d])
        else:
            seconds = sum(e["detect_ms"] for e in per.values()) / 1000
            samples = sum(e["samples"] for e in per.values())
        summary["seconds_per_million"] = seconds / samples * 1e6
        summary["samples_per_second"] = samples / seconds
        results[d]["summary"] = summary

    json.dump(results, open(out / "events_peers.json", "w"), indent=1)
    fmt = lambda v: "—" if v is None else f"{v:.3f}"
    lines = [
        f"| detector | κ all | fixation κ | saccade κ | PSO κ | blink κ | fixation F1 | saccade F1 | PSO F1 | s per 10⁶ samples |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for d in detectors:
        s = results[d]["summary"]
        lines.append(f"| {d} | {fmt(s['kappa'])} | {fmt(s['fixation_kappa'])} | {fmt(s['saccade_kappa'])} | {fmt(s['pso_kappa'])} | "
                     f"{fmt(s['blink_kappa'])} | {fmt(s['fixation_f1'])} | {fmt(s['saccade_f1'])} | {fmt(s['pso_f1'])} | "
                     f"{s['seconds_per_million']:.3f} |")
    table = "\n".join(lines)
    (out / "events_peers.md").write_text(table + "\n")
    print(table)
    print(f"wrote {out / 'events_peers.json'} and {out / 'events_peers.md'}")
    if args.picture:
        s1 = files[0]
        nhp = labels_dir / f"{s1.stem}.nhp-samples.csv"
        subprocess.run([args.foveal, "gaze", str(s1), "--display", DISPLAY, "--events", "nhp", "--samples-out", str(nhp), "--no-scanpath", "-q"],
                       check=True)
        subprocess.run([str(python), os.path.abspath(__file__), "--picture-worker", args.picture, str(s1), "4.6", "0.5",
                        f"expert={s1}", f"nhp={nhp}", f"REMoDNaV={labels_dir / f'{s1.stem}.remodnav-nopursuit.csv'}"], check=True)
        print(f"wrote {args.picture}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
