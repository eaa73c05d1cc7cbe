"""Gaze: eye-tracker recordings as NumPy arrays, fixation filters, and live sources.

``read`` reads an EyeLink ASC, a Pupil Player ``gaze_positions.csv``, a Tobii TSV or a plain
``t,x,y`` CSV with the command line's readers; ``fixations`` runs its I-VT or I-DT filter;
``PupilSource`` is the live Pupil Capture connection and ``LslSource`` a Lab Streaming Layer gaze
stream (through pylsl). Samples are a NumPy structured array with the fields
``t_s`` (seconds, the tracker's clock), ``x``, ``y`` (screen pixels, origin top-left, NaN where
the eye was lost), ``confidence`` (0–1), ``valid`` (bool) and ``pupil`` (the tracker's pupil
size in its own units, NaN where it gives none). ``events`` labels every sample (fixation,
saccade, PSO, pursuit, blink) with the command line's detectors and ``evaluate`` scores labels
against human coders.
"""

from __future__ import annotations

import time
import warnings as _warnings
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from . import _core

SAMPLE_DTYPE = np.dtype([("t_s", "f8"), ("x", "f8"), ("y", "f8"), ("confidence", "f4"), ("valid", "?"), ("pupil", "f4")])
EVENT_DTYPE = np.dtype([("start_s", "f8"), ("end_s", "f8"), ("x", "f8"), ("y", "f8")])
FIXATION_DTYPE = np.dtype([("start_s", "f8"), ("end_s", "f8"), ("x", "f8"), ("y", "f8"), ("first", "i8"), ("last", "i8")])

#: The label codes of ``events`` (Zemblys et al. 2018's numbering: 0 undefined, 1 fixation, 2
#: saccade, 3 PSO, 4 pursuit, 5 blink); ``LABELS[code]`` is the name.
LABELS = ("undefined", "fixation", "saccade", "pso", "pursuit", "blink")
#: One detected event (a run of samples with one label); angles in degrees from the screen centre,
#: x right, y up; NaN where undefined (a blink's amplitude).
EVENTS_DTYPE = np.dtype([("label", "U9"), ("first", "i8"), ("last", "i8"), ("onset_s", "f8"), ("duration_s", "f8"),
                         ("amplitude_deg", "f8"), ("peak_velocity_deg_s", "f8"), ("start_x_deg", "f8"),
                         ("start_y_deg", "f8"), ("end_x_deg", "f8"), ("end_y_deg", "f8")])

#: Each detected saccade's landing as the live predictor saw it (``foveal gaze --events
#: --landings-out``, docs/realtime.md): the event's index in ``Events.table``, its onset, landing
#: and amplitude, where it ended (degrees), whether the predictor saw the flight, its first
#: prediction past the peak and the error of it, the prediction two thirds in and its error, and
#: for how long before the landing every prediction was within 1° (NaN where none was)
LANDINGS_DTYPE = np.dtype([("event", "i8"), ("onset_s", "f8"), ("landing_s", "f8"), ("amplitude_deg", "f8"), ("end_x_deg", "f8"),
                           ("end_y_deg", "f8"), ("predicted", "?"), ("predicted_x_deg", "f8"), ("predicted_y_deg", "f8"),
                           ("error_deg", "f8"), ("two_thirds_x_deg", "f8"), ("two_thirds_y_deg", "f8"),
                           ("two_thirds_error_deg", "f8"), ("gained_ms", "f8")])

__all__ = ["Recording", "Events", "read", "fixations", "events", "evaluate", "landing_params", "predict_landings", "PupilSource", "LslSource", "SAMPLE_DTYPE",
           "EVENT_DTYPE", "FIXATION_DTYPE", "EVENTS_DTYPE", "LANDINGS_DTYPE", "LABELS"]


def _samples(columns: Dict[str, np.ndarray]) -> np.ndarray:
    out = np.empty(len(columns["t_s"]), SAMPLE_DTYPE)
    for name in SAMPLE_DTYPE.names:
        out[name] = columns[name]
    return out


