#!/usr/bin/env python3
"""A gaze-contingent PsychoPy window: foveal's real-time loop follows ioHub's eye tracker.

Every refresh: the tracker's new samples go to ``foveal.Loop`` (its saccade predictor sees each of
them) → ``loop.frame()`` returns within the frame budget an image whose fovea — around the gaze, or
around a saccade's predicted landing while the eye is in flight — is refined first (the GIL is
released while it renders on the worker threads) → the image is drawn and flipped. Per flip it
logs the latest gaze sample's time, the flip time (both on PsychoPy's clock: ioHub's time base is
``psychopy.core.getTime``), and the fovea's state (refining or converged), so the gaze-to-photon
latency is flip time − sample time and the fovea's refinement is read from the same log.

    python examples/psychopy/gaze_contingent.py                      # MouseGaze: the mouse is the eye
    python examples/psychopy/gaze_contingent.py --tracker eyelink.yaml   # any ioHub eye tracker
    xvfb-run -a python examples/psychopy/gaze_contingent.py --frames 60 --move-mouse --log frames.csv --plot session.png

``--tracker`` takes an ioHub device configuration (YAML) with one eye-tracker entry, e.g.
``eyetracker.hw.sr_research.eyelink.EyeTracker: {name: tracker, ...}``; without it ioHub's
MouseGaze simulator is used. ``--move-mouse`` moves the X pointer along a path with XTest (for
running without a person, under Xvfb). Escape ends the run.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import signal
import sys
import threading
import time

import numpy as np

from session_checks import check_display, check_foveal_inputs, check_output, refresh_rate
from session_plot import EXTENSIONS as PICTURES, draw_session, read_log


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--scene", default="builtin:box", help="scene for foveal.Scene (default: builtin:box)")
    p.add_argument("--camera", default=None, help="named camera of the scene (default: its first)")
    p.add_argument("--size", default="840x525", help="window and render size WxH in pixels (default 840x525)")
    p.add_argument("--display", default="47.5,30,60", help="the screen W_CM,H_CM,DIST_CM (default: the papers' 22-inch at 60 cm)")
    p.add_argument("--max-rays", type=int, default=400, help="n_max, AO rays per pixel of the fovea (default 400, the papers')")
    p.add_argument("--gamma", type=float, default=2.0, help="γ of the ray budget (default 2)")
    p.add_argument("--device", default="auto", help="auto, cpu or cuda")
    p.add_argument("--refresh-hz", type=float, default=None, help="the display's refresh rate (default: measured by PsychoPy, else 60; a measured rate over 240 Hz, "
                                                                "the pace of flips that do not wait for the vertical blank under Xvfb, "
                                                                "is said to be doubtful)")
    p.add_argument("--no-predict", action="store_true", help="no saccade landing prediction: the fovea stays at the measured gaze")
    p.add_argument("--landing", default="", metavar="NAME=VALUE,…",
                   help="the saccade landing predictor's parameters (docs/realtime.md), e.g. onset_deg_s=60 for a noisy tracker")
    p.add_argument("--margin-ms", type=float, default=None,
                   help="the least time each frame keeps free for the machine's pauses, ms (default: the loop's, 2 ms; more where "
                        "`foveal bench stalls` finds longer pauses; kept within half the budget the script leaves the loop each "
                        "flip; docs/realtime.md)")
    p.add_argument("--periphery-share", type=float, default=1.0,
                   help="the periphery's rays stop once a frame has spent this share of its budget, the fovea's go on to the "
                        "deadline (default 1: the periphery's too; less leaves a busy machine's pauses room; docs/realtime.md)")
    p.add_argument("--min-scale", type=float, default=0.25,
                   help="the smallest size the loop may render at where its base shading does not fit the budget, a share of "
                        "the size in (0, 1] (default 0.25; 1: the stimulus keeps its resolution throughout, and such frames come "
                        "late instead; docs/realtime.md)")
    p.add_argument("--no-rays-ahead", action="store_true",
                   help="once every pixel has its n(E), render nothing more (by default the spare time of each frame, up to half "
                        "its budget, takes every pixel on to n_max, nearest the gaze first: docs/realtime.md)")
    p.add_argument("--frames", type=int, default=0, help="stop after this many frames (0: until Escape)")
    p.add_argument("--tracker", default=None, help="ioHub eye-tracker configuration (YAML); default MouseGaze")
    p.add_argument("--move-mouse", action="store_true", help="move the pointer along a path (XTest), for runs without a person")
    p.add_argument("--log", default="gaze_contingent_frames.csv",
                   help="per-flip log (CSV; written as the session runs into LOG.partial, which takes the name LOG at its end: a failed "
                        "session keeps its flips there)")
    p.add_argument("--summary", default=None, help="write the latency summary as JSON")
    p.add_argument("--plot", default=None, metavar="PICTURE",
                   help="at the end, draw the session from its log: gaze and fovea, gaze → flip, each frame against its "
                        "budget, the fovea's state (.png, .svg or .pdf; session_plot.py draws any log later)")
    p.add_argument("--fullscreen", action="store_true", help="full screen (ioHub's mouse wants it for exact positions)")
    p.add_argument("--probe-stalls", type=float, default=0, metavar="SECONDS",
                   help="first measure for this long how often the machine itself pauses a working thread (foveal.stalls, "
                        "`foveal bench stalls`): the late frames to expect from it, not from the rendering (default 0: not)")
    args = p.parse_args(argv)
    check_args(p, args)
    return args


def check_args(parser, args):
    """Refuse bad values before the window opens: a session's log must not be lost at its end."""
    try:
        w, h = (int(v) for v in args.size.lower().split("x"))
        assert 1 <= w <= 16384 and 1 <= h <= 16384
    except (ValueError, AssertionError):
        parser.error(f"--size: expected WxH in pixels (1–16384 each), got {args.size!r}")
    try:
        display = [float(v) for v in args.display.split(",")]
        assert len(display) == 3 and all(math.isfinite(v) and v > 0 for v in display)
    except (ValueError, AssertionError):
        parser.error(f"--display: expected three positive numbers W_CM,H_CM,DIST_CM, got {args.display!r}")
    if args.landing and args.no_predict:
        parser.error("--landing: the predictor's parameters, but --no-predict turns it off")
    import foveal
    try:  # parsed and checked as the command line's --landing
        args.landing_params = foveal.gaze.landing_params(args.landing)
    except ValueError as error:
        parser.error(f"--landing: {error}")
    if args.margin_ms is not None and not (math.isfinite(args.margin_ms) and args.margin_ms >= 0):
        parser.error(f"--margin-ms: must be 0 or more ms, got {args.margin_ms}")
    if not 0 < args.periphery_share <= 1:
        parser.error(f"--periphery-share: must be in (0, 1], got {args.periphery_share}")
    if not 0 < args.min_scale <= 1:
        parser.error(f"--min-scale: must be in (0, 1], got {args.min_scale}")
    if args.refresh_hz is not None and not 1 <= args.refresh_hz <= 1000:
        parser.error(f"--refresh-hz: must be in [1, 1000] Hz, got {args.refresh_hz}")
    for name, value in (("--frames", args.frames), ("--max-rays", args.max_rays), ("--probe-stalls", args.probe_stalls)):
        if not value >= 0:
            parser.error(f"{name}: must be 0 or more, got {value}")
    inputs = {f"--scene {args.scene}": args.scene, f"--tracker {args.tracker}": args.tracker}  # (never written over)
    for name, path, extensions in (("--log", args.log, None), ("--summary", args.summary, None), ("--plot", args.plot, PICTURES)):
        why = check_output(path, inputs, extensions) if path is not None else ""
        if why:
            parser.error(f"{name}: {why}")
    if args.log is not None and os.path.exists(args.log + ".partial"):  # a failed session's flips: never written over
        parser.error(f"--log: {args.log}.partial holds the flips of a session that failed; move it away first")
    if args.plot is not None:
        try:
            import matplotlib  # noqa: F401 (drawn after the session: missing then, the picture would be lost)
        except ImportError:
            parser.error("--plot: matplotlib is not installed (scripts/python-env.sh installs it)")
    outputs = [(name, path) for name, path in (("--log", args.log), ("--summary", args.summary), ("--plot", args.plot))
               if path is not None]
    for k, (name, path) in enumerate(outputs):
        for other_name, other in outputs[k + 1:]:
            if os.path.abspath(path) == os.path.abspath(other):
                parser.error(f"{name} {path} and {other_name} {other}: two outputs into one file; give each its own name")
    # Before the stall probe and the window: the scene (loaded once: the session takes it), its camera, the device
    args.scene_object = check_foveal_inputs(parser, args.scene, args.camera, args.device)
    check_display(parser)


