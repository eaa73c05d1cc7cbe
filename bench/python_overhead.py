#!/usr/bin/env python3
"""The Python package's own cost per Renderer.render call, against the C++ call in the same run.

For each call: the wall time of ``renderer.render(...)`` as Python sees it, and ``frame.library_ms``,
the library's render_frame alone timed inside the binding. Their difference is what the binding
adds (argument conversion, the GIL hand-over, the Frame object); reported as a share of the frame.

Then what a window pays every frame to show one: the frame as sRGB floats in PsychoPy's [−1, 1],
rows bottom-up, by ``foveal.linear_to_srgb`` into one buffer, against NumPy's table lookup of 4096
levels (the PsychoPy example's conversion before it) on the same frame in the same run.

    .venv/bin/python bench/python_overhead.py                    # builtin:box, 840x525, 30 frames
    .venv/bin/python bench/python_overhead.py --scene scenes/conference.json --frames 100 --markdown out.md
"""
import argparse
import statistics
import sys
import time

import foveal


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scene", default="builtin:box")
    p.add_argument("--size", default="840x525")
    p.add_argument("--frames", type=int, default=30)
    p.add_argument("--max-rays", type=int, default=400)
    p.add_argument("--device", default="auto")
    p.add_argument("--markdown", default=None)
    args = p.parse_args(argv)
    w, h = (int(v) for v in args.size.split("x"))
    renderer = foveal.Renderer(foveal.Scene(args.scene), device=args.device)
    renderer.render(size=(w, h), max_rays=args.max_rays)  # warm-up
    wall, library = [], []
    for i in range(args.frames):
        gaze = (w * (0.2 + 0.6 * (i % 7) / 6), h * (0.3 + 0.4 * (i % 5) / 4))
        start = time.perf_counter()
        frame = renderer.render(size=(w, h), gaze=gaze, max_rays=args.max_rays)
        image = frame.image  # the zero-copy view is part of a call's use
        wall.append(1000 * (time.perf_counter() - start))
        library.append(frame.library_ms)
        del image, frame
    overhead = [a - b for a, b in zip(wall, library)]
    med_wall, med_lib, med_over = statistics.median(wall), statistics.median(library), statistics.median(overhead)
    share = med_over / med_lib
    line = (f"| {args.scene} | {w}x{h} | {renderer.device} | {args.frames} | {med_lib:.2f} | {med_wall:.2f} | "
            f"{1000 * med_over:.0f} | {max(overhead) * 1000:.0f} | {100 * share:.3f} % |")
    print(f"python_overhead: {args.scene} {w}x{h} on {renderer.device}, {args.frames} foveated frames: "
          f"library {med_lib:.2f} ms, Python call {med_wall:.2f} ms, binding {1000 * med_over:.0f} µs "
          f"(max {1000 * max(overhead):.0f} µs) = {100 * share:.3f} % of the frame (median)")
    convert_ms, numpy_ms = display_conversion(renderer.render(size=(w, h), max_rays=args.max_rays).image.copy(), args.frames)
    print(f"python_overhead: the frame for a window (sRGB in [-1, 1], rows bottom-up): foveal.linear_to_srgb {convert_ms:.2f} ms, "
          f"NumPy's table lookup {numpy_ms:.2f} ms (median of {args.frames}; {numpy_ms / convert_ms:.1f}x)")
    if args.markdown:
        with open(args.markdown, "w") as f:
            f.write("| scene | size | device | frames | library ms | Python call ms | binding µs (median) | binding µs (max) | binding / frame |\n")
            f.write("|---|---|---|---:|---:|---:|---:|---:|---:|\n" + line + "\n\n")
            f.write("| size | foveal.linear_to_srgb ms | NumPy table lookup ms | ratio |\n|---|---:|---:|---:|\n")
            f.write(f"| {w}x{h} | {convert_ms:.2f} | {numpy_ms:.2f} | {numpy_ms / convert_ms:.1f} |\n")
    return 0 if share < 0.01 else 1


def display_conversion(image, frames):
    """Median ms of foveal.linear_to_srgb into one buffer, and of NumPy's 4096-level table lookup."""
    import numpy as np
    levels = np.linspace(0.0, 1.0, 4096)
    table = (np.where(levels <= 0.0031308, 12.92 * levels, 1.055 * np.power(levels, 1 / 2.4) - 0.055) * 2 - 1).astype(np.float32)
    out = np.empty(image.shape, np.float32)
    ours, theirs = [], []
    for _ in range(frames):
        start = time.perf_counter()
        foveal.linear_to_srgb(image, out, low=-1.0, high=1.0, bottom_up=True)
        ours.append(1000 * (time.perf_counter() - start))
        start = time.perf_counter()
        looked_up = table[np.clip(image * 4095.0 + 0.5, 0, 4095).astype(np.uint16)[::-1]]
        theirs.append(1000 * (time.perf_counter() - start))
    if not np.allclose(out, looked_up, atol=2.5e-3):  # the table's 4096 levels are within 1/800 of the curve above its knee
        raise SystemExit("python_overhead: foveal.linear_to_srgb and the table lookup disagree")
    return statistics.median(ours), statistics.median(theirs)


if __name__ == "__main__":
    sys.exit(main())