def _columns(samples, screen, argument: str = "recording") -> Dict[str, object]:
    """A Recording (or a structured sample array with ``screen``) as the columns the core reads."""
    extra: Dict[str, object] = {}
    if isinstance(samples, Recording):
        screen = screen or samples.screen
        extra["block_starts"] = list(samples.block_starts)
        if samples.directions is not None:
            extra["directions"] = np.ascontiguousarray(samples.directions, dtype=np.float64).reshape(-1)
        extra["fixations"] = {k: np.ascontiguousarray(samples.fixations[k], dtype=np.float64) for k in EVENT_DTYPE.names}
        extra["has_tracker_fixations"] = bool(samples.has_tracker_fixations)
        extra["tracker"] = samples.tracker
        samples = samples.samples
    if screen is None:
        raise ValueError(f"screen: give screen=(W, H) in pixels with a bare sample array as {argument}")
    samples = np.asarray(samples)
    required = ("t_s", "x", "y", "confidence", "valid")
    if samples.dtype.names is None or not set(required) <= set(samples.dtype.names):
        raise TypeError(f"{argument}: expected a foveal.gaze.Recording or samples with the fields {', '.join(required)}, "
                        f"got {type(samples).__name__} of dtype {samples.dtype}")
    col = lambda name: np.ascontiguousarray(samples[name], dtype=np.float64)  # noqa: E731
    columns: Dict[str, object] = {name: col(name) for name in required}
    columns["pupil"] = col("pupil") if "pupil" in samples.dtype.names else np.full(len(samples), np.nan)
    columns["screen"] = (int(screen[0]), int(screen[1]))
    columns.update(extra)
    return columns


def _display(display, screen, recording=None) -> "_core.Display":
    if display is None:
        if isinstance(recording, Recording) and recording.screen_cm is not None:
            w, h, d = recording.screen_cm
            return _core.Display(float(w), float(h), float(d), int(screen[0]), int(screen[1]))
        return _core.Display(47.5, 30.0, 60.0, int(screen[0]), int(screen[1]))
    if not isinstance(display, _core.Display):
        raise TypeError(f"display: expected a foveal.Display, got {type(display).__name__}")
    return display


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
    #: the display's (width_cm, height_cm, distance_cm) where the file states it (a BIDS sidecar):
    #: the default display of ``fixations`` and ``events``
    screen_cm: Optional[Tuple[float, float, float]] = None

    def __len__(self) -> int:
        return len(self.samples)


_TIME_SCALES = {"s": 1.0, "ms": 1e-3, "us": 1e-6}


def read(path, format: str = "auto", screen: Optional[Tuple[int, int]] = None, eye: str = "average",
         min_confidence: float = 0.6, time_unit: str = "s", coords: str = "px", origin: str = "top-left",
         fixations_file: str = "", blinks_file: str = "", display_resolution: Tuple[int, int] = (1680, 1050),
         display: Optional[_core.Display] = None) -> Recording:
    """Read a recording (the options of ``foveal gaze``).

    ``path``: the recording (EyeLink .asc, a Pupil Player export's gaze_positions.csv, a Tobii
    TSV, a t,x,y CSV, a BIDS ``*_physio.tsv.gz`` with its sidecar beside it). ``format``: auto,
    asc, pupil, tobii, csv or bids. ``screen``: (W, H) pixels for
    normalised coordinates or to override the file's (default: what the file states, else the
    display's resolution). ``eye``: average, left or right. For csv: ``time_unit`` s/ms/us,
    ``coords`` px, norm (0–1) or deg (degrees from the screen centre, x right, y up: converted
    with ``display``), ``origin`` top-left/bottom-left. ``min_confidence``: samples below it are
    invalid. ``fixations_file``/``blinks_file``: a Pupil export's side files (default: found
    beside it). ``display``: the physical screen (default 47.5×30 cm at 60 cm with
    ``display_resolution`` pixels, the command line's --display). Raises ValueError naming
    file:line on malformed input, FileNotFoundError for a missing file.
    """
    if time_unit not in _TIME_SCALES:
        raise ValueError(f"time_unit: unknown unit '{time_unit}' (expected s, ms or us)")
    if coords not in ("px", "norm", "deg"):
        raise ValueError(f"coords: expected px, norm or deg, got '{coords}'")
    if origin not in ("top-left", "bottom-left"):
        raise ValueError(f"origin: expected top-left or bottom-left, got '{origin}'")
    if display is None:
        display = _core.Display(47.5, 30.0, 60.0, int(display_resolution[0]), int(display_resolution[1]))
    elif not isinstance(display, _core.Display):
        raise TypeError(f"display: expected a foveal.Display, got {type(display).__name__}")
    import os
    d = _core._read_recording(os.fspath(path), format, screen, eye, float(min_confidence), _TIME_SCALES[time_unit],
                              coords, origin == "bottom-left", os.fspath(fixations_file), os.fspath(blinks_file), display)
    for message in d["warnings"]:
        _warnings.warn(message, stacklevel=2)
    return Recording(samples=_samples(d["samples"]), fixations=_events(d["fixations"]), blinks=_events(d["blinks"]),
                     source=d["source"], format=d["format"], tracker=d["tracker"], screen=tuple(d["screen"]),
                     eyes=d["eyes"], rate_hz=d["rate_hz"], nominal_rate_hz=d["nominal_rate_hz"],
                     has_tracker_fixations=d["has_tracker_fixations"], block_starts=list(d["block_starts"]),
                     notes=list(d["notes"]), warnings=list(d["warnings"]),
                     directions=None if d["directions"] is None else np.asarray(d["directions"]).reshape(-1, 3),
                     screen_cm=None if d["screen_cm"] is None else tuple(d["screen_cm"]))


