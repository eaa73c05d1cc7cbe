#!/usr/bin/env python3
"""A gaze-contingent session at a glance: the per-flip log of ``gaze_contingent.py`` drawn as one picture.

Four panels over the session's time (seconds from its first flip):

1. the gaze and the fovea the loop placed (render pixels, x and y), with the flips whose fovea was
   at a predicted saccade landing shaded;
2. gaze → flip, the gaze-to-photon latency of each flip (flip time − the gaze sample's time), with
   one and two refreshes marked;
3. each flip's frame time (the loop's ``frame()``) against the budget it was given, late frames in red;
4. the fovea's converged fraction, and the size the loop rendered at (a share of the largest).

    python examples/psychopy/session_plot.py gaze_contingent_frames.csv -o session.png
    python examples/psychopy/session_plot.py frames.csv.partial -o failed.png --refresh-hz 60

A failed session's ``LOG.partial`` is drawn as well. ``gaze_contingent.py --plot F`` draws its own
log at the session's end. The picture is PNG, SVG or PDF (by the name's extension), written whole or
not at all.
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import secrets
import sys

import numpy as np

from session_checks import check_output

# The columns drawn (a log of gaze_contingent.py has these and more)
COLUMNS = ("flip", "gaze_x", "gaze_y", "fovea_x", "fovea_y", "predicted", "fovea_converged", "render_ms", "late", "flip_time_s",
           "gaze_to_flip_ms", "budget_ms", "width")
POSITIVE = ("budget_ms", "width")  # (a frame's budget and its width are never 0)
EXTENSIONS = (".png", ".svg", ".pdf")


class LogError(ValueError):
    """A log that cannot be drawn, naming the file and, where it is one, the line and column."""


def read_log(path):
    """The drawn columns of a session log as float arrays (a dict by column name).

    Raises FileNotFoundError for a missing file, LogError naming the file (and the line and column)
    for one that is not such a log: a column missing, a value that is no finite number, no flips.
    Columns are read one by one into arrays: an hour at 60 Hz is 216,000 rows.
    """
    values = {name: [] for name in COLUMNS}
    with open(path, newline="") as f:
        reader = csv.reader(f)
        header = next(reader, None)
        if header is None:
            raise LogError(f"{path}: the file is empty; expected a log of gaze_contingent.py (a CSV with a header)")
        if header == ["flip"]:  # (what a session that ended before its first flip writes)
            raise LogError(f"{path}: no flips logged")
        missing = [name for name in COLUMNS if name not in header]
        if missing:
            raise LogError(f"{path}: line 1: no column {', '.join(repr(m) for m in missing)}; a log of gaze_contingent.py has "
                           f"{', '.join(COLUMNS)}")
        where = [header.index(name) for name in COLUMNS]
        for line, row in enumerate(reader, start=2):
            if not row:
                continue
            if len(row) != len(header):
                raise LogError(f"{path}: line {line}: {len(row)} values where the header names {len(header)}")
            for name, k in zip(COLUMNS, where):
                try:
                    v = float(row[k])
                except ValueError:
                    raise LogError(f"{path}: line {line}: column {name!r}: {row[k]!r} is no number") from None
                if not math.isfinite(v):
                    raise LogError(f"{path}: line {line}: column {name!r}: {row[k]!r} is not a finite number")
                if name in POSITIVE and not v > 0:
                    raise LogError(f"{path}: line {line}: column {name!r}: {row[k]!r} is not above 0")
                values[name].append(v)
    if not values["flip"]:
        raise LogError(f"{path}: no flips logged")
    return {name: np.asarray(v) for name, v in values.items()}


def session_figures(log, refresh_hz=None):
    """What the picture states in words: flips, late frames, flips at a predicted landing, the
    gaze-to-flip median and 95th percentile (from the second flip, as the session's summary: the
    first waits for the tracker), and the refresh the latency is read against — `refresh_hz` where
    given, else the median interval between flips (`refresh_from`: 'given' or 'flips')."""
    flips = len(log["flip"])
    latencies = log["gaze_to_flip_ms"][1:] if flips > 1 else log["gaze_to_flip_ms"]
    if refresh_hz is None and flips > 1 and np.median(np.diff(log["flip_time_s"])) > 0:
        refresh_hz, source = 1.0 / float(np.median(np.diff(log["flip_time_s"]))), "flips"
    else:
        source = "given" if refresh_hz is not None else None
    median = float(np.median(latencies))
    return {"flips": flips, "late": int(np.count_nonzero(log["late"])), "predicted": int(np.count_nonzero(log["predicted"])),
            "gaze_to_flip_ms_median": median, "gaze_to_flip_ms_p95": float(np.percentile(latencies, 95)),
            "refresh_hz": refresh_hz, "refresh_from": source,
            "gaze_to_flip_refreshes_median": median * refresh_hz / 1000 if refresh_hz else None}


def _spans(t, flags):
    """(start, end) times of the runs of consecutive flips where `flags` is set (each flip until the next)."""
    spans, start = [], None
    ends = np.append(t[1:], t[-1] + (t[-1] - t[-2] if len(t) > 1 else 0.0))
    for k, on in enumerate(flags):
        if on and start is None:
            start = t[k]
        if start is not None and (not on or k == len(flags) - 1):
            spans.append((start, ends[k] if on else t[k]))
            start = None
    return spans


def _headroom(ax, share=0.3):
    """Room above the curves for the panel's legend."""
    low, high = ax.get_ylim()
    ax.set_ylim(low, high + share * (high - low))


