"""The benchmark scripts' outputs: checked before the work and written as foveal's commands do."""
import os

import foveal


def check_outputs(parser, outputs, inputs):
    """Before any work, foveal's own check of each output (its folder exists, it may be written,
    never a read-only file), no output one of the inputs, and no two outputs one file."""
    named = [(flag, path) for flag, path in outputs if path]
    for k, (flag, path) in enumerate(named):
        for other_flag, other in named[k + 1:]:
            if os.path.abspath(path) == os.path.abspath(other) or (
                    os.path.exists(path) and os.path.exists(other) and os.path.samefile(path, other)):
                parser.error(f"{flag} {path} and {other_flag} {other}: two outputs into one file; give each its own name")
    for flag, path in named:
        if any(os.path.exists(path) and os.path.exists(i) and os.path.samefile(path, i) for i in inputs):
            parser.error(f"{flag}: {path}: is an input of this run; it is never written over")
        try:
            foveal._core._check_output_file(os.fspath(path))
        except ValueError as error:
            parser.error(f"{flag}: {error}")


def write_output(path, text):
    """Written as every foveal writer writes: whole or not at all, never over a read-only file."""
    foveal._core._write_text(os.fspath(path), text)


def refuse_by_option(parser, error, options):
    """A library error that names its keyword ("size: …") as one line naming the option that set it
    (`options`: keyword → option), or as given where it names none of them."""
    message = str(error)
    for keyword, option in options.items():
        if message.startswith(keyword + ":"):
            parser.error(option + message[len(keyword):])
    parser.error(message)