def tracker_config(path):
    if path is None:
        return {"eyetracker.hw.mouse.EyeTracker": {"name": "tracker", "controls": {"move": [], "blink": ["LEFT_BUTTON", "RIGHT_BUTTON"],
                                                                                    "saccade_threshold": 0.5}}}
    import yaml
    with open(path) as f:
        config = yaml.safe_load(f)
    trackers = [k for k in config if k.startswith("eyetracker.hw.")]
    if len(trackers) != 1:
        raise SystemExit(f"{path}: expected one eyetracker.hw.* entry, found {len(trackers)}")
    config[trackers[0]].setdefault("name", "tracker")
    return config


def move_pointer(stop: threading.Event):
    """Move the X pointer around a Lissajous path over the screen (XTest)."""
    from Xlib import X, display
    from Xlib.ext import xtest
    d = display.Display()
    width, height = d.screen().width_in_pixels, d.screen().height_in_pixels
    t0 = time.monotonic()
    while not stop.is_set():
        t = time.monotonic() - t0
        x = int(width / 2 + 0.4 * width * math.sin(1.3 * t))
        y = int(height / 2 + 0.4 * height * math.sin(0.9 * t + 0.5))
        xtest.fake_input(d, X.MotionNotify, x=x, y=y)
        d.sync()
        time.sleep(0.01)