def draw_session(log, path, refresh_hz=None, title=None):
    """Draw `log` (read_log's arrays) into `path` (.png, .svg or .pdf), written whole or not at all.

    Returns session_figures(log, refresh_hz), what the picture's titles state."""
    ext = os.path.splitext(path)[1].lower()
    if ext not in EXTENSIONS:
        raise LogError(f"{path}: a picture is {', '.join(EXTENSIONS)}")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figures = session_figures(log, refresh_hz)
    t = log["flip_time_s"] - log["flip_time_s"][0]
    fig, axes = plt.subplots(4, 1, figsize=(10, 9), sharex=True, gridspec_kw={"height_ratios": [3, 2, 2, 1.5]})
    try:
        fig.suptitle(title or "a gaze-contingent session", fontsize=12)
        ax = axes[0]
        for start, end in _spans(t, log["predicted"] > 0):
            ax.axvspan(start, end, color="#c9b3e6", alpha=0.6, lw=0)
        ax.plot(t, log["gaze_x"], color="#1f77b4", lw=1.2, label="gaze x")
        ax.plot(t, log["fovea_x"], color="#1f77b4", lw=1.0, ls="--", label="fovea x")
        ax.plot(t, log["gaze_y"], color="#ff7f0e", lw=1.2, label="gaze y")
        ax.plot(t, log["fovea_y"], color="#ff7f0e", lw=1.0, ls="--", label="fovea y")
        ax.plot([], [], color="#c9b3e6", lw=6, label="fovea at a predicted landing")
        ax.set_ylabel("render px")
        ax.set_title(f"gaze and the fovea the loop placed; {figures['predicted']} of {figures['flips']} flips at a predicted "
                     "landing", fontsize=10)
        _headroom(ax)
        ax.legend(loc="upper right", fontsize=8, ncol=5)

        ax = axes[1]
        ax.plot(t, log["gaze_to_flip_ms"], color="#2ca02c", lw=0.8, marker=".", ms=2)
        hz = figures["refresh_hz"]
        words = f"median {figures['gaze_to_flip_ms_median']:.1f} ms, 95th percentile {figures['gaze_to_flip_ms_p95']:.1f} ms"
        if hz:
            for k in (1, 2):
                ax.axhline(1000 * k / hz, color="grey", lw=0.8, ls=":")
                ax.annotate(f"{k} refresh{'es' if k > 1 else ''}", (1.0, 1000 * k / hz), xycoords=("axes fraction", "data"),
                            fontsize=7, color="grey", ha="right", va="bottom",
                            bbox={"fc": "white", "ec": "none", "alpha": 0.8, "pad": 1})
            words += (f" ({figures['gaze_to_flip_refreshes_median']:.2f} refreshes of {hz:.0f} Hz, "
                      f"{'given' if figures['refresh_from'] == 'given' else 'the median interval between flips'})")
        ax.set_ylabel("ms")
        ax.set_title(f"gaze → flip: {words}", fontsize=10)

        ax = axes[2]
        ax.plot(t, log["render_ms"], color="#444444", lw=0.8, label="frame()")
        ax.step(t, log["budget_ms"], where="post", color="#1f77b4", lw=1.0, ls="--", label="budget")
        late = log["late"] > 0
        ax.plot(t[late], log["render_ms"][late], "o", color="#d62728", ms=4, label="late")
        ax.set_ylabel("ms")
        ax.set_title(f"each flip's frame against its budget; {figures['late']} late of {figures['flips']}", fontsize=10)
        _headroom(ax)
        ax.legend(loc="upper right", fontsize=8, ncol=3)

        ax = axes[3]
        ax.plot(t, log["fovea_converged"], color="#9467bd", lw=1.0, label="fovea converged (fraction)")
        ax.plot(t, log["width"] / log["width"].max(), color="#8c564b", lw=1.0, ls="--", label="size (share of the largest)")
        ax.set_ylim(-0.05, 1.05)
        ax.set_xlabel("seconds from the first flip")
        ax.legend(loc="lower right", fontsize=8, ncol=2)
        fig.tight_layout()
        # Written whole or not at all: into a file beside it, then given its name
        # (created as any file is, under the umask: a temporary file's own mode would be the owner's alone)
        folder = os.path.dirname(os.path.abspath(path))
        temporary = os.path.join(folder, f".session_plot.{os.getpid()}.{secrets.token_hex(4)}{ext}")
        try:
            with open(temporary, "xb") as f:
                fig.savefig(f, format=ext[1:], dpi=100)
            os.replace(temporary, path)
        except BaseException:
            if os.path.exists(temporary):
                os.unlink(temporary)
            raise
    finally:
        plt.close(fig)
    return figures


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("log", help="a per-flip log of gaze_contingent.py (--log; a failed session's LOG.partial too)")
    p.add_argument("-o", "--output", default=None, help="the picture: .png, .svg or .pdf (default: the log's name with .png)")
    p.add_argument("--refresh-hz", type=float, default=None,
                   help="the display's refresh rate the latency is read against (default: the median interval between flips)")
    p.add_argument("--title", default=None, help="the picture's title (default: the log's name)")
    args = p.parse_args(argv)
    output = args.output or os.path.splitext(args.log)[0] + ".png"
    if args.refresh_hz is not None and not (math.isfinite(args.refresh_hz) and 1 <= args.refresh_hz <= 1000):
        p.error(f"--refresh-hz: must be in [1, 1000] Hz, got {args.refresh_hz}")
    why = check_output(output, inputs={args.log: args.log}, extensions=EXTENSIONS)
    if why:
        p.error(f"{'--output' if args.output else 'the picture'}: {why}")
    try:
        log = read_log(args.log)
    except FileNotFoundError:
        p.error(f"{args.log}: no such file")
    except IsADirectoryError:
        p.error(f"{args.log} is a folder; give a session's log")
    except OSError as error:
        p.error(f"{args.log}: {error.strerror or error}")
    except (LogError, UnicodeDecodeError, csv.Error) as error:
        p.error(str(error) if isinstance(error, LogError) else f"{args.log}: not a CSV log ({error})")
    figures = draw_session(log, output, args.refresh_hz, title=args.title or os.path.basename(args.log))
    print(f"session_plot: {figures['flips']} flips, {figures['late']} late, gaze-to-flip median "
          f"{figures['gaze_to_flip_ms_median']:.1f} ms → {output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
