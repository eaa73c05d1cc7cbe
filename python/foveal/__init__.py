"""foveal: gaze-contingent ray tracing from Python.

The same C++ library as the ``foveal`` command line, with NumPy arrays in and out:

>>> import foveal
>>> scene = foveal.Scene("builtin:box")
>>> renderer = foveal.Renderer(scene)
>>> frame = renderer.render(size=(840, 525), gaze=(300, 200))
>>> frame.image.shape            # float32, linear RGB, a view of the frame's buffer
(525, 840, 3)

Errors are the command line's one-line messages, raised as ``ValueError`` (bad input),
``FileNotFoundError`` (a missing file) or ``RuntimeError`` (a device that cannot be used).
"""

from __future__ import annotations

import math
import os
from typing import Any, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _core
from ._core import (  # noqa: F401  (re-exported)
    Camera,
    Display,
    Frame,
    Loop,
    LoopFrame,
    MachineSnapshot,
    Renderer,
    Scene,
    VisionSimulation,
    VisionStep,
    choose_device,
    device_available,
    device_description,
    busiest_others,
    load_image,
    machine_snapshot,
    stalls,
)
from . import gaze  # noqa: F401
from . import gaze as _gaze

__all__ = [
    "Camera", "Display", "Frame", "Loop", "LoopFrame", "MachineSnapshot", "Renderer", "Scene", "VisionSimulation", "VisionStep",
    "bench_latency", "busiest_others", "compare", "gaze", "linear_to_srgb", "load_image", "machine_snapshot", "perceive", "save_image",
    "srgb_to_linear", "stalls",
    "choose_device", "device_available", "device_description",
]
__version__ = "0.1.0"

ImageLike = Union[str, "os.PathLike[str]", np.ndarray]


def _array(value: Any, name: str) -> np.ndarray:
    if isinstance(value, np.ndarray):
        return value
    try:
        array = np.asarray(value)
    except (TypeError, ValueError) as error:
        raise TypeError(f"{name}: expected a NumPy array, got {type(value).__name__}") from error
    if array.dtype == object:
        raise TypeError(f"{name}: expected a NumPy array of numbers, got {type(value).__name__}")
    return array


def _check_finite(array: np.ndarray, name: str) -> None:
    if array.dtype.kind == "f":
        bad = array.size - int(np.count_nonzero(np.isfinite(array)))
        if bad:
            raise ValueError(f"{name}: {bad} NaN or infinite values; images need finite pixels")


def _float_image(value: Any, name: str, grey_2d: bool = True, finite: bool = True) -> np.ndarray:
    """An H×W×C float32 image as the core reads it (linear values), checked: a uint8 or uint16
    array (display-encoded sRGB, not linear) is refused rather than read as linear floats; NaN or
    infinite values too, unless `finite` is False (where the core checks them itself)."""
    array = _array(value, name)
    if array.dtype.kind in "ui":
        raise TypeError(f"{name}: {array.dtype} pixels; this takes linear float images (as rendered or load_image "
                        f"gives them). For 8-bit sRGB pixels use foveal.srgb_to_linear({name}) first")
    if array.dtype.kind != "f":
        raise TypeError(f"{name}: expected float pixels, got dtype {array.dtype}")
    if array.ndim == 2 and grey_2d:
        array = array[:, :, None]
    if array.ndim != 3 or array.shape[2] not in (1, 3, 4) or array.shape[0] == 0 or array.shape[1] == 0:
        raise ValueError(f"{name}: expected an H×W×C image (C = 1, 3 or 4), got an array of shape {array.shape}")
    if finite:
        _check_finite(array, name)
    return np.ascontiguousarray(array, dtype=np.float32)


def _image(value: ImageLike, name: str) -> np.ndarray:
    if isinstance(value, (str, os.PathLike)):
        return _core.load_image(os.fspath(value))
    return _float_image(value, name)


