#!/usr/bin/env python3
"""The real-time loop with a moving camera: does it keep its AO rays?

Replays a gaze recording through `foveal.Loop` (the loop of `replay --realtime` and `view
--realtime`) while the camera orbits its look point (`Camera.orbit`, as `replay --orbit`), once
keeping the rays of the surfaces each moved view still sees (the default) and once starting each
moved view afresh (`keep_history=False`, what every build before did). The samples are pushed as a
tracker delivers them, a frame every refresh of the recording's clock, as fast as frames come (the
wall clock: each frame within its budget). Reports per run the frames, the late ones, the frames
whose fovea was converged, the frame time and the size the loop rendered at; then judges the last
frame, at the loop's size, against two full references at its camera (n_max rays at every pixel,
two seeds: `foveal.compare(reference2=...)`), next to the paper's foveated frame at the same camera
and gaze (a whole frame, no deadline).

    .venv/bin/python bench/loop_orbit.py [--shared ../shared] [--orbit 10 30] [--duration 4] [--rest 1.5]
                                         [--max-angle 40] [--out build/bench-orbit] [--markdown F]
                                         [--picture PNG]

After the orbit the camera rests --rest seconds: the size the loop had before the camera moved
comes back half a second on, built a few rows at a time while the smaller view is shown; the
second table gives the late frames at rest and when the full size was shown.

--picture draws the last frames of the first speed side by side: rays kept, afresh, the paper's
frame (each scaled to half the size asked for, nearest pixel, as a display shows a smaller frame).
"""
import argparse
import json
import statistics
import sys
from pathlib import Path

import numpy as np

import foveal


