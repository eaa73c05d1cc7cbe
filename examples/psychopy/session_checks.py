"""What both PsychoPy examples check before any rendering or window: foveal's own inputs (the
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


def check_display(parser):
    """A window needs a display: without one PsychoPy's window fails deep inside pyglet."""
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        parser.error("no display to open the window on (DISPLAY is not set): run it on a desktop, or under "
                     "xvfb-run -a -s \"-screen 0 840x525x24\" (docs/realtime.md)")