def srgb_to_linear(image: Any) -> np.ndarray:
    """Display-encoded pixels (uint8 0–255, uint16 0–65535, or floats 0–1 in sRGB) as linear
    float32 values, exactly as the command line decodes a PNG (IEC 61966-2-1's curve); the array
    keeps its shape (an alpha channel, the 4th, is scaled but not decoded)."""
    array = _array(image, "image")
    if array.dtype.kind not in "uif" or array.ndim not in (2, 3):
        raise TypeError(f"image: expected an H×W or H×W×C array of uint8, uint16 or float pixels, got "
                        f"{array.dtype} of shape {array.shape}")
    shape = array.shape
    three = array[:, :, None] if array.ndim == 2 else array
    if array.dtype.kind == "f":
        _check_finite(three, "image")
        three = np.ascontiguousarray(three, dtype=np.float32)
    else:
        three = np.ascontiguousarray(three, dtype=np.uint16 if array.dtype.itemsize > 1 else np.uint8)
    return np.asarray(_core._srgb_to_linear(three)).reshape(shape)


def linear_to_srgb(image: Any, out: Optional[np.ndarray] = None, *, low: float = 0.0, high: float = 1.0,
                   bottom_up: bool = False) -> np.ndarray:
    """A linear float image as display-encoded sRGB floats, for a window to show every frame: each
    value clipped to [0, 1], encoded by IEC 61966-2-1's curve (within 1e-6 of it; the command line
    rounds the same values to bytes for a PNG) and mapped to [``low``, ``high``]; a 4th channel
    (alpha) is clipped and mapped, not encoded. ``bottom_up`` reverses the rows, as OpenGL's textures
    take them. PsychoPy's ``ImageStim`` takes ``low=-1, high=1, bottom_up=True``.

    ``image``: a float32 (or float64) H×W or H×W×C array (C = 1, 3 or 4) of finite values, as
    ``Loop.frame()`` or ``Renderer.render`` gives it; a value that is not finite raises ValueError
    naming its pixel. ``out``: a C-contiguous float32 array of the result's shape to write into
    (no allocation per frame; ``image`` itself unless ``bottom_up``), else a new one. Returned.
    Runs on foveal's threads with the GIL released: 1.7 ms for an 840×525 frame on two cores, where
    NumPy's lookup in a table of 4096 levels took 2.9–3.1 ms (``bench/python_overhead.py``).
    """
    array = _float_image(image, "image", finite=False)  # (the core names a value that is not finite: no pass of NumPy's)
    for name, value in (("low", low), ("high", high)):
        if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)) or not math.isfinite(value):
            raise ValueError(f"{name}: expected a finite number, got {value!r}")
    shape = np.shape(image) if np.ndim(image) == 2 else array.shape
    if out is None:
        result = np.empty(array.shape, np.float32)
    else:
        if not isinstance(out, np.ndarray):
            got = type(out).__name__
        else:
            got = f"{out.dtype} of shape {out.shape}" + ("" if out.flags.c_contiguous else ", not C-contiguous") \
                + ("" if out.flags.writeable else ", read-only")
        if got != f"float32 of shape {shape}":
            raise ValueError(f"out: expected a writable C-contiguous float32 array of shape {shape}, got {got}")
        if bottom_up and np.shares_memory(out, array):
            raise ValueError("out: shares memory with image: reversing the rows into it would overwrite rows not yet read; "
                             "give another array (or bottom_up=False)")
        result = out.reshape(array.shape)
    _core._linear_to_srgb(array, result, float(low), float(high), bool(bottom_up))
    return result.reshape(shape) if out is None else out


