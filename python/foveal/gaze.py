"""Gaze: eye-tracker recordings as NumPy arrays, fixation filters, and live sources.

``read`` reads an EyeLink ASC, a Pupil Player ``gaze_positions.csv``, a Tobii TSV or a plain
``t,x,y`` CSV with the command line's readers; ``fixations`` runs its I-VT or I-DT filter;
``PupilSource`` is the live Pupil Capture connection and ``LslSource`` a Lab Streaming Layer gaze
stream (through pylsl). Samples are a NumPy structured array with the fields
``t_s`` (seconds, the tracker's clock), ``x``, ``y`` (screen pixels, origin top-left, NaN where
the eye was lost), ``confidence`` (0–1) and ``valid`` (bool).
"""

from __future__ import annotations

import time
import warnings as _warnings
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from . import _core

SAMPLE_DTYPE = np.dtype([("t_s", "f8"), ("x", "f8"), ("y", "f8"), ("confidence", "f4"), ("valid", "?")])
EVENT_DTYPE = np.dtype([("start_s", "f8"), ("end_s", "f8"), ("x", "f8"), ("y", "f8")])
FIXATION_DTYPE = np.dtype([("start_s", "f8"), ("end_s", "f8"), ("x", "f8"), ("y", "f8"), ("first", "i8"), ("last", "i8")])

__all__ = ["Recording", "read", "fixations", "PupilSource", "LslSource", "SAMPLE_DTYPE", "EVENT_DTYPE", "FIXATION_DTYPE"]


def _samples(columns: Dict[str, np.ndarray]) -> np.ndarray:
    out = np.empty(len(columns["t_s"]), SAMPLE_DTYPE)
    for name in SAMPLE_DTYPE.names:
        out[name] = columns[name]
    return out


def _events(columns: Dict[str, np.ndarray], dtype: np.dtype = EVENT_DTYPE) -> np.ndarray:
    out = np.empty(len(columns["start_s"]), dtype)
    for name in dtype.names:
        out[name] = columns[name]
    return out


@dataclass
class Recording:
    """A recording as read: samples, the tracker's own events and what the file says of itself."""

    samples: np.ndarray            #: structured array of SAMPLE_DTYPE
    fixations: np.ndarray          #: the tracker's own fixations (EVENT_DTYPE; empty if none)
    blinks: np.ndarray             #: the tracker's own blinks (EVENT_DTYPE)
    source: str = ""
    format: str = ""
    tracker: str = ""
    screen: Tuple[int, int] = (0, 0)   #: the screen the points are in, pixels
    eyes: str = ""
    rate_hz: float = 0.0
    nominal_rate_hz: float = 0.0
    has_tracker_fixations: bool = False
    block_starts: List[int] = field(default_factory=list)  #: first sample of each recording block
    notes: List[str] = field(default_factory=list)
    #: what the reader warns of (an EyeLink block without END: the file may be truncated); also
    #: issued as Python warnings (UserWarning) when the file is read
    warnings: List[str] = field(default_factory=list)
    #: the tracker's 3-D gaze direction per sample (N×3, NaN where none), where it gives one (Pupil's
    #: gaze_point_3d); the filters measure angles with it, as the command line does
    directions: Optional[np.ndarray] = None

    def __len__(self) -> int:
        return len(self.samples)


_TIME_SCALES = {"s": 1.0, "ms": 1e-3, "us": 1e-6}


