"""Shared fixtures: the command line to compare against, the shared data, a PFM reader."""
import os
import pathlib
import shutil
import subprocess

import numpy as np
import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
SHARED = pathlib.Path(os.environ.get("FOVEAL_SHARED", REPO.parent / "shared")) / "data"


@pytest.fixture(scope="session")
def cli():
    """The `foveal` executable of the CMake build (FOVEAL_CLI overrides); skip without one."""
    path = pathlib.Path(os.environ.get("FOVEAL_CLI", REPO / "build" / "foveal"))
    if not path.exists():
        pytest.skip(f"no foveal command line at {path} (build it, or set FOVEAL_CLI)")
    return str(path)


def run_cli(cli, *args, check=True):
    result = subprocess.run([cli, *map(str, args)], capture_output=True, text=True, timeout=600)
    if check and result.returncode != 0:
        raise AssertionError(f"foveal {' '.join(map(str, args))} failed: {result.stderr}")
    return result


def cli_error(cli, *args):
    """The one-line message the command line prints for an error (without 'foveal: error: ')."""
    result = run_cli(cli, *args, check=False)
    assert result.returncode != 0, "the command line accepted it"
    line = result.stderr.strip().splitlines()[-1]
    assert line.startswith("foveal: error: "), line
    return line[len("foveal: error: "):]


def shared(*parts):
    path = SHARED.joinpath(*parts)
    if not path.exists():
        pytest.skip(f"{path} is absent (../shared/data)")
    return path


def read_pfm(path):
    """A PFM file as float32 H×W×C, rows top to bottom (written independently of foveal's reader)."""
    with open(path, "rb") as f:
        kind = f.readline().strip()
        width, height = map(int, f.readline().split())
        scale = float(f.readline())
        channels = 3 if kind == b"PF" else 1
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    return np.flipud(data.reshape(height, width, channels)).astype(np.float32)