def save_image(image: Any, path: Union[str, "os.PathLike[str]"]) -> None:
    """Write a linear float image as the command line does: .png/.jpg/.bmp sRGB-encoded 8-bit
    (dithered as render's), .pfm/.exr exact floats.

    ``image``: a float32 (or float64) H×W×C array, C = 1, 3 or 4, C-contiguous (as rendered,
    loaded or perceived). A uint8 array (already display-encoded) raises TypeError, a 2-D or
    non-contiguous array ValueError, NaN or infinite pixels ValueError for an 8-bit file (EXR and
    PFM keep them: the AOVs' NaN where nothing was hit). ``path``: the file; its extension picks
    the format.
    """
    array = _array(image, "image")
    if array.ndim == 2:
        raise ValueError(f"image: a 2-D array of shape {array.shape}; give H×W×C (grey: image[:, :, None])")
    if array.ndim == 3 and not array.flags.c_contiguous:
        raise ValueError("image: not C-contiguous (a strided view); pass np.ascontiguousarray(image)")
    path = os.fspath(path)
    float_file = os.path.splitext(path)[1].lower() in (".pfm", ".exr")
    if float_file and array.dtype.kind == "f" and array.ndim == 3:
        if array.shape[2] not in (1, 3, 4) or 0 in array.shape:
            raise ValueError(f"image: expected an H×W×C image (C = 1, 3 or 4), got an array of shape {array.shape}")
        checked = np.ascontiguousarray(array, dtype=np.float32)
    else:
        checked = _float_image(array, "image", grey_2d=False)
    _core.save_image(checked, path)


_VIDEO = (".mp4", ".mkv", ".mov", ".webm", ".avi", ".m4v")


def _stimulus_frames(value: Any, encoding: str) -> Tuple[List[np.ndarray], bool]:
    """Frames given as arrays: (contiguous uint8/uint16/float32 H×W×C arrays, whether they are sRGB)."""
    arrays = list(value) if isinstance(value, (list, tuple)) else None
    if arrays is None:
        array = _array(value, "stimulus")
        arrays = list(array) if array.ndim == 4 else [array]
    if not arrays:
        raise ValueError("stimulus: no frames")
    kinds = set()
    frames = []
    for k, frame in enumerate(arrays):
        name = "stimulus" if len(arrays) == 1 else f"stimulus[{k}]"
        a = _array(frame, name)
        if a.ndim == 2:
            a = a[:, :, None]
        if a.ndim != 3 or a.shape[2] not in (1, 3, 4) or 0 in a.shape:
            raise ValueError(f"{name}: expected an H×W, H×W×3 or H×W×4 image, got an array of shape {a.shape}")
        if a.dtype in (np.uint8, np.uint16):
            kinds.add("integer")
        elif a.dtype.kind == "f":
            _check_finite(a, name)
            a = a.astype(np.float32, copy=False)
            kinds.add("float")
        else:
            raise TypeError(f"{name}: expected uint8, uint16 or float pixels, got dtype {a.dtype}")
        frames.append(np.ascontiguousarray(a))
    if len(kinds) > 1:
        raise TypeError("stimulus: frames mix integer and float pixels; give them all one way")
    if encoding == "auto":
        encoding = "srgb" if kinds == {"integer"} else "linear"
    if encoding == "linear" and kinds == {"integer"}:
        raise ValueError("encoding: 'linear' integer pixels are not a thing foveal reads; uint8/uint16 pixels are sRGB "
                         "(encoding='srgb' or 'auto')")
    return frames, encoding == "srgb"