_PARAMETERS = ("velocity_threshold_deg_s", "velocity_window_s", "gap_fill_s", "merge_gap_s", "merge_angle_deg",
               "min_fixation_s", "median_window", "dispersion_deg", "min_duration_s")
_PURSUIT_PARAMETERS = ("pursuit_velocity_deg_s", "pursuit_window_s", "min_pursuit_s")
_EVENT_PARAMETERS = ("filter_window_s", "detection_window_s", "ek_lambda", "blink_flank_s", "max_blink_s")


def _parameters(params: Dict[str, float], known: Sequence[str]) -> Dict[str, float]:
    for key, value in params.items():
        if key not in known:
            raise ValueError(f"{key}: unknown parameter (known: {', '.join(known)})")
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise TypeError(f"{key}: expected a number, got {type(value).__name__}")
    return {k: float(v) for k, v in params.items()}


def fixations(samples, method: str = "ivt", display: Optional[_core.Display] = None,
              screen: Optional[Tuple[int, int]] = None, labels: bool = False, **params):
    """Fixations of a recording (or a SAMPLE_DTYPE array) by I-VT or I-DT, as ``foveal gaze`` finds them.

    ``samples``: a Recording (its screen and blocks are used) or a structured sample array (then
    give ``screen``). ``method``: ivt or idt (for pursuit, saccades and PSOs: ``events``).
    ``display``: the physical screen for the angles (default 47.5×30 cm at 60 cm, the command
    line's). ``params`` (defaults as the command line's): velocity_threshold_deg_s (30),
    velocity_window_s (0.02), gap_fill_s (0.075), merge_gap_s (0.075), merge_angle_deg (0.5),
    min_fixation_s (0.06), median_window (1), dispersion_deg (1.0), min_duration_s (0.08).
    Returns a structured array of FIXATION_DTYPE (``first``/``last`` are sample indices); with
    ``labels=True`` also each sample's fixation index (−1: none).
    """
    if method in ("auto", "nhr", "nhp", "nh", "ek"):
        raise ValueError(f"method: '{method}' is an event detector: foveal.gaze.events(recording, method='{method}') labels "
                         "fixations, saccades, PSOs, pursuit and blinks")
    columns = _columns(samples, screen, "samples")
    d = _core._fixations(columns, _display(display, columns["screen"], samples), method, _parameters(params, _PARAMETERS))
    result = _events(d, FIXATION_DTYPE)
    return (result, np.asarray(d["label"])) if labels else result


@dataclass
class Events:
    """What ``events`` found: a label per sample and the events (runs of one label)."""

    labels: np.ndarray          #: uint8 per sample, codes of LABELS (0 undefined … 5 blink)
    table: np.ndarray           #: the events, EVENTS_DTYPE (undefined runs left out)
    t_s: np.ndarray             #: each sample's time (the recording's clock), seconds
    velocity_deg_s: np.ndarray  #: each sample's angular velocity, deg/s (NaN where the eye was lost)
    method: str = ""            #: the detector (auto resolved)
    sampling_hz: float = 0.0
    peak_threshold_deg_s: float = float("nan")   #: the adaptive thresholds (nh, nhp; ek: mean η)
    onset_threshold_deg_s: float = float("nan")
    tsv: str = ""               #: the BIDS-style events table, as ``foveal gaze --events-out`` writes it
    landings: np.ndarray = field(default_factory=lambda: np.empty(0, LANDINGS_DTYPE))  #: LANDINGS_DTYPE, one row per saccade
    landings_tsv: str = ""      #: the same table as ``foveal gaze --landings-out`` writes it

    def __len__(self) -> int:
        return len(self.table)

    @property
    def label_names(self) -> np.ndarray:
        """Each sample's label as a name (fixation, saccade, pso, pursuit, blink, undefined)."""
        return np.asarray(LABELS, dtype="U9")[self.labels]

    def counts(self) -> Dict[str, int]:
        """Events per class."""
        return {name: int(np.count_nonzero(self.table["label"] == name)) for name in LABELS[1:]}

    def to_dataframe(self):
        """The events table as a pandas DataFrame (pandas is not a dependency: install it to use this)."""
        try:
            import pandas as pd
        except ImportError as error:
            raise RuntimeError("to_dataframe needs pandas (pip install pandas); the table is also Events.table, "
                               "a NumPy structured array") from error
        return pd.DataFrame({name: self.table[name] for name in EVENTS_DTYPE.names})

    def write_bids(self, path) -> None:
        """Write the events as a BIDS-style events.tsv (onset, duration, trial_type, amplitude_deg,
        peak_velocity_deg_s, start/end x/y in degrees; onsets from the first sample) — the file of
        ``foveal gaze --events-out``. An existing file is replaced only once the new one is whole."""
        _write_whole(path, self.tsv)

    def write_landings(self, path) -> None:
        """Write each saccade's landing as the live predictor saw it — the file of ``foveal gaze
        --landings-out`` (tab-separated, n/a where not predicted). Replaced only once whole."""
        _write_whole(path, self.landings_tsv)