def run(scene, rec, speed, keep, a):
    width, height = (int(v) for v in a.size.split("x"))
    loop = foveal.Loop(scene, size=(width, height), max_rays=a.max_rays, refresh_hz=a.fps, device=a.device,
                       keep_history=keep)
    camera = scene.cameras[0]
    samples = rec.samples
    sx, sy = width / rec.screen[0], height / rec.screen[1]  # the recording's screen fills the render
    t = samples["t_s"] - samples["t_s"][0]
    duration = min(a.duration, a.max_angle / abs(speed))
    count = int(duration * a.fps) + 1
    first = np.searchsorted(t, a.start)

    def push_until(now):  # the samples the tracker has delivered by `now`
        nonlocal first
        end = np.searchsorted(t, now, side="right")
        for i in range(first, end):
            s = samples[i]
            loop.push(float(t[i]), (float(s["x"]) * sx, float(s["y"]) * sy) if s["valid"] else None)
        first = end

    frames = []
    last = None
    for k in range(count):
        push_until(a.start + k / a.fps)
        view = camera.orbit(speed * k / a.fps)
        f = loop.frame(camera=view)
        frames.append((f.ms, f.budget_ms, f.fovea_converged, f.kept_pixels, f.image.shape[1], f.image.shape[0]))
        last = (f, view)
    f, view = last
    # Then the camera rests: the size it had before it moved comes back (half a second on), built a
    # few rows at a time while the smaller view is shown
    rest = []
    for k in range(int(a.rest * a.fps)):
        push_until(a.start + (count + k) / a.fps)
        r = loop.frame(camera=view)
        rest.append((r.ms, r.budget_ms, r.rebuilding, r.image.shape[1]))
    back = next((k for k, (_, _, _, w) in enumerate(rest) if w == width), None)
    image = np.array(f.image)
    h, w = image.shape[:2]
    gaze = tuple(f.gaze)
    renderer = foveal.Renderer(scene, device=a.device)
    refs = [renderer.render(size=(w, h), camera=view, mode="full", max_rays=a.max_rays, seed=1001 + 1000 * k).image for k in (0, 1)]
    paper = renderer.render(size=(w, h), camera=view, gaze=gaze, max_rays=a.max_rays).image
    scores = {}
    for label, img in (("loop", image), ("paper", paper)):
        d = foveal.compare(img, refs[0], gaze=gaze, reference2=refs[1])
        fovea = next(b for b in d["bands"] if b["name"].startswith("q"))
        scores[label] = (d["acuity_weighted_ratio"], fovea["noise_ratio"])
    ms = sorted(m for m, *_ in frames)
    pictures = {"loop": image, "paper": paper}
    return pictures, {
        "orbit": speed, "history": "kept" if keep else "afresh", "frames": len(frames), "seconds": len(frames) / a.fps,
        "late": sum(m > b for m, b, *_ in frames), "converged": sum(c >= 1 for _, _, c, *_ in frames),
        "mean_converged": statistics.mean(c for _, _, c, *_ in frames), "ms_p50": statistics.median(ms),
        "ms_p99": ms[max(0, int(0.99 * len(ms)) - 1)], "size": f"{w}x{h}",
        "error": scores["loop"][0], "fovea_error": scores["loop"][1], "paper_error": scores["paper"][0],
        "rest_frames": len(rest), "rest_late": sum(m > b for m, b, *_ in rest), "rest_ms_max": max((m for m, *_ in rest), default=0.0),
        "rebuilding_frames": sum(1 for _, _, r, _ in rest if r),
        "full_size_after_ms": None if back is None else 1000 * (back + 1) / a.fps,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--shared", default="../shared")
    ap.add_argument("--scene", default="scenes/dragon-box.json")
    ap.add_argument("--recording", help="gaze recording (default: the shared EyeLink recording)")
    ap.add_argument("--orbit", type=float, nargs="+", default=[10.0, 30.0], help="orbit speeds, degrees per second")
    ap.add_argument("--start", type=float, default=2.0, help="seconds into the recording")
    ap.add_argument("--duration", type=float, default=4.0, help="seconds of gaze, at most --max-angle of orbit")
    ap.add_argument("--max-angle", type=float, default=40.0,
                    help="the orbit's extent, degrees (the dragon's box is open towards its first camera only)")
    ap.add_argument("--rest", type=float, default=1.5, help="seconds the camera then rests (the size it had comes back)")
    ap.add_argument("--fps", type=float, default=60.0, help="the display's refresh rate, Hz (one frame each)")
    ap.add_argument("--size", default="840x525")
    ap.add_argument("--max-rays", type=int, default=400)
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--out", default="build/bench-orbit")
    ap.add_argument("--markdown", help="also write the table here")
    ap.add_argument("--picture", help="the first speed's last frames side by side (PNG): rays kept, afresh, the paper's frame")
    a = ap.parse_args()
    recording = Path(a.recording) if a.recording else Path(a.shared) / "data/gaze/eyelink/monoRemote500.asc"
    if not recording.exists():
        print(f"skipped: {recording} is absent (the shared data folder holds it)")
        return 0
    scene = foveal.Scene(a.scene)
    rec = foveal.gaze.read(str(recording))
    rows, shown = [], []
    for speed in a.orbit:
        for keep in (True, False):
            pictures, row = run(scene, rec, speed, keep, a)
            rows.append(row)
            if speed == a.orbit[0]:
                shown.append(pictures["loop"])
                if not keep:
                    shown.append(pictures["paper"])
            print(f"orbit {speed:g} °/s, {rows[-1]['history']}: done", file=sys.stderr)
    if a.picture:
        width, height = (int(v) // 2 for v in a.size.split("x"))
        panels = []
        for img in shown:  # nearest pixel to half the size asked for, a white gap between
            ys = (np.arange(height) * img.shape[0] // height).clip(0, img.shape[0] - 1)
            xs = (np.arange(width) * img.shape[1] // width).clip(0, img.shape[1] - 1)
            panels += [img[ys][:, xs], np.ones((height, 6, 3), np.float32)]
        foveal.save_image(np.ascontiguousarray(np.concatenate(panels[:-1], axis=1)), a.picture)
    lines = ["| orbit °/s | rays of a moved view | frames (s) | late | fovea converged (frames) | mean converged fraction | "
             "frame ms p50 / p99 | size at the end | last frame: acuity-weighted error × noise | its fovea | the paper's frame |",
             "|---:|---|---:|---:|---:|---:|---:|---|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['orbit']:g} | {r['history']} | {r['frames']} ({r['seconds']:.1f}) | {r['late']} | {r['converged']} | "
                     f"{r['mean_converged']:.3f} | {r['ms_p50']:.1f} / {r['ms_p99']:.1f} | {r['size']} | {r['error']:.2f} | "
                     f"{r['fovea_error']:.2f} | {r['paper_error']:.2f} |")
    lines += ["", "Then at rest:", "",
              "| orbit °/s | rays of a moved view | frames at rest (s) | late | longest frame ms | frames building the full size | "
              "full size shown after (ms at rest) |", "|---:|---|---:|---:|---:|---:|---:|"]
    for r in rows:
        back = "—" if r["full_size_after_ms"] is None else f"{r['full_size_after_ms']:.0f}"
        lines.append(f"| {r['orbit']:g} | {r['history']} | {r['rest_frames']} ({r['rest_frames'] / a.fps:.1f}) | {r['rest_late']} | "
                     f"{r['rest_ms_max']:.1f} | {r['rebuilding_frames']} | {back} |")
    table = "\n".join(lines)
    print(table)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "loop_orbit.json").write_text(json.dumps(rows, indent=1))
    if a.markdown:
        Path(a.markdown).write_text(table + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