def perceive(stimulus: Any, eye: str = "healthy", gaze: Any = None, display: Any = None, depth: Any = None,
             output: Optional[Union[str, "os.PathLike[str]"]] = None, encoding: str = "auto",
             pupil_mm: Optional[float] = None, optics: bool = True, blur_taps: int = 64, fps: float = 30.0,
             start_s: float = 0.0, fixation: str = "auto", stimulus_rect: Optional[Sequence[int]] = None,
             threads: int = 0, **fixation_params: float) -> Any:
    """A person's eye applied to a stimulus, as ``foveal perceive`` (the same library code, bit for bit).

    ``stimulus``: an image array (H×W grey, H×W×3 RGB or H×W×4 RGBA; uint8/uint16 sRGB or float
    linear, see ``encoding``), a sequence of them (a list, or an N×H×W×C array), or a path: an
    image, a folder of images, a video (ffmpeg), ``builtin:amsler`` or ``builtin:lamps``.
    ``eye``: presets joined with '+' (myopia:-2, cataract:0.5, cvd:deutan:0.6, field:24-2:FILE.csv,
    amd:5, …) or a profile .json, as the command line's --eye. ``gaze``: None (the centre), (x,
    y) in image pixels, one (x, y) per frame (an N×2 array, for frames given as arrays), or a
    recording (a ``foveal.gaze.Recording`` or a recording's path): each frame fixates where the
    recording's fixation was at the frame's time (``fps``, ``start_s``, ``fixation`` — auto, nhp,
    ivt, idt or tracker — and ``fixation_params``, the filters' parameters as
    ``foveal.gaze.fixations`` takes them; ``stimulus_rect`` (x, y, w, h) where the stimulus was on
    the recording's screen). ``display``: (width_cm, height_cm, distance_cm), the stimulus filling
    the width with square pixels (default (47.5, 30, 60)), or a ``foveal.Display`` with its
    resolution. ``depth``: metres from the eye per pixel (an H×W float array, or an EXR/PFM path),
    default a plane at the viewing distance. ``output``: with a path stimulus, write there as the
    command line does (an image, a folder, a video) and return None. ``encoding``: auto (integer
    pixels are sRGB, floats linear), srgb (floats in 0–1 that are display-encoded) or linear.
    ``pupil_mm`` overrides the eye's pupil; ``optics`` False skips the defocus blur; ``blur_taps``
    the most blur taps per pixel; ``threads`` 0 = all cores. Returns linear float32 H×W×C arrays
    (grey input gives RGB; RGBA keeps its alpha): one for one image, a list for a sequence, folder
    or video. The GIL is released while it works. A gaze off the frame by more than its size
    warns; farther than 10 image sizes raises ValueError.
    """
    if encoding not in ("auto", "srgb", "linear"):
        raise ValueError(f"encoding: expected auto, srgb or linear, got {encoding!r}")
    if not isinstance(eye, str):
        raise TypeError(f"eye: expected presets joined with '+' or a profile path, got {type(eye).__name__}")
    if isinstance(blur_taps, bool) or not isinstance(blur_taps, (int, np.integer)):
        raise TypeError(f"blur_taps: expected an integer, got {type(blur_taps).__name__}")
    # The display: 3 numbers (the stimulus fills the width) or a Display (with its resolution)
    if display is None:
        display_values = (47.5, 30.0, 60.0, 0, 0)
    elif isinstance(display, Display):
        display_values = (display.width_cm, display.height_cm, display.distance_cm, display.res_x, display.res_y)
    else:
        values = tuple(display)
        if len(values) != 3:
            raise ValueError(f"display: expected (width_cm, height_cm, distance_cm) or a foveal.Display, got {display!r}")
        display_values = (*map(float, values), 0, 0)
    # The frames: a path, or arrays
    path = ""
    frames: List[np.ndarray] = []
    srgb = False
    if isinstance(stimulus, (str, os.PathLike)):
        path = os.fspath(stimulus)
        single = not os.path.isdir(path) and not path.lower().endswith(_VIDEO)  # one image (or card)
        if encoding != "auto":
            raise ValueError("encoding: files say their own encoding (PNG/JPEG sRGB, EXR/PFM linear); leave it 'auto'")
    else:
        if output is not None:
            raise ValueError("output: writes a path stimulus as the command line does; save arrays with foveal.save_image")
        single = not isinstance(stimulus, (list, tuple)) and _array(stimulus, "stimulus").ndim != 4
        frames, srgb = _stimulus_frames(stimulus, encoding)
    depth_array = None
    if depth is not None:
        if isinstance(depth, (str, os.PathLike)):
            depth = _core.load_image(os.fspath(depth))
        depth_array = _array(depth, "depth")
        if depth_array.ndim == 2:
            depth_array = depth_array[:, :, None]
        if depth_array.ndim != 3 or depth_array.shape[2] != 1 or depth_array.dtype.kind != "f":
            raise ValueError(f"depth: expected an H×W float array of metres, got {depth_array.dtype} of shape {depth_array.shape}")
        depth_array = np.ascontiguousarray(depth_array, dtype=np.float32)
    # The gaze: a point, a point per frame, or a recording
    point = points = recording = None
    if isinstance(gaze, (str, os.PathLike)):
        gaze = _gaze.read(gaze, display_resolution=(int(display_values[3]) or 1680, int(display_values[4]) or 1050))
    if isinstance(gaze, _gaze.Recording):
        recording = _gaze._columns(gaze, None, "gaze")
    elif gaze is not None:
        g = _array(gaze, "gaze").astype(np.float64, copy=False)
        if g.shape == (2,):
            point = (float(g[0]), float(g[1]))
        elif g.ndim == 2 and g.shape[1] == 2:
            points = np.ascontiguousarray(g)
        else:
            raise ValueError(f"gaze: expected (x, y), one (x, y) per frame (N×2) or a recording, got shape {g.shape}")
        if not np.all(np.isfinite(g)):
            raise ValueError("gaze: must be finite image pixels")
    if stimulus_rect is not None:
        rect = tuple(int(v) for v in stimulus_rect)
        if len(rect) != 4:
            raise ValueError(f"stimulus_rect: expected (x, y, w, h), got {stimulus_rect!r}")
        rect_text = ",".join(map(str, rect))
    else:
        rect_text = ""
    params = _gaze._parameters(fixation_params, _gaze._PARAMETERS + _gaze._PURSUIT_PARAMETERS)
    result = _core._perceive(frames, srgb, path, "" if output is None else os.fspath(output), eye, pupil_mm,
                             display_values, depth_array, bool(optics), int(blur_taps), float(fps), point, points,
                             recording, fixation, params, float(start_s), rect_text, int(threads))
    if result is None:
        return None
    return result[0] if single else list(result)


