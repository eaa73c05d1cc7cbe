#!/usr/bin/env python3
"""Peak resident memory per triangle of `foveal render` on height-field grids of N triangles.

Writes a binary little-endian PLY grid (a smooth height field, float32 positions, int32 faces) of
each size to a temporary folder, renders it at 420x262 on the CPU, and reads the peak resident set
from the render's --stats. The baseline is the same render of builtin:plane in the same run;
bytes per triangle = (peak − baseline) / triangles.

    python3 bench/memory_per_triangle.py                       # 0.1 and 1 million triangles
    python3 bench/memory_per_triangle.py --full                # also 10 million (needs ~2 GB and a minute)
    python3 bench/memory_per_triangle.py --triangles 2e6 --markdown mem.md
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

import numpy as np


def write_grid(path, triangles):
    n = max(2, int(math.sqrt(triangles / 2)) + 1)  # n×n vertices, 2(n−1)² triangles
    u = np.linspace(-1, 1, n, dtype=np.float32)
    x, z = np.meshgrid(u, u)
    y = 0.1 * np.sin(6 * x) * np.cos(5 * z)
    verts = np.stack([x, y, z], axis=-1).reshape(-1, 3).astype("<f4")
    i = np.arange(n - 1)
    a = (i[:, None] * n + i[None, :]).reshape(-1)
    quads = np.stack([a, a + n, a + 1, a + 1, a + n, a + n + 1], axis=-1).reshape(-1, 3)
    faces = np.empty(len(quads), dtype=[("n", "u1"), ("v", "<i4", (3,))])
    faces["n"] = 3
    faces["v"] = quads
    with open(path, "wb") as f:
        f.write((f"ply\nformat binary_little_endian 1.0\nelement vertex {len(verts)}\n"
                 "property float x\nproperty float y\nproperty float z\n"
                 f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n").encode())
        f.write(verts.tobytes())
        f.write(faces.tobytes())
    return len(faces)


def peak_mib(cli, scene, folder):
    stats = os.path.join(folder, "stats.json")
    subprocess.run([cli, "render", "--scene", scene, "--size", "420x262", "--max-rays", "16", "--device", "cpu",
                    "-o", os.path.join(folder, "r.png"), "--stats", stats, "-q"],
                   check=True)
    with open(stats) as f:
        return json.load(f)["peak_rss_mib"]


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--cli", default=os.path.join(os.path.dirname(__file__), "..", "build", "foveal"))
    p.add_argument("--triangles", type=float, action="append", help="triangle counts (default 1e5 and 1e6; --full adds 1e7)")
    p.add_argument("--full", action="store_true")
    p.add_argument("--markdown", default=None)
    args = p.parse_args(argv)
    sizes = args.triangles or ([1e5, 1e6, 1e7] if args.full else [1e5, 1e6])
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        base = peak_mib(args.cli, "builtin:plane", folder)
        for n in sizes:
            path = os.path.join(folder, "grid.ply")
            tris = write_grid(path, int(n))
            peak = peak_mib(args.cli, path, folder)
            per = (peak - base) * 2**20 / tris
            rows.append((tris, peak, base, per))
            print(f"memory_per_triangle: {tris:>10,} triangles: peak {peak:8.1f} MiB (baseline {base:.1f}) = {per:6.1f} bytes per triangle")
            os.remove(path)
    if args.markdown:
        with open(args.markdown, "w") as f:
            f.write("| triangles | peak RSS MiB | baseline MiB | bytes per triangle |\n|---:|---:|---:|---:|\n")
            for tris, peak, base, per in rows:
                f.write(f"| {tris:,} | {peak:.1f} | {base:.1f} | {per:.1f} |\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