def read(path: str, format: str = "auto", screen: Optional[Tuple[int, int]] = None, eye: str = "average",
         min_confidence: float = 0.6, time_unit: str = "s", coords: str = "px", origin: str = "top-left",
         fixations_file: str = "", blinks_file: str = "", display_resolution: Tuple[int, int] = (1680, 1050)) -> Recording:
    """Read a recording (the options of ``foveal gaze``).

    format: auto, asc (EyeLink), pupil, tobii or csv. screen: (W, H) pixels for normalised
    coordinates or to override the file's (default: what the file states, else
    ``display_resolution``). eye: average, left or right. For csv: time_unit s/ms/us, coords
    px/norm, origin top-left/bottom-left. Raises ValueError naming file:line on malformed input.
    """
    if time_unit not in _TIME_SCALES:
        raise ValueError(f"time_unit: unknown unit '{time_unit}' (expected s, ms or us)")
    if coords not in ("px", "norm"):
        raise ValueError(f"coords: expected px or norm, got '{coords}'")
    if origin not in ("top-left", "bottom-left"):
        raise ValueError(f"origin: expected top-left or bottom-left, got '{origin}'")
    d = _core._read_recording(str(path), format, screen, eye, float(min_confidence), _TIME_SCALES[time_unit],
                              coords == "norm", origin == "bottom-left", fixations_file, blinks_file, display_resolution)
    for message in d["warnings"]:
        _warnings.warn(message, stacklevel=2)
    return Recording(samples=_samples(d["samples"]), fixations=_events(d["fixations"]), blinks=_events(d["blinks"]),
                     source=d["source"], format=d["format"], tracker=d["tracker"], screen=tuple(d["screen"]),
                     eyes=d["eyes"], rate_hz=d["rate_hz"], nominal_rate_hz=d["nominal_rate_hz"],
                     has_tracker_fixations=d["has_tracker_fixations"], block_starts=list(d["block_starts"]),
                     notes=list(d["notes"]), warnings=list(d["warnings"]),
                     directions=None if d["directions"] is None else np.asarray(d["directions"]).reshape(-1, 3))


_PARAMETERS = ("velocity_threshold_deg_s", "velocity_window_s", "gap_fill_s", "merge_gap_s", "merge_angle_deg",
               "min_fixation_s", "median_window", "dispersion_deg", "min_duration_s")


def fixations(samples, method: str = "ivt", display: Optional[_core.Display] = None,
              screen: Optional[Tuple[int, int]] = None, labels: bool = False, **params):
    """Fixations of a recording (or a SAMPLE_DTYPE array) by I-VT or I-DT, as ``foveal gaze`` finds them.

    ``samples``: a Recording (its screen and blocks are used) or a structured sample array (then
    give ``screen``). ``display``: the physical screen for the angles (default 47.5×30 cm at 60 cm,
    the command line's). ``params`` (defaults as the command line's): velocity_threshold_deg_s (30),
    velocity_window_s (0.02), gap_fill_s (0.075), merge_gap_s (0.075), merge_angle_deg (0.5),
    min_fixation_s (0.06), median_window (1), dispersion_deg (1.0), min_duration_s (0.08).
    Returns a structured array of FIXATION_DTYPE (``first``/``last`` are sample indices); with
    ``labels=True`` also each sample's fixation index (−1: none).
    """
    blocks, directions = None, None
    if isinstance(samples, Recording):
        screen = screen or samples.screen
        blocks = samples.block_starts
        if samples.directions is not None:
            directions = np.ascontiguousarray(samples.directions, dtype=np.float64).reshape(-1)
        samples = samples.samples
    if screen is None:
        raise ValueError("fixations: give screen=(W, H) in pixels with a bare sample array")
    samples = np.asarray(samples)
    if samples.dtype.names is None or not set(SAMPLE_DTYPE.names) <= set(samples.dtype.names):
        raise ValueError(f"fixations: expected samples with the fields {', '.join(SAMPLE_DTYPE.names)}")
    unknown = set(params) - set(_PARAMETERS)
    if unknown:
        raise ValueError(f"fixations: unknown parameter '{sorted(unknown)[0]}' ({', '.join(_PARAMETERS)})")
    if display is None:
        display = _core.Display(47.5, 30.0, 60.0, int(screen[0]), int(screen[1]))
    col = lambda name: np.ascontiguousarray(samples[name], dtype=np.float64)  # noqa: E731
    d = _core._fixations(col("t_s"), col("x"), col("y"), col("confidence"), col("valid"), (int(screen[0]), int(screen[1])),
                         display, method, {k: float(v) for k, v in params.items()}, blocks, directions)
    result = _events(d, FIXATION_DTYPE)
    return (result, np.asarray(d["label"])) if labels else result


