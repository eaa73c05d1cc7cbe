"""What the PsychoPy examples check before any rendering or window: foveal's own inputs (the
scene, its camera, the device, as foveal takes them) and a display to open the window on. Each is
refused in one line naming its option (keep this file beside the examples: they import it)."""
import os
import sys


def check_foveal_inputs(parser, scene, camera, device):
    """Loads `scene` (returned: the session takes it), checks `camera` (None: the scene's first) and
    `device` as foveal chooses it."""
    import foveal
    try:
        loaded = foveal.Scene(scene)
    except (OSError, ValueError) as error:
        parser.error(f"--scene: {error}")
    if camera is not None:
        try:
            loaded.camera(camera)
        except ValueError as error:
            parser.error(f"--camera: {error}")
    try:
        foveal.choose_device(device)
    except ValueError as error:  # an unknown name ("device: unknown device …")
        parser.error(f"--device: {str(error).split(': ', 1)[-1]}")
    except RuntimeError as error:  # cuda without a usable GPU
        parser.error(f"--device {device}: {str(error).split(': ', 1)[-1]}; give --device auto or cpu")
    return loaded


def check_output(path, inputs=None, extensions=None):
    """Why `path` cannot take an output ('' where it can): its extension (one of `extensions`, where
    given), a folder of that name, its folder missing or not writable, a read-only file (never
    replaced, by root either), or one of `inputs` (never written over: {what it is called: its path},
the path None where not given)."""
    folder = os.path.dirname(os.path.abspath(path))
    if extensions and os.path.splitext(path)[1].lower() not in extensions:
        return f"{path}: the name must end in {', '.join(extensions)}"
    if os.path.isdir(path):
        return f"{path} is a folder; give a file name"
    if not os.path.isdir(folder):
        return f"{path}: the folder {folder} does not exist"
    if not os.access(folder, os.W_OK):
        return f"{path}: the folder {folder} cannot be written"
    if os.path.exists(path) and not os.stat(path).st_mode & 0o222:  # (root may write anything: the mode says)
        return f"{path}: is read-only; it is not replaced (give another name, or make it writable)"
    for name, given in (inputs or {}).items():
        if given and os.path.exists(given) and os.path.exists(path) and os.path.samefile(given, path):
            return f"{path}: is {name}, an input; it is never written over"
    return ""


def check_display(parser):
    """A window needs a display: without one PsychoPy's window fails deep inside pyglet."""
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        parser.error("no display to open the window on (DISPLAY is not set): run it on a desktop, or under "
                     "xvfb-run -a -s \"-screen 0 840x525x24\" (docs/realtime.md)")


# Lab displays run at 60–240 Hz as a rule; a rate measured above this is most likely the pace of
# flips that do not wait for the vertical blank (Xvfb, or vsync off in the driver)
FASTEST_USUAL_HZ = 240.0


def refresh_rate(given_hz, measured_hz):
    """The refresh rate a session runs at, and a note where it is not the display's for certain:
    `given_hz` (--refresh-hz) where given; else what PsychoPy measured (`measured_hz`, None where it
    found no steady rate: then 60 Hz). Under Xvfb PsychoPy measured flips at 490–533 Hz at 840x525:
    a budget of 4 ms, which lowered the render's size."""
    if given_hz is not None:
        return given_hz, ""
    if measured_hz is None or not measured_hz > 0:
        return 60.0, ("PsychoPy found no steady refresh rate: 60 Hz assumed; give the display's rate with --refresh-hz")
    if measured_hz > FASTEST_USUAL_HZ:
        return measured_hz, (f"PsychoPy measured flips at {measured_hz:.0f} Hz, faster than lab displays run as a rule: where "
                             "the flip does not wait for the vertical blank (Xvfb, or vsync off in the driver) that is the "
                             f"drawing's pace, not the display's, and the loop's budget follows it ({1000 / measured_hz:.1f} ms a "
                             "frame); give the display's rate with --refresh-hz (e.g. 60)")
    return measured_hz, ""
