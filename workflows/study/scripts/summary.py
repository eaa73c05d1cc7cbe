#!/usr/bin/env python3
"""The study's group summary: one row per recording from what `foveal gaze --events --json` and
`--events-out` wrote — samples, duration, events per class, fixation durations, saccade amplitudes
and peak velocities, the main sequence (peak velocity against amplitude, a power law fitted per
recording: V = a·A^b, as Bahill, Clark & Stark 1975 describe it) and the scores where labels were
given — and a figure of the same (events per participant, fixation durations, saccade amplitudes,
the main sequence). Both are written whole or not at all.

Usage: summary.py --tsv OUT.tsv --png OUT.png --json A_gaze.json ... --events A_events.tsv ...
"""
import argparse
import csv
import json
import math
import os
import sys
import tempfile

import numpy as np

CLASSES = ("fixation", "saccade", "pso", "pursuit", "blink")
COLUMNS = ["recording", "subject", "session", "task", "run", "samples", "duration_s", "rate_hz", "valid_fraction", "detector",
           *[f"{c}_events" for c in CLASSES], "fixation_duration_ms_median", "saccade_amplitude_deg_median",
           "saccade_peak_velocity_deg_s_median", "main_sequence_a", "main_sequence_b", "kappa"]


def entities(stem):
    e = dict(part.split("-", 1) for part in stem.split("_") if "-" in part)
    return {"subject": e.get("sub", ""), "session": e.get("ses", ""), "task": e.get("task", ""), "run": e.get("run", "")}


def median(values):
    finite = [v for v in values if math.isfinite(v)]
    return float(np.median(finite)) if finite else float("nan")


def power_law(amplitudes, velocities):
    """V = a·A^b by least squares on log V = log a + b log A, over saccades with both positive."""
    a, v = np.asarray(amplitudes, float), np.asarray(velocities, float)
    keep = (a > 0) & (v > 0)
    if keep.sum() < 3 or np.ptp(np.log(a[keep])) == 0:
        return float("nan"), float("nan")
    b, log_a = np.polyfit(np.log(a[keep]), np.log(v[keep]), 1)
    return float(np.exp(log_a)), float(b)


def number(text):
    return float("nan") if text in ("n/a", "") else float(text)


def read_events(path):
    with open(path, newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f, delimiter="\t"))


def row_of(json_path, events_path):
    with open(json_path, encoding="utf-8") as f:
        report = json.load(f)
    stem = os.path.basename(json_path)[: -len("_gaze.json")]
    events = read_events(events_path)
    ev = report.get("events", {})
    counts = ev.get("counts", {})
    fixations = [number(e["duration"]) * 1000 for e in events if e["trial_type"] == "fixation"]
    saccades = [e for e in events if e["trial_type"] == "saccade"]
    amplitudes = [number(e["amplitude_deg"]) for e in saccades]
    velocities = [number(e["peak_velocity_deg_s"]) for e in saccades]
    a, b = power_law(amplitudes, velocities)
    row = {"recording": stem, **entities(stem), "samples": report["samples"], "duration_s": report["duration_s"],
           "rate_hz": report["rate_hz"], "valid_fraction": report["valid_fraction"], "detector": ev.get("detector", ""),
           **{f"{c}_events": counts.get(c, 0) for c in CLASSES},
           "fixation_duration_ms_median": median(fixations), "saccade_amplitude_deg_median": median(amplitudes),
           "saccade_peak_velocity_deg_s_median": median(velocities), "main_sequence_a": a, "main_sequence_b": b,
           "kappa": ev.get("kappa", float("nan"))}
    return row, fixations, amplitudes, velocities


def write_atomically(path, write):
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    handle, temporary = tempfile.mkstemp(prefix="." + os.path.basename(path) + ".", dir=folder)
    os.close(handle)
    try:
        write(temporary)
        os.replace(temporary, path)
    except BaseException:
        if os.path.exists(temporary):
            os.unlink(temporary)
        raise


def cell(value):
    if isinstance(value, float):
        return "n/a" if math.isnan(value) else f"{value:.6g}"
    return str(value)


def figure(path, rows, details):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 2, figsize=(11, 8))
    labels = [r["recording"].split("_task")[0] for r in rows]
    bottom = [0] * len(rows)
    for c in CLASSES:
        values = [r[f"{c}_events"] for r in rows]
        ax[0, 0].bar(labels, values, bottom=bottom, label=c)
        bottom = [b + v for b, v in zip(bottom, values)]
    ax[0, 0].set_title("Events per recording")
    ax[0, 0].legend(fontsize=8)
    ax[0, 0].tick_params(axis="x", rotation=45, labelsize=8)
    ax[0, 1].boxplot([d[0] or [float("nan")] for d in details])
    ax[0, 1].set_xticks(range(1, len(labels) + 1), labels)
    ax[0, 1].set_title("Fixation durations (ms)")
    ax[0, 1].tick_params(axis="x", rotation=45, labelsize=8)
    every = [a for d in details for a in d[1] if a > 0]
    ax[1, 0].hist(every, bins=40, color="tab:orange")
    ax[1, 0].set_title("Saccade amplitudes (deg), all recordings")
    for label, d in zip(labels, details):
        ax[1, 1].loglog([a for a, v in zip(d[1], d[2]) if a > 0 and v > 0], [v for a, v in zip(d[1], d[2]) if a > 0 and v > 0],
                        ".", label=label, alpha=0.6)
    ax[1, 1].set_title("Main sequence: peak velocity (deg/s) vs amplitude (deg)")
    ax[1, 1].legend(fontsize=7)
    fig.suptitle(f"{len(rows)} recordings: events by foveal gaze --events ({rows[0]['detector'] if rows else ''})")
    fig.tight_layout()
    fig.savefig(path, format="png", dpi=90)
    plt.close(fig)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--tsv", required=True)
    p.add_argument("--png", required=True)
    p.add_argument("--json", nargs="+", required=True)
    p.add_argument("--events", nargs="+", required=True)
    args = p.parse_args(argv)
    if len(args.json) != len(args.events):
        sys.exit("summary.py: --json and --events need one file each per recording")
    results = [row_of(j, e) for j, e in zip(args.json, args.events)]
    rows = [r[0] for r in results]
    details = [r[1:] for r in results]

    def tsv(path):
        with open(path, "w", newline="", encoding="utf-8") as f:
            f.write("\t".join(COLUMNS) + "\n")
            for r in rows:
                f.write("\t".join(cell(r[c]) for c in COLUMNS) + "\n")

    write_atomically(args.tsv, tsv)
    write_atomically(args.png, lambda path: figure(path, rows, details))
    return 0


if __name__ == "__main__":
    sys.exit(main())
