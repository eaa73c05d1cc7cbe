#!/usr/bin/env python3
"""A gaze-contingent PsychoPy window: foveated frames rendered by foveal follow ioHub's eye tracker.

Each frame: the tracker's latest gaze sample → foveal renders the foveated frame around it (the
GIL is released meanwhile) → the frame is drawn and flipped. Per frame it logs the gaze sample's
time, the render time and the flip time, all on PsychoPy's own clock (ioHub's time base is
``psychopy.core.getTime``), so the gaze-to-photon latency is flip time − sample time.

    python examples/psychopy/gaze_contingent.py                      # MouseGaze: the mouse is the eye
    python examples/psychopy/gaze_contingent.py --tracker eyelink.yaml   # any ioHub eye tracker
    xvfb-run -a python examples/psychopy/gaze_contingent.py --frames 60 --move-mouse --log frames.csv

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
import sys
import threading
import time

import numpy as np


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--scene", default="builtin:box", help="scene for foveal.Scene (default: builtin:box)")
    p.add_argument("--camera", default=None, help="named camera of the scene (default: its first)")
    p.add_argument("--size", default="840x525", help="window and render size WxH in pixels (default 840x525)")
    p.add_argument("--display", default="47.5,30,60", help="the screen W_CM,H_CM,DIST_CM (default: the papers' 22-inch at 60 cm)")
    p.add_argument("--max-rays", type=int, default=100, help="n_max, AO rays per pixel at the gaze (default 100)")
    p.add_argument("--gamma", type=float, default=2.0, help="γ of the ray budget (default 2)")
    p.add_argument("--device", default="auto", help="auto, cpu or cuda")
    p.add_argument("--frames", type=int, default=0, help="stop after this many frames (0: until Escape)")
    p.add_argument("--tracker", default=None, help="ioHub eye-tracker configuration (YAML); default MouseGaze")
    p.add_argument("--move-mouse", action="store_true", help="move the pointer along a path (XTest), for runs without a person")
    p.add_argument("--log", default="gaze_contingent_frames.csv", help="per-frame log (CSV)")
    p.add_argument("--summary", default=None, help="write the latency summary as JSON")
    p.add_argument("--fullscreen", action="store_true", help="full screen (ioHub's mouse wants it for exact positions)")
    return p.parse_args(argv)


def linear_to_psychopy(image: np.ndarray) -> np.ndarray:
    """Linear RGB [0, 1] → sRGB → PsychoPy's float image range [−1, 1], rows bottom-up."""
    c = np.clip(image, 0.0, 1.0)
    srgb = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    return np.flipud(srgb * 2.0 - 1.0).astype(np.float32)


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

    w, h = (int(v) for v in args.size.lower().split("x"))
    wcm, hcm, dcm = (float(v) for v in args.display.split(","))
    display = foveal.Display(wcm, hcm, dcm, w, h)
    scene = foveal.Scene(args.scene)
    renderer = foveal.Renderer(scene, device=args.device)

    win = visual.Window((w, h), units="pix", fullscr=args.fullscreen, allowGUI=False, color=(-1, -1, -1), pos=(0, 0))
    io = launchHubServer(window=win, **tracker_config(args.tracker))
    tracker = io.devices.tracker
    tracker.setRecordingState(True)
    stim = visual.ImageStim(win, image=np.zeros((h, w, 3), np.float32), size=(w, h), units="pix", interpolate=False)

    stop = threading.Event()
    mover = None
    if args.move_mouse:
        mover = threading.Thread(target=move_pointer, args=(stop,), daemon=True)
        mover.start()

    rows = []
    frame_index = 0
    gaze_px = (w / 2.0, h / 2.0)
    sample_time = core.getTime()
    try:
        while args.frames == 0 or frame_index < args.frames:
            if "escape" in event.getKeys():
                break
            samples = [e for e in tracker.getEvents() if hasattr(e, "time")]
            position = tracker.getLastGazePosition()
            if position is not None and samples:
                # ioHub 'pix' units: origin at the window centre, y up → render pixels, origin top-left, y down
                gaze_px = (position[0] + w / 2.0, h / 2.0 - position[1])
                sample_time = samples[-1].time  # ioHub's time base is PsychoPy's core.getTime()
            start = core.getTime()
            frame = renderer.render(size=(w, h), camera=args.camera, gaze=gaze_px, max_rays=args.max_rays,
                                    gamma=args.gamma, display=display)
            rendered = core.getTime()
            stim.image = linear_to_psychopy(frame.image)
            stim.draw()
            flip = win.flip()
            rows.append({"frame": frame_index, "gaze_x": gaze_px[0], "gaze_y": gaze_px[1], "sample_time_s": sample_time,
                         "render_start_s": start, "render_ms": 1000 * (rendered - start),
                         "library_ms": frame.library_ms, "flip_time_s": flip,
                         "gaze_to_flip_ms": 1000 * (flip - sample_time)})
            frame_index += 1
    finally:
        stop.set()
        tracker.setRecordingState(False)
        io.quit()
        win.close()

    with open(args.log, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]) if rows else ["frame"])
        writer.writeheader()
        writer.writerows(rows)
    latencies = np.array([r["gaze_to_flip_ms"] for r in rows[1:]])  # the first frame waits for the tracker
    summary = {"frames": len(rows), "size": [w, h], "scene": args.scene, "device": renderer.device,
               "gaze_positions": len({(round(r["gaze_x"]), round(r["gaze_y"])) for r in rows}),
               "gaze_to_flip_ms_median": float(np.median(latencies)) if len(latencies) else None,
               "gaze_to_flip_ms_p95": float(np.percentile(latencies, 95)) if len(latencies) else None,
               "render_ms_median": float(np.median([r["render_ms"] for r in rows])) if rows else None}
    print(f"gaze_contingent: {summary['frames']} frames at {w}x{h} on {summary['device']}, "
          f"{summary['gaze_positions']} gaze positions, gaze-to-flip median {summary['gaze_to_flip_ms_median']:.1f} ms, "
          f"95th percentile {summary['gaze_to_flip_ms_p95']:.1f} ms; log {args.log}")
    if args.summary:
        with open(args.summary, "w") as f:
            json.dump(summary, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
