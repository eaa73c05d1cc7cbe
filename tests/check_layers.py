#!/usr/bin/env python3
"""The include rule of docs/architecture.md: every file includes only from its own layer or below.

    util → scene, perception → trace, gaze, impair, io → render, vision, quality → cuda
         → experiments → ui → apps, python

A file of src/foveal/MODULE/ (tests, *_test.cpp, excepted: they check across layers), of apps/ or
of python/src/ may include "foveal/OTHER/…" only where OTHER's layer is at or below its own, and
modules of one layer may not include each other both ways. Exits 1 naming each offending
file:line and the two layers; 0 when the tree keeps the rule.

Usage: check_layers.py [--root REPO]   (default: the repository this script sits in)
       check_layers.py --self-test     (plants an upward include in a copy and expects a failure)
"""
import argparse
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

LAYERS = [
    ["util"],
    ["scene", "perception"],
    ["trace", "gaze", "impair", "io"],
    ["render", "vision", "quality"],
    ["cuda"],
    ["experiments"],
    ["ui"],
    ["apps", "python"],
]
RANK = {module: rank for rank, modules in enumerate(LAYERS) for module in modules}
INCLUDE = re.compile(r'^\s*#\s*include\s*"foveal/([a-z_]+)/')
SOURCES = (".h", ".hpp", ".cpp", ".cu", ".cuh")


def files(root: Path):
    """(module, path) of every non-test source the rule covers."""
    for path in sorted((root / "src" / "foveal").rglob("*")):
        if path.suffix in SOURCES and not path.stem.endswith("_test"):
            yield path.relative_to(root / "src" / "foveal").parts[0], path
    for folder, module in (("apps", "apps"), ("python/src", "python")):
        for path in sorted((root / folder).rglob("*")):
            if path.suffix in SOURCES:
                yield module, path


def check(root: Path) -> list:
    problems, edges = [], {}
    for module, path in files(root):
        if module not in RANK:
            problems.append(f"{path.relative_to(root)}: module '{module}' has no layer (add it to {Path(__file__).name})")
            continue
        for number, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), 1):
            match = INCLUDE.match(line)
            if not match or match.group(1) == module:
                continue
            target = match.group(1)
            where = f"{path.relative_to(root)}:{number}"
            if target not in RANK:
                problems.append(f"{where}: includes from 'foveal/{target}/', which has no layer")
            elif RANK[target] > RANK[module]:
                problems.append(f"{where}: '{module}' (layer {RANK[module]}) includes from '{target}' (layer {RANK[target]}), "
                                f"a layer above it: {line.strip()}")
            else:
                edges.setdefault((module, target), where)
    for (a, b), where in sorted(edges.items()):
        if a < b and (b, a) in edges:
            problems.append(f"{where} and {edges[(b, a)]}: '{a}' and '{b}' include each other")
    return problems


def self_test() -> int:
    """The check passes on this tree and fails on a copy with one planted upward include."""
    root = Path(__file__).resolve().parent.parent
    if check(root):
        print("self-test: the tree itself does not keep the rule; run check_layers.py for the list")
        return 1
    with tempfile.TemporaryDirectory() as tmp:
        copy = Path(tmp)
        for folder in ("src", "apps", "python/src"):
            shutil.copytree(root / folder, copy / folder)
        planted = copy / "src/foveal/render/render.h"
        planted.write_text(planted.read_text() + '\n#include "foveal/ui/session.h"\n')
        result = subprocess.run([sys.executable, __file__, "--root", str(copy)], capture_output=True, text=True)
        if result.returncode != 1 or "src/foveal/render/render.h" not in result.stdout or "'ui'" not in result.stdout:
            print(f"self-test: a planted upward include was not reported (exit {result.returncode}):\n{result.stdout}")
            return 1
        # Two modules of one layer including each other are reported too
        (copy / "src/foveal/render/render.h").write_text((root / "src/foveal/render/render.h").read_text()
                                                          + '\n#include "foveal/vision/blur.h"\n')
        result = subprocess.run([sys.executable, __file__, "--root", str(copy)], capture_output=True, text=True)
        if result.returncode != 1 or "include each other" not in result.stdout:
            print(f"self-test: a cycle within a layer was not reported (exit {result.returncode}):\n{result.stdout}")
            return 1
    print("self-test: the tree keeps the rule; a planted upward include and a cycle are reported")
    return 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--root", type=Path, default=Path(__file__).resolve().parent.parent)
    parser.add_argument("--self-test", action="store_true")
    args = parser.parse_args()
    if args.self_test:
        return self_test()
    problems = check(args.root)
    for p in problems:
        print(p)
    if problems:
        print(f"{len(problems)} include(s) break the layer rule (see docs/architecture.md)")
        return 1
    print(f"layers: every include points to its own layer or below ({sum(1 for _ in files(args.root))} files)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
