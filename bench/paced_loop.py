#!/usr/bin/env python3
"""The real-time loop paced as an application runs it: a frame at every refresh, then a wait.

`foveal bench latency` runs its frames back to back on a simulated display clock, so the loop's
cores never rest; a gaze-contingent application (the PsychoPy example, `view --realtime`) asks for
a frame at each refresh and waits for the next. This script does the latter with `foveal.Loop` on
a gaze recording: at every refresh of the wall clock it pushes the samples recorded up to then
(the recording's screen fills the render), asks for a frame with the latest gaze, and sleeps until
the next refresh. It reports the frames, the late ones (a frame costing more than its budget), the
refreshes missed (a frame handed back after the next refresh was due), the frame time p50 / p99,
and what else ran on the machine meanwhile (`foveal.machine_snapshot`).

    .venv/bin/python bench/paced_loop.py [--recording REC] [--start 2] [--duration 40]
                                         [--refresh-hz 60] [--frame-budget-ms MS] [--size 840x525] [--scene SCENE]
                                         [--max-rays 400] [--device cpu|cuda|auto] [--json F]

Run it under a scheduling policy to compare (for example `chrt -f 50`, as root).
"""
import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

import foveal
from outputs import check_outputs, refuse_by_option, write_output



def main():
    here = Path(__file__).resolve().parent.parent
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--recording", default=str(here.parent / "shared/data/gaze/eyelink/monoRemote500.asc"),
                   help="a gaze recording in any format foveal.gaze.read reads (the shared EyeLink recording)")
    p.add_argument("--start", type=float, default=2.0, help="seconds into the recording (2)")
    p.add_argument("--duration", type=float, default=40.0, help="seconds of frames (40)")
    p.add_argument("--refresh-hz", type=float, default=60.0, help="the display's refresh rate (60)")
    p.add_argument("--frame-budget-ms", type=float,
                   help="each frame's budget, ms (default: one refresh; an experiment gives the loop what its own drawing and "
                        "flipping leave of the refresh, 4-9 ms in the PsychoPy example under Xvfb)")
    p.add_argument("--size", default="840x525", help="render size WxH (840x525)")
    p.add_argument("--scene", default=str(here / "scenes/dragon-box.json"),
                   help="the scene (the dragon box, bench latency's)")
    p.add_argument("--max-rays", type=int, default=400, help="n_max (400)")
    p.add_argument("--device", default="cpu", help="where the loop renders: cpu, cuda or auto (cpu, as bench latency)")
    p.add_argument("--json", help="write the figures as JSON")
    a = p.parse_args()
    if not (a.duration > 0 and a.refresh_hz > 0 and a.start >= 0):
        p.error("--duration and --refresh-hz must be > 0, --start >= 0")
    if not os.path.exists(a.recording):
        p.error(f"--recording: {a.recording} does not exist")
    try:
        width, height = (int(v) for v in a.size.lower().split("x"))
    except ValueError:
        p.error(f"--size: {a.size} is not WxH")
    check_outputs(p, [("--json", a.json)], [a.recording, a.scene])
    try:
        scene = foveal.Scene(a.scene)
    except (OSError, ValueError) as e:
        p.error(f"--scene: {e}")
    try:
        rec = foveal.gaze.read(a.recording)
    except (OSError, ValueError) as e:
        p.error(f"--recording: {e}")
    samples = rec.samples
    t = samples["t_s"] - samples["t_s"][0]
    if a.start >= t[-1]:
        p.error(f"--start: {a.start} s is past the recording's end ({t[-1]:.1f} s)")
    sx, sy = width / rec.screen[0], height / rec.screen[1]
    try:
        loop = foveal.Loop(scene, size=(width, height), max_rays=a.max_rays, refresh_hz=a.refresh_hz,
                           frame_budget_ms=a.frame_budget_ms, device=a.device)
    except (ValueError, RuntimeError) as e:  # the loop names its keyword: the option that set it
        refuse_by_option(p, e, {"size": "--size", "max_rays": "--max-rays", "refresh_hz": "--refresh-hz", "device": "--device",
                                "frame_budget_ms": "--frame-budget-ms"})
    period = 1.0 / a.refresh_hz
    count = int(round(a.duration * a.refresh_hz))
    first = int(np.searchsorted(t, a.start))
    ms, rays, late, missed = [], [], [], 0
    snapshot = foveal.machine_snapshot()
    origin = time.perf_counter() + 0.05
    gaze = None
    for k in range(count):
        due = origin + k * period
        while True:  # sleep to a millisecond before the refresh, then wait for it exactly
            left = due - time.perf_counter()
            if left <= 0:
                break
            if left > 0.002:
                time.sleep(left - 0.001)
        now = a.start + k * period
        end = int(np.searchsorted(t, now, side="right"))
        for i in range(first, end):
            s = samples[i]
            point = (float(s["x"]) * sx, float(s["y"]) * sy) if s["valid"] else None
            loop.push(float(t[i]), point)
            gaze = point
        first = end
        frame = loop.frame(gaze, now)
        ms.append(frame.ms)
        rays.append(frame.rays)
        if frame.late:
            late.append({"index": k, "ms": round(frame.ms, 3)})
        if time.perf_counter() > due + period:
            missed += 1
    others = foveal.busiest_others(snapshot, most=5)
    out = {
        "recording": a.recording, "scene": a.scene, "device": loop.device, "size": [width, height],
        "refresh_hz": a.refresh_hz, "budget_ms": loop.budget_ms, "frames": count, "frames_late": len(late),
        "refreshes_missed": missed, "frame_ms_p50": float(np.percentile(ms, 50)), "frame_ms_p99": float(np.percentile(ms, 99)),
        "rays_per_frame": float(np.mean(rays)), "late_frames": late, "scale": loop.scale, "others": others,
    }
    print(f"{count} frames at {a.refresh_hz:g} Hz ({loop.budget_ms:.1f} ms each) on {loop.device}: {len(late)} late, {missed} refreshes missed; "
          f"frame p50 {out['frame_ms_p50']:.1f} ms, p99 {out['frame_ms_p99']:.1f} ms; {out['rays_per_frame']:,.0f} AO rays a frame")
    if others:
        print("what else ran: " + "; ".join(f"{o['name']} {o['cpu_ms']:.1f} ms in {int(o['slices'])} turns" for o in others))
    if a.json:
        write_output(a.json, json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
