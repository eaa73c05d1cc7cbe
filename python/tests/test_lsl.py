"""LslSource on a loopback LSL stream with the XDF gaze meta-data."""
import time
import uuid

import numpy as np
import pytest

import foveal

pylsl = pytest.importorskip("pylsl")


def outlet(name, channels, fmt=None):
    info = pylsl.StreamInfo(name, "Gaze", len(channels), 120, pylsl.cf_float32, uuid.uuid4().hex)
    chans = info.desc().append_child("channels")
    for label, kind, unit in channels:
        c = chans.append_child("channel")
        c.append_child_value("label", label)
        c.append_child_value("eye", "both")
        c.append_child_value(fmt or "type", kind)
        c.append_child_value("unit", unit)
    return pylsl.StreamOutlet(info)


def pull(source, count, timeout=5.0):
    got = []
    end = time.monotonic() + timeout
    while sum(len(g) for g in got) < count and time.monotonic() < end:
        got.append(source.poll())
        time.sleep(0.01)
    return np.concatenate(got) if got else np.empty(0, foveal.gaze.SAMPLE_DTYPE)


def test_normalised_gaze_with_confidence_follows_the_metadata():
    name = "foveal-test-" + uuid.uuid4().hex[:8]
    # Channels in an unusual order: the metadata, not the position, says which is which
    out = outlet(name, [("conf", "Confidence", "normalized"), ("gy", "ScreenY", "normalized"), ("gx", "ScreenX", "normalized")])
    source = foveal.gaze.LslSource(name=name, screen=(1000, 500), timeout=5)
    assert source.state == "waiting"
    time.sleep(0.3)
    sent = [(0.9, 0.25, 0.5), (0.2, 0.5, 0.1), (1.0, 1.0, 1.0)]
    for s in sent:
        out.push_sample(list(s))
    got = pull(source, 3)
    assert len(got) == 3
    np.testing.assert_allclose(got["x"], [500, 100, 1000])
    np.testing.assert_allclose(got["y"], [125, 250, 500])
    np.testing.assert_allclose(got["confidence"], [0.9, 0.2, 1.0], rtol=1e-6)
    assert list(got["valid"]) == [True, False, True]  # 0.2 < min_confidence 0.6
    assert np.all(np.diff(got["t_s"]) >= 0)
    assert source.state == "live"
    del out
    end = time.monotonic() + 5
    while source.state not in ("stale", "disconnected") and time.monotonic() < end:
        source.poll()
        time.sleep(0.05)
    assert source.state in ("stale", "disconnected")


def test_pixel_gaze_and_pupils_metatype_with_bottom_left_origin():
    name = "foveal-test-" + uuid.uuid4().hex[:8]
    out = outlet(name, [("norm_pos_x", "ScreenX", "normalized"), ("norm_pos_y", "ScreenY", "normalized")], fmt="metatype")
    source = foveal.gaze.LslSource(name=name, screen=(800, 600), origin="bottom-left")
    time.sleep(0.3)
    out.push_sample([0.5, 0.0])
    got = pull(source, 1)
    assert got["x"][0] == pytest.approx(400) and got["y"][0] == pytest.approx(600)
    assert got["confidence"][0] == 1 and got["valid"][0]
    name2 = "foveal-test-" + uuid.uuid4().hex[:8]
    out2 = outlet(name2, [("x", "ScreenX", "pixels"), ("y", "ScreenY", "pixels")])
    src2 = foveal.gaze.LslSource(name=name2)
    time.sleep(0.3)
    out2.push_sample([321.0, 123.0])
    got = pull(src2, 1)
    assert (got["x"][0], got["y"][0]) == (321.0, 123.0)


def test_a_stream_that_is_not_there_or_has_no_gaze_channels():
    with pytest.raises(RuntimeError, match="no LSL stream"):
        foveal.gaze.LslSource(name="foveal-absent-" + uuid.uuid4().hex, timeout=0.5)
    name = "foveal-test-" + uuid.uuid4().hex[:8]
    out = outlet(name, [("pupil", "Diameter", "mm"), ("blink", "Blink", "")])  # noqa: F841
    with pytest.raises(ValueError, match="ScreenX"):
        foveal.gaze.LslSource(name=name)