def _flag(value: Any, name: str) -> bool:
    """A yes/no argument: True or False, not a number or a string that would read as one."""
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name}: expected True or False, got {type(value).__name__}")
    return bool(value)


def _numbers(value: Any) -> Any:
    """The JSON document's "inf" strings as floats."""
    if isinstance(value, dict):
        return {k: _numbers(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_numbers(v) for v in value]
    if value in ("inf", "-inf"):
        return float(value)
    return value


def compare(a: ImageLike, b: ImageLike, gaze: Optional[Tuple[float, float]] = None,
            display: Optional[Display] = None, reference2: Optional[ImageLike] = None,
            ellipse: float = 1.538, ssim_border: str = "reflect") -> dict:
    """Image quality of ``a`` against the reference ``b``, whole and per eccentricity band.

    ``a`` and ``b`` are H×W×C float arrays (linear, as rendered) or image paths. ``gaze`` is in
    image pixels (default: the centre); ``display`` the screen the image filled (default, as
    the command line's: the papers' 47.5×30 cm, 1680×1050 at 60 cm). With ``reference2`` (the reference
    rendered with another seed) every band's error is also given as a multiple of the reference's
    own noise. ``ssim_border``: ``reflect`` (the image mirrored at the edges, every pixel counts)
    or ``valid`` (only windows wholly inside the image, as Wang et al.'s code and scikit-image).
    Returns the dict of ``foveal compare --json``: ``whole``, ``bands`` (RMSE, PSNR,
    SSIM per band), ``acuity_weighted_rmse`` and, with ``reference2``, the noise ratios.
    """
    ia, ib = _image(a, "a"), _image(b, "b")
    ib2 = None if reference2 is None else _image(reference2, "reference2")
    return _numbers(_core._compare(ia, ib, ib2, gaze, display, ellipse, ssim_border))


def bench_latency(recordings: Any, scene: Scene, camera: Any = None, size: Tuple[int, int] = (840, 525),
                  display: Optional[Display] = None, start_s: float = 0.0, duration_s: float = 3.0, refresh_hz: float = 60.0,
                  frame_budget_ms: Optional[float] = None, latency_ms: Optional[float] = None, margin_ms: Optional[float] = None,
                  clock: str = "wall", model_rays_per_ms: Optional[float] = None, model_fixed_ms: Optional[float] = None,
                  loops: Sequence[str] = ("whole-frame", "deadline", "deadline+prediction"), min_amplitude_deg: float = 2.0,
                  max_rays: int = 400, tolerance: float = 0.35, seed: int = 1, device: str = "cpu", threads: int = 0,
                  progress: bool = False, timeline: Optional[Union[str, "os.PathLike[str]"]] = None,
                  timeline_saccade: int = 0, landing: Optional[Union[dict, str]] = None, periphery_share: Optional[float] = None,
                  rays_ahead: bool = True, min_scale: Optional[float] = None) -> dict:
    """``foveal bench latency`` from Python: gaze-to-photon latency of the display loops on recorded gaze.

    ``recordings``: one or a list of recordings — paths (read as the command line reads them, the
    recording's screen filling ``display``) or ``foveal.gaze.Recording`` objects. ``scene`` a
    ``foveal.Scene``, or its path or ``builtin:NAME`` (the command line's default is the dragon box, ``scenes/dragon-box.json``),
    ``camera`` a camera name or ``Camera`` (its first). The other arguments are the command line's
    options (docs/realtime.md): the segment (``start_s``, ``duration_s``), the display
    (``refresh_hz``, ``frame_budget_ms``), the tracker's ``latency_ms``, the deadline loops'
    ``margin_ms`` and ``periphery_share`` (None: the loop's default, 1), ``rays_ahead`` (``--no-rays-ahead``: False) and
    ``min_scale`` (None: the loop's default, 0.25), the ``clock`` (wall or model, with ``model_rays_per_ms`` and
    ``model_fixed_ms``), the ``loops`` (whole-frame, deadline, deadline+prediction,
    deadline+oracle), the judged saccades' ``min_amplitude_deg``. ``progress`` prints the
    command line's progress lines; ``timeline`` draws a saccade's timeline (.png or .svg);
    ``landing`` the prediction loops' landing predictor parameters, a dict by name or the text of
    ``--landing`` (``foveal.gaze.landing_params()`` lists them). Returns
    the dict of ``--json`` with its tables under ``"markdown"``; the GIL is released while it runs.
    """
    if isinstance(recordings, (str, os.PathLike, _gaze.Recording)):
        recordings = [recordings]
    elif not isinstance(recordings, (list, tuple)):
        raise TypeError(f"recordings: a path, a foveal.gaze.Recording or a list of them, got {type(recordings).__name__}")
    d = display if display is not None else Display()
    columns = []
    for k, r in enumerate(recordings):
        if isinstance(r, (str, os.PathLike)):
            r = _gaze.read(r, display=d)
        elif not isinstance(r, _gaze.Recording):
            raise TypeError(f"recordings[{k}]: a path or a foveal.gaze.Recording, got {type(r).__name__}")
        columns.append((r.source or f"recordings[{k}]", _gaze._columns(r, None, f"recordings[{k}]")))
    if isinstance(loops, str):
        loops = loops.split(",")
    def number(value, name):  # ints are numbers too (the core takes floats)
        if value is None:
            return None
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise TypeError(f"{name}: expected a number, got {type(value).__name__}")
        return float(value)
    return _numbers(_core._bench_latency(
        scene, columns, camera, size, display, number(start_s, "start_s"),
        number(duration_s, "duration_s"), number(refresh_hz, "refresh_hz"), number(frame_budget_ms, "frame_budget_ms"),
        number(latency_ms, "latency_ms"), number(margin_ms, "margin_ms"), clock, number(model_rays_per_ms, "model_rays_per_ms"),
        number(model_fixed_ms, "model_fixed_ms"), list(loops), number(min_amplitude_deg, "min_amplitude_deg"), max_rays,
        number(tolerance, "tolerance"), seed, device, threads, progress, "" if timeline is None else os.fspath(timeline),
        timeline_saccade, landing,  # (a dict or --landing's text; the core names anything else)
        number(periphery_share, "periphery_share"), _flag(rays_ahead, "rays_ahead"), number(min_scale, "min_scale")))
