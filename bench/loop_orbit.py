#!/usr/bin/env python3
"""The real-time loop with a moving camera: does it keep its AO rays?

Replays a gaze recording through `foveal replay --realtime` while the camera orbits its look point
(`--orbit DEG_PER_S`), once keeping the rays of the surfaces the moved view still sees (the
default) and once starting each moved view afresh (`--no-history`). Reports per run the frames,
the late ones, the frames whose fovea was converged, the frame time, and the size the loop rendered
at; then judges the last frame against two full references at its camera and size (n_max rays at
every pixel, two seeds: `foveal compare --reference2`), next to the paper's foveated frame at the
same camera and gaze (one whole frame, no deadline).

    python3 bench/loop_orbit.py [--foveal build/foveal] [--shared ../shared] [--orbit 10 30]
                                [--duration 4] [--out build/bench-orbit] [--markdown F]
"""
import argparse
import csv
import json
import math
import statistics
import struct
import subprocess
import sys
from pathlib import Path


def png_size(path):
    with open(path, "rb") as f:
        head = f.read(24)
    if head[:8] != b"\x89PNG\r\n\x1a\n":
        raise SystemExit(f"{path}: not a PNG")
    return struct.unpack(">II", head[16:24])


def orbit(eye, look, degrees):
    """The eye turned about the vertical through the look point (foveal's orbit_camera with up = +y)."""
    a = math.radians(degrees)
    rx, ry, rz = (e - l for e, l in zip(eye, look))
    return [look[0] + rx * math.cos(a) + rz * math.sin(a), look[1] + ry, look[2] - rx * math.sin(a) + rz * math.cos(a)]


def run(cmd):
    done = subprocess.run([str(c) for c in cmd], capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"failed ({done.returncode}): {' '.join(map(str, cmd))}\n{done.stderr}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--foveal", default="build/foveal")
    ap.add_argument("--shared", default="../shared")
    ap.add_argument("--scene", default="scenes/dragon-box.json")
    ap.add_argument("--recording", help="gaze recording (default: the shared EyeLink recording)")
    ap.add_argument("--orbit", type=float, nargs="+", default=[10.0, 30.0], help="orbit speeds, degrees per second")
    ap.add_argument("--start", type=float, default=2.0)
    ap.add_argument("--duration", type=float, default=4.0, help="seconds of gaze, at most --max-angle of orbit")
    ap.add_argument("--max-angle", type=float, default=40.0,
                    help="the orbit's extent, degrees (the dragon's box is open towards the first camera only)")
    ap.add_argument("--fps", type=float, default=60.0)
    ap.add_argument("--size", default="840x525")
    ap.add_argument("--out", default="build/bench-orbit")
    ap.add_argument("--markdown", help="also write the table here")
    a = ap.parse_args()
    recording = Path(a.recording) if a.recording else Path(a.shared) / "data/gaze/eyelink/monoRemote500.asc"
    if not recording.exists():
        print(f"skipped: {recording} is absent (the shared data folder holds it)")
        return 0
    scene = json.loads(Path(a.scene).read_text())
    camera = scene["cameras"][0]
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    width, height = (int(v) for v in a.size.split("x"))
    rows = []
    for speed in a.orbit:
        for keep in (True, False):
            name = f"orbit{speed:g}-{'kept' if keep else 'afresh'}"
            frames_dir = out / name
            if frames_dir.exists():
                for f in frames_dir.iterdir():
                    f.unlink()
                frames_dir.rmdir()
            cmd = [a.foveal, "replay", "--gaze", recording, "--scene", a.scene, "--size", a.size, "--realtime", "--fps", a.fps,
                   "--start", a.start, "--duration", min(a.duration, a.max_angle / abs(speed)), "--orbit", speed, "-o", frames_dir, "-q"]
            run(cmd + ([] if keep else ["--no-history"]))
            frames = list(csv.DictReader(open(frames_dir / "frames.csv")))
            ms = sorted(float(f["ms"]) for f in frames)
            converged = [float(f["fovea_converged"]) for f in frames]
            last = frames[-1]
            png = frames_dir / f"frame_{int(last['frame']):05d}.png"
            w, h = png_size(png)
            # The last frame's camera and gaze, at the size the loop rendered it
            eye = orbit(camera["eye"], camera["look"], speed * int(last["frame"]) / a.fps)
            gaze = f"{float(last['gaze_x']) * w / width:.2f},{float(last['gaze_y']) * h / height:.2f}"
            view = ["--scene", a.scene, "--eye", ",".join(f"{v:.6f}" for v in eye), "--look", ",".join(map(str, camera["look"])),
                    "--fov", camera.get("fov", 45), "--size", f"{w}x{h}", "-q"]
            refs = [out / f"{name}-ref{k}.png" for k in (1, 2)]
            for k, ref in enumerate(refs):
                run([a.foveal, "render", *view, "--mode", "full", "--seed", 1001 + 1000 * k, "-o", ref])
            paper = out / f"{name}-paper.png"
            run([a.foveal, "render", *view, "--gaze", gaze, "-o", paper])
            scores = {}
            for label, image in (("loop", png), ("paper", paper)):
                j = out / f"{name}-{label}.json"
                run([a.foveal, "compare", image, refs[0], "--reference2", refs[1], "--gaze", gaze, "--json", j, "-q"])
                d = json.loads(j.read_text())
                fovea = next(b for b in d["bands"] if b["name"].startswith("q"))
                scores[label] = (d["acuity_weighted_ratio"], fovea["noise_ratio"])
            rows.append({
                "orbit": speed, "history": "kept" if keep else "afresh", "frames": len(frames),
                "late": sum(m > 1000 / a.fps for m in ms), "converged": sum(c >= 1 for c in converged),
                "mean_converged": statistics.mean(converged), "ms_p50": statistics.median(ms), "ms_p99": ms[int(0.99 * len(ms)) - 1],
                "size": f"{w}x{h}", "kept_p50": statistics.median(int(f["kept_pixels"] or 0) for f in frames),
                "error": scores["loop"][0], "fovea_error": scores["loop"][1], "paper_error": scores["paper"][0],
            })
            print(f"{name}: done", file=sys.stderr)
    lines = ["| orbit °/s | rays of a moved view | frames (s) | late | fovea converged (frames) | mean converged fraction | "
             "frame ms p50 / p99 | size at the end | last frame: acuity-weighted error × noise | its fovea | the paper's frame |",
             "|---:|---|---:|---:|---:|---:|---:|---|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['orbit']:g} | {r['history']} | {r['frames']} ({r['frames'] / a.fps:.1f}) | {r['late']} | {r['converged']} | {r['mean_converged']:.3f} | "
                     f"{r['ms_p50']:.1f} / {r['ms_p99']:.1f} | {r['size']} | {r['error']:.2f} | {r['fovea_error']:.2f} | "
                     f"{r['paper_error']:.2f} |")
    table = "\n".join(lines)
    print(table)
    if a.markdown:
        Path(a.markdown).write_text(table + "\n")
    (out / "loop_orbit.json").write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