def _write_whole(path, text: str) -> None:
    """Write ``text`` to ``path`` as every foveal writer does: through a partial copy beside it, an
    existing file replaced only once the new one is whole, never over a read-only file."""
    import os
    _core._write_text(os.fspath(path), text)


def events(recording, method: str = "auto", display: Optional[_core.Display] = None,
           screen: Optional[Tuple[int, int]] = None, **params) -> Events:
    """Label every sample and list the events, as ``foveal gaze RECORDING --events METHOD``.

    ``recording``: a Recording (from ``read``) or a structured sample array (then give
    ``screen``). ``method``: auto (= nhr, the recommended: saccades on local robust thresholds,
    PSOs, pursuit in context), nhr, nhp, nh (Nyström & Holmqvist 2010), ek (Engbert & Kliegl
    2003), ivt or idt (docs/gaze.md). ``display``: the physical screen for the angles (default
    47.5×30 cm at 60 cm and the recording's screen in pixels, the command line's). ``params``, in
    seconds and degrees: the fixation filters' (see ``fixations``), pursuit_velocity_deg_s (6),
    pursuit_window_s (0.04), min_pursuit_s (0.08), filter_window_s (the Savitzky–Golay window;
    default the detector's: 0.006 nh/nhp, 0.010 nhr), detection_window_s (0.02), ek_lambda (6),
    blink_flank_s (0.1), max_blink_s (2). Returns an ``Events`` — with ``landings``, each
    saccade's landing as the live predictor of the real-time loop saw it (``--landings-out``); the
    GIL is released while it runs.
    """
    if not isinstance(method, str):
        raise TypeError(f"method: expected a detector's name, got {type(method).__name__}")
    columns = _columns(recording, screen)
    d = _core._events(columns, _display(display, columns["screen"], recording), method,
                      _parameters(params, _PARAMETERS + _PURSUIT_PARAMETERS + _EVENT_PARAMETERS))
    t = d["table"]
    table = np.empty(len(t["onset_s"]), EVENTS_DTYPE)
    table["label"] = np.asarray(LABELS, dtype="U9")[np.asarray(t["label"], dtype=np.intp)]
    for name in EVENTS_DTYPE.names[1:]:
        table[name] = t[name]
    lt = d["landings"]
    landings = np.empty(len(lt["event"]), LANDINGS_DTYPE)
    for name in LANDINGS_DTYPE.names:
        landings[name] = lt[name]
    return Events(labels=np.asarray(d["labels"]), table=table, t_s=columns["t_s"],
                  velocity_deg_s=np.asarray(d["velocity_deg_s"]), method=d["method"], sampling_hz=d["sampling_hz"],
                  peak_threshold_deg_s=d["peak_threshold_deg_s"], onset_threshold_deg_s=d["onset_threshold_deg_s"],
                  tsv=d["tsv"], landings=landings, landings_tsv=d["landings_tsv"])


def landing_params(text: str = "", **params) -> dict:
    """Every parameter of the real-time loop's saccade landing predictor (gaze/landing.h;
    docs/realtime.md) by name: the defaults, with those of ``text`` (``"NAME=VALUE,…"``, as the
    command line's ``--landing``) and then ``params`` over them, checked. The dict goes to
    ``predict_landings(…, **d)``, ``foveal.Loop(landing=d)`` and ``foveal.bench_latency(landing=d)``;
    an unknown name, a value that is no number or one out of range raises ValueError naming it."""
    if not isinstance(text, str):
        raise TypeError(f"text: expected 'NAME=VALUE,…', got {type(text).__name__}")
    return _core._landing_params(text, params)