class _LiveSource:
    """A live source closes when its ``with`` block ends."""

    def close(self) -> None:  # pragma: no cover - overridden
        raise NotImplementedError

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class PupilSource(_LiveSource):
    """Live gaze from Pupil Capture's Network API (``pupil://HOST:PORT[?surface=NAME]``).

    Connecting waits a bounded time for Pupil Remote (``timeout=`` in the URL, default 2 s) and
    raises ValueError if it does not answer. ``poll()`` never blocks: it returns the samples that
    arrived since the last call (SAMPLE_DTYPE; norm_pos scaled to ``screen``). ``state`` is
    waiting, live, stale or disconnected.
    """

    def __init__(self, url: str, screen: Tuple[int, int] = (1680, 1050), min_confidence: float = 0.6):
        self._source = _core._PupilSource(url, (int(screen[0]), int(screen[1])), float(min_confidence))
        self.screen = tuple(screen)

    def poll(self) -> np.ndarray:
        return _samples(self._source.poll())

    @property
    def state(self) -> str:
        return self._source.state

    @property
    def silent_s(self) -> float:
        return self._source.silent_s

    @property
    def name(self) -> str:
        return self._source.name

    def close(self) -> None:
        self._source.close()


class LslSource(_LiveSource):
    """Live gaze from a Lab Streaming Layer stream, read through pylsl.

    The stream is found by ``name`` (or ``type``, default "Gaze") within ``timeout`` seconds. Its
    channels are taken from the stream's metadata following the XDF gaze meta-data convention:
    each ``<channel>`` under ``<channels>`` has a ``<type>`` (also read as ``<metatype>``, as Pupil's
    LSL relay writes it) of ScreenX, ScreenY or Confidence and a ``<unit>`` of ``normalized`` or
    ``pixels``; labels x/y/confidence (or norm_pos_x/norm_pos_y) are used when the types are
    missing, and ``channels={"x": i, "y": j, "confidence": k}`` overrides both. Normalised
    coordinates are scaled to ``screen`` with the origin ``origin`` (top-left, or bottom-left as
    Pupil's norm_pos). Sample times are LSL's clock (``pylsl.local_clock()``), in seconds.

    ``poll()`` never blocks and returns the new samples (SAMPLE_DTYPE); a sample whose
    confidence is below ``min_confidence`` or whose point is not finite is invalid. ``state`` is
    waiting, live, stale (no sample for ``stale_s``) or disconnected (the outlet went away).
    """

    def __init__(self, name: Optional[str] = None, type: str = "Gaze", screen: Tuple[int, int] = (1680, 1050),
                 timeout: float = 5.0, origin: str = "top-left", min_confidence: float = 0.6,
                 channels: Optional[Dict[str, int]] = None, stale_s: float = 0.5):
        try:
            import pylsl
        except ImportError as error:  # pragma: no cover - depends on the environment
            raise RuntimeError("LslSource needs pylsl: pip install pylsl (or pip install foveal[lsl])") from error
        if origin not in ("top-left", "bottom-left"):
            raise ValueError(f"origin: expected top-left or bottom-left, got '{origin}'")
        if not (timeout > 0):
            raise ValueError(f"timeout: must be positive seconds, got {timeout}")
        self._lsl = pylsl
        lost = getattr(pylsl, "LostError", None)
        if lost is None:
            from pylsl.util import LostError as lost
        self._lost_error = lost
        prop, value = ("name", name) if name is not None else ("type", type)
        found = pylsl.resolve_byprop(prop, value, 1, timeout)
        if not found:
            raise RuntimeError(f"LslSource: no LSL stream with {prop} '{value}' answered within {timeout:g} s")
        self._inlet = pylsl.StreamInlet(found[0], max_buflen=30, recover=False)
        info = self._inlet.info(timeout)
        self.name = info.name()
        self.screen = (int(screen[0]), int(screen[1]))
        self.min_confidence = float(min_confidence)
        self.stale_s = float(stale_s)
        self.channel_count = info.channel_count()
        self.x, self.y, self.confidence, self.normalised = self._channels(info, channels)
        self.bottom_left = origin == "bottom-left"
        self._inlet.open_stream(timeout)
        self._start = time.monotonic()
        self._last: Optional[float] = None
        self._lost = False

    def _channels(self, info, override):
        labels, types, units = [], [], []
        channel = info.desc().child("channels").child("channel")
        while not channel.empty():
            labels.append(channel.child_value("label").strip().lower())
            kind = channel.child_value("type") or channel.child_value("metatype")
            types.append(kind.strip().lower())
            units.append(channel.child_value("unit").strip().lower())
            channel = channel.next_sibling("channel")

        def find(kind: str, names: Sequence[str]) -> Optional[int]:
            for i, t in enumerate(types):
                if t == kind:
                    return i
            for i, label in enumerate(labels):
                if label in names:
                    return i
            return None

        x = find("screenx", ("x", "norm_pos_x", "gaze_x", "screen_x"))
        y = find("screeny", ("y", "norm_pos_y", "gaze_y", "screen_y"))
        c = find("confidence", ("confidence",))
        if override:
            unknown = set(override) - {"x", "y", "confidence"}
            if unknown:
                raise ValueError(f"channels: unknown key '{sorted(unknown)[0]}' (x, y, confidence)")
            x, y, c = override.get("x", x), override.get("y", y), override.get("confidence", c)
        if x is None or y is None:
            if self.channel_count >= 2 and not labels:
                x, y = 0, 1  # no metadata at all: the first two channels
            else:
                raise ValueError(f"LslSource: stream '{self.name}' has no ScreenX/ScreenY channels in its metadata "
                                 f"(labels {labels}); give channels={{'x': i, 'y': j}}")
        for key, index in (("x", x), ("y", y), ("confidence", c)):
            if index is not None and not 0 <= index < self.channel_count:
                raise ValueError(f"channels: {key} = {index} is not one of the stream's {self.channel_count} channels")
        unit = units[x] if x < len(units) else ""
        normalised = unit in ("normalized", "normalised", "norm") if unit else False
        return x, y, c, normalised

    def poll(self) -> np.ndarray:
        try:
            chunk, stamps = self._inlet.pull_chunk(timeout=0.0)
        except self._lost_error:
            self._lost = True
            chunk, stamps = [], []
        if not stamps:
            return np.empty(0, SAMPLE_DTYPE)
        data = np.asarray(chunk, dtype=np.float64).reshape(len(stamps), -1)
        out = np.empty(len(stamps), SAMPLE_DTYPE)
        out["t_s"] = stamps
        x, y = data[:, self.x], data[:, self.y]
        if self.normalised:
            x = x * self.screen[0]
            y = (1.0 - y) * self.screen[1] if self.bottom_left else y * self.screen[1]
        out["x"], out["y"] = x, y
        out["confidence"] = data[:, self.confidence] if self.confidence is not None else 1.0
        out["valid"] = np.isfinite(x) & np.isfinite(y) & (out["confidence"] >= self.min_confidence)
        out["x"][~np.isfinite(x)] = np.nan
        out["y"][~np.isfinite(y)] = np.nan
        self._last = time.monotonic()
        return out

    @property
    def silent_s(self) -> float:
        return time.monotonic() - (self._last if self._last is not None else self._start)

    @property
    def state(self) -> str:
        if self._lost:
            return "disconnected"
        if self._last is None:
            return "waiting"
        return "stale" if self.silent_s > self.stale_s else "live"

    def close(self) -> None:
        self._inlet.close_stream()
