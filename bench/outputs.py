"""The benchmark scripts' outputs: checked before the work, written as foveal writes its own."""
import os

import foveal


def check_outputs(parser, outputs, inputs):
    """Before any work: each output's folder exists and may be written (read-only is refused for
    every user, as foveal's writers refuse it), and no output is one of the inputs."""
    for flag, path in outputs:
        if not path:
            continue
        folder = os.path.dirname(os.path.abspath(path))
        if not os.path.isdir(folder):
            parser.error(f"{flag}: {path}: the folder {folder} does not exist")
        if any(os.path.exists(path) and os.path.exists(i) and os.path.samefile(path, i) for i in inputs):
            parser.error(f"{flag}: {path}: is an input of this run; it is never written over")
        if not os.stat(folder).st_mode & 0o222 or (os.path.exists(path) and not os.stat(path).st_mode & 0o222):
            parser.error(f"{flag}: {path}: is read-only, or its folder is")


def write_output(path, text):
    """Written as every foveal writer writes: whole or not at all, never over a read-only file."""
    foveal._core._write_text(os.fspath(path), text)
