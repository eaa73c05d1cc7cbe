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

from typing import Any, Optional, Sequence, Tuple, Union

import numpy as np

from . import _core
from ._core import (  # noqa: F401  (re-exported)
    Camera,
    Display,
    Frame,
    Loop,
    LoopFrame,
    Renderer,
    Scene,
    VisionSimulation,
    VisionStep,
    device_available,
    device_description,
    load_image,
    save_image,
)
from . import gaze  # noqa: F401

__all__ = [
    "Camera", "Display", "Frame", "Loop", "LoopFrame", "Renderer", "Scene", "VisionSimulation", "VisionStep",
    "compare", "gaze", "load_image", "save_image", "device_available", "device_description",
]
__version__ = "0.1.0"

ImageLike = Union[str, np.ndarray]


def _image(value: ImageLike, name: str) -> np.ndarray:
    if isinstance(value, str):
        return _core.load_image(value)
    array = np.asarray(value)
    if array.ndim == 2:
        array = array[:, :, None]
    if array.ndim != 3:
        raise ValueError(f"{name}: expected an H×W×C image, got an array of shape {array.shape}")
    return np.ascontiguousarray(array, dtype=np.float32)


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