def main(argv=None) -> int:
    args = parse_args(argv)
    import foveal
    from psychopy import core, event, visual
    from psychopy.iohub import launchHubServer

    machine = None
    if args.probe_stalls > 0:
        machine = foveal.stalls(duration_s=args.probe_stalls)
        machine.pop("stalls")
        print(f"gaze_contingent: the machine paused a working thread {machine['off_cpu']['count']} times off its CPU and "
              f"{machine['on_cpu']['count']} times on it in {machine['duration_s']:.1f} s (worst "
              f"{max(machine['off_cpu']['worst_ms'], machine['on_cpu']['worst_ms']):.1f} ms): up to "
              f"{machine['late_frames_per_minute_at_most']:.0f} late frames a minute from the machine itself")
    w, h = (int(v) for v in args.size.lower().split("x"))
    wcm, hcm, dcm = (float(v) for v in args.display.split(","))
    display = foveal.Display(wcm, hcm, dcm, w, h)
    scene = args.scene_object

    win = visual.Window((w, h), units="pix", fullscr=args.fullscreen, allowGUI=False, color=(-1, -1, -1), pos=(0, 0))
    # The display's rate: as given, else as PsychoPy measures it (said where that is doubtful)
    measured = None if args.refresh_hz is not None else win.getActualFrameRate(nIdentical=10, nMaxFrames=60)
    refresh_hz, refresh_note = refresh_rate(args.refresh_hz, measured)
    if refresh_note:
        print(f"gaze_contingent: {refresh_note}")
    loop = foveal.Loop(scene, size=(w, h), camera=args.camera, display=display, max_rays=args.max_rays, gamma=args.gamma,
                       refresh_hz=refresh_hz, predict=not args.no_predict, device=args.device, landing=args.landing_params,
                       margin_ms=args.margin_ms, periphery_share=args.periphery_share, rays_ahead=not args.no_rays_ahead,
                       min_scale=args.min_scale)
    if loop.note:
        print(f"gaze_contingent: {loop.note}")
    io = launchHubServer(window=win, **tracker_config(args.tracker))
    tracker = io.devices.tracker
    tracker.setRecordingState(True)
    stim = visual.ImageStim(win, image=np.zeros((h, w, 3), np.float32), size=(w, h), units="pix", interpolate=False)

    stop = threading.Event()
    mover = None
    if args.move_mouse:
        mover = threading.Thread(target=move_pointer, args=(stop,), daemon=True)
        mover.start()

    def to_render(x, y):
        # ioHub 'pix' units: origin at the window centre, y up → render pixels, origin top-left, y down
        return (x + w / 2.0, h / 2.0 - y)

    # Each flip is logged as it happens, into LOG.partial (flushed every second), and the file takes
    # its name once the session has ended: a session that fails keeps every flip logged so far there —
    # one stopped by SIGTERM too (a session manager's kill, a cluster's time limit), which otherwise
    # ends Python without its clean-up
    def terminated(signum, _frame):
        raise SystemExit(128 + signum)
    signal.signal(signal.SIGTERM, terminated)
    partial = args.log + ".partial"
    log_file = open(partial, "w", newline="")
    writer = None
    # The numbers the summary needs, per flip (a tuple each: an hour at 60 Hz is 216,000 of them)
    rows = []  # (gaze x, gaze y, sample time, converged, render ms, late, gaze-to-flip ms)
    frames_left_behind = 0  # frames whose rays left chunks to threads the machine had paused
    session = foveal.machine_snapshot()  # what else runs on the machine during the session (named at its end)
    own_ms = 0.0
    texture = None  # the image PsychoPy is given, in its float format: one buffer, written every frame
    flip_index = 0
    completed = False
    gaze_px = (w / 2.0, h / 2.0)
    sample_time = core.getTime()
    try:
        while args.frames == 0 or flip_index < args.frames:
            if "escape" in event.getKeys():
                break
            # Every sample since the last flip goes to the loop (the saccade predictor needs them all)
            for e in tracker.getEvents():
                if not hasattr(e, "time"):
                    continue
                x, y = getattr(e, "gaze_x", None), getattr(e, "gaze_y", None)
                if x is None or y is None or not (math.isfinite(x) and math.isfinite(y)):
                    loop.push(e.time, None)
                    continue
                gaze_px = to_render(x, y)
                sample_time = e.time
                loop.push(e.time, gaze_px)
            if not rows or sample_time <= rows[-1][2]:
                position = tracker.getLastGazePosition()  # trackers whose events carry no gaze
                if position is not None:
                    gaze_px = to_render(*position)
                    sample_time = core.getTime()
                    loop.push(sample_time, gaze_px)
            start = core.getTime()
            frame = loop.frame()
            rendered = core.getTime()
            # Linear → sRGB in PsychoPy's [−1, 1], rows bottom-up, on foveal's threads into one buffer (1.9 ms
            # at 840x525 on two cores under Xvfb, where NumPy's table lookup took 3.1 ms of the refresh)
            if texture is None or texture.shape != frame.image.shape:  # (the loop's size may change)
                texture = np.empty(frame.image.shape, np.float32)
            stim.image = foveal.linear_to_srgb(frame.image, texture, low=-1.0, high=1.0, bottom_up=True)  # (uploaded here)
            stim.draw()
            flip = win.flip()
            # The loop gets what this script's own work (conversion, drawing, the flip) leaves of the refresh
            # (from the second flip: the first, which creates the window's first texture, took 30 ms under
            # Xvfb where the next took 8–11, and the 4-ms budget it left made the loop render smaller)
            overhead = flip - rendered
            if rows:
                own_ms = overhead * 1000 if len(rows) == 1 else 0.8 * own_ms + 0.2 * overhead * 1000
                loop.budget_ms = max(4.0, 1000.0 / refresh_hz - own_ms - 1.0)
            row = {"flip": flip_index, "gaze_x": gaze_px[0], "gaze_y": gaze_px[1], "sample_time_s": sample_time,
                   "fovea_x": frame.gaze[0] / frame.scale, "fovea_y": frame.gaze[1] / frame.scale,
                   "predicted": int(frame.predicted), "fovea": frame.fovea,
                   "fovea_converged": round(frame.fovea_converged, 4), "rays": frame.rays,
                   "render_start_s": start, "render_ms": 1000 * (rendered - start), "library_ms": frame.ms,
                   "late": int(frame.late), "flip_time_s": flip, "gaze_to_flip_ms": 1000 * (flip - sample_time),
                   # (appended: readers by column index keep theirs)
                   "budget_ms": frame.budget_ms, "width": frame.image.shape[1], "height": frame.image.shape[0],
                   # chunks of the frame's rays left to threads the machine had paused rather than waited for
                   "chunks_left_behind": frame.chunks_left_behind}
            if writer is None:
                writer = csv.DictWriter(log_file, fieldnames=list(row))
                writer.writeheader()
            writer.writerow(row)
            if flip_index % max(1, round(refresh_hz)) == 0:
                log_file.flush()
            rows.append((gaze_px[0], gaze_px[1], sample_time, frame.fovea == "converged", row["render_ms"], frame.late, row["gaze_to_flip_ms"]))
            frames_left_behind += frame.chunks_left_behind > 0
            flip_index += 1
        completed = True
    finally:
        log_file.close()  # (first: what follows talks to ioHub and the window, which may fail in turn)
        if not completed:
            print(f"gaze_contingent: the session failed after {flip_index} flips; they are logged in {partial}", file=sys.stderr)
        others = foveal.busiest_others(session)
        stop.set()
        tracker.setRecordingState(False)
        io.quit()
        win.close()

    if writer is None:
        with open(partial, "w", newline="") as f:
            csv.writer(f).writerow(["flip"])
    os.replace(partial, args.log)
    latencies = np.array([r[6] for r in rows[1:]])  # the first flip waits for the tracker
    summary = {"flips": len(rows), "size": [w, h], "render_size": list(loop.size), "scene": args.scene, "device": loop.device,
               "refresh_hz": refresh_hz, "refresh_measured": args.refresh_hz is None, "refresh_note": refresh_note,
               "budget_ms": loop.budget_ms, "margin_ms": loop.margin_ms, "periphery_share": loop.periphery_share,
               "rays_ahead": loop.rays_ahead, "min_scale": loop.min_scale,
               "predict": not args.no_predict,
               "gaze_positions": len({(round(r[0]), round(r[1])) for r in rows}),
               "frames_late": sum(bool(r[5]) for r in rows),
               "frames_left_behind": frames_left_behind,
               "flips_converged": sum(r[3] for r in rows),
               "gaze_to_flip_ms_median": float(np.median(latencies)) if len(latencies) else None,
               "gaze_to_flip_ms_p95": float(np.percentile(latencies, 95)) if len(latencies) else None,
               "gaze_to_flip_refreshes_median": float(np.median(latencies)) * refresh_hz / 1000 if len(latencies) else None,
               "render_ms_median": float(np.median([r[4] for r in rows])) if rows else None,
               "gaze_sample_hz": loop.gaze_sample_hz,
               "machine_stalls": machine, "other_processes": others, "gaze_note": loop.gaze_note}
    print(f"gaze_contingent: {summary['flips']} flips at {w}x{h} on {summary['device']} ({refresh_hz:.0f} Hz, budget "
          f"{loop.budget_ms:.1f} ms), {summary['gaze_positions']} gaze positions, gaze-to-flip median "
          f"{summary['gaze_to_flip_ms_median']:.1f} ms ({summary['gaze_to_flip_refreshes_median']:.2f} refreshes), 95th percentile "
          f"{summary['gaze_to_flip_ms_p95']:.1f} ms; {summary['frames_late']} late frames; log {args.log}")
    if refresh_note:  # (said at the start too, and now beside the figures it makes doubtful)
        print(f"gaze_contingent: {refresh_note}")
    if loop.gaze_note:  # what the tracker's samples leave the predictor (too slow, times not in seconds, a clock gone back)
        print(f"gaze_contingent: {loop.gaze_note}")
    if others:  # what took the loop's cores: what to stop before the next session
        print("gaze_contingent: what else ran during the session: " + "; ".join(
            f"{o['name']} ({'a kernel thread' if o['kernel'] else 'pid ' + str(o['pid'])}) {o['cpu_ms']:.1f} ms" for o in others))
    if args.summary:
        with open(args.summary, "w") as f:
            json.dump(summary, f, indent=2)
    if args.plot and not rows:
        print(f"gaze_contingent: --plot: no flips, so no picture ({args.plot} not written)")
    elif args.plot:  # (from the log as written: the picture session_plot.py draws of it)
        try:
            draw_session(read_log(args.log), args.plot, refresh_hz, title=f"{args.log}: {len(rows)} flips at {w}x{h}, {refresh_hz:.0f} Hz")
        except (OSError, ValueError) as error:  # (a full disk, say: the log and the summary are written)
            print(f"gaze_contingent: --plot {args.plot}: {error}; the log {args.log} is kept (session_plot.py draws it)", file=sys.stderr)
            return 1
        print(f"gaze_contingent: the session drawn in {args.plot}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