def predict_landings(t_s, deg, **params) -> list:
    """Run the real-time loop's live saccade landing predictor over a whole sample stream.

    ``t_s``: rising sample times in seconds; ``deg``: an (N, 2) array of gaze positions in degrees
    in any fixed planar frame (NaN marks a lost sample, which ends a flight). ``params``: the
    predictor's, by name (``landing_params()`` lists them with their defaults).

    Returns one dict per saccade the predictor saw land: ``onset_s``, ``detected_s`` (the sample
    that revealed the onset), ``first_prediction_s`` and ``first_landing_deg`` (the first
    prediction past the velocity peak), ``settled_s`` (from then on every prediction was within 1°
    of the landing; NaN if never), ``landing_s``, ``landing_deg`` and ``amplitude_deg`` (measured),
    and every prediction of the flight: ``prediction_s``, ``prediction_x_deg``,
    ``prediction_y_deg``. The GIL is released while it runs. Samples under 20 Hz (a median interval
    over 50 ms, most often times in milliseconds) raise ValueError: no saccade's onset shows in them.
    """
    t = np.ascontiguousarray(t_s, dtype=np.float64)
    d = np.asarray(deg, dtype=np.float64)
    if t.ndim != 1:
        raise ValueError(f"t_s: expected a 1-D array of times, got shape {t.shape}")
    if d.ndim != 2 or d.shape[1] != 2:
        raise ValueError(f"deg: expected an (N, 2) array of positions in degrees, got shape {d.shape}")
    if len(d) != len(t):
        raise ValueError(f"deg: {len(d)} positions for {len(t)} times")
    return _core._predict_landings(t, np.ascontiguousarray(d[:, 0]), np.ascontiguousarray(d[:, 1]), params)


def _label_codes(labels, argument: str) -> np.ndarray:
    array = np.asarray(labels)
    if array.ndim != 1:
        raise ValueError(f"{argument}: expected one label per sample (1-D), got shape {array.shape}")
    if array.dtype.kind in "USO":
        names = {name: code for code, name in enumerate(LABELS)}
        try:
            return np.asarray([names[str(v).lower()] for v in array], dtype=np.uint8)
        except KeyError as error:
            raise ValueError(f"{argument}: unknown label {error.args[0]!r} (known: {', '.join(LABELS)})") from None
    if array.dtype.kind not in "iub":
        raise TypeError(f"{argument}: expected label codes 0–5 or names, got dtype {array.dtype}")
    if array.size and (array.min() < 0 or array.max() >= len(LABELS)):
        raise ValueError(f"{argument}: label codes are 0–5 ({', '.join(LABELS)}), got {array.min()}…{array.max()}")
    return np.ascontiguousarray(array, dtype=np.uint8)


def evaluate(labels, coder, coder2=None, t_s=None) -> dict:
    """Score labels against a human coder's, as ``foveal gaze --events … --evaluate CODER --coder2 CODER2``.

    ``labels``: an ``Events`` (its labels and sample times) or one label per sample (codes 0–5 or
    names; then give ``t_s``, each sample's time). ``coder``, ``coder2``: a label file (CSV with a
    time column t/t_s/time and a ``label`` column, e.g. the IRF or Lund 2013 recordings; matched to
    the samples by time) or one label per sample. With ``coder2`` the labels are scored against it
    too (``coder2``), and the second coder's agreement with the first is the ``ceiling``. Scores are
    over the samples every coder labelled: ``samples``, ``kappa`` (Cohen's, all classes),
    ``accuracy``, and per class in ``classes``: ``kappa``, ``f1``
    (Hooge et al. 2018's event matching), ``hits``, ``misses``, ``false_alarms``,
    ``reference_events``, ``test_events``, ``rto_ms``, ``rtd_ms`` (None where undefined).
    """
    if isinstance(labels, Events):
        t_s = labels.t_s if t_s is None else t_s
        labels = labels.labels
    if t_s is None:
        raise ValueError("t_s: give each sample's time with bare labels (or pass the Events from foveal.gaze.events)")
    codes = _label_codes(labels, "labels")
    times = np.ascontiguousarray(t_s, dtype=np.float64)
    if times.ndim != 1 or len(times) != len(codes):
        raise ValueError(f"t_s: expected {len(codes)} times (one per label), got shape {times.shape}")

    def coder_of(value, argument):
        if value is None:
            return None
        if isinstance(value, (str, bytes)) or hasattr(value, "__fspath__"):
            import os
            return os.fspath(value)
        return _label_codes(value, argument)

    return _core._evaluate(codes, times, coder_of(coder, "coder"), coder_of(coder2, "coder2"))


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
