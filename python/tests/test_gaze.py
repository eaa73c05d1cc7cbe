"""foveal.gaze against `foveal gaze`: the same samples, fixations and errors."""
import json

import numpy as np
import pytest

import foveal
from conftest import cli_error, run_cli, shared

RECORDINGS = [("eyelink", "bino1000.asc"), ("eyelink", "monoRemote500.asc"), ("pupil_labs", "gaze_positions.csv"),
              ("tobii", "tx300_participant1_trial2.tsv")]


def read_samples_csv(path):
    data = np.genfromtxt(path, delimiter=",", names=True)
    return np.atleast_1d(data)


@pytest.mark.parametrize("folder,name", RECORDINGS)
def test_read_gives_the_samples_of_foveal_gaze(cli, tmp_path, folder, name):
    path = shared("gaze", folder, name)
    csv, summary = tmp_path / "samples.csv", tmp_path / "summary.json"
    run_cli(cli, "gaze", path, "--samples", csv, "--json", summary, "--no-scanpath", "-q")
    rec = foveal.gaze.read(str(path))
    expected = read_samples_csv(csv)
    assert len(rec.samples) == len(expected) > 0
    np.testing.assert_array_equal(rec.samples["t_s"], expected["t_s"])
    np.testing.assert_array_equal(rec.samples["x"], expected["x"])  # NaN where the eye was lost, in both
    np.testing.assert_array_equal(rec.samples["y"], expected["y"])
    np.testing.assert_allclose(rec.samples["confidence"], expected["confidence"], rtol=1e-7)
    np.testing.assert_array_equal(rec.samples["valid"], expected["valid"].astype(bool))
    s = json.loads(summary.read_text())
    assert rec.samples["valid"].sum() == s["valid_samples"]
    assert list(rec.screen) == s["screen_px"]
    assert len(rec.fixations) == (s["tracker_fixations"] or 0)
    assert len(rec.blinks) == (s["tracker_blinks"] or 0)
    assert rec.tracker == s["tracker"]
    # The same filters find the same fixations
    for method in ("ivt", "idt"):
        fix = foveal.gaze.fixations(rec, method=method)
        assert len(fix) == s["fixations"][method]["count"], method
        if len(fix):
            mean_ms = 1000 * np.mean(fix["end_s"] - fix["start_s"])
            assert mean_ms == pytest.approx(s["fixations"][method]["mean_duration_ms"], rel=1e-9)


def test_fixations_of_a_synthetic_scan(tmp_path):
    # Two steady 300 ms fixations joined by a fast saccade, 500 Hz
    t = np.arange(0, 0.7, 0.002)
    x = np.where(t < 0.35, 400.0, 1200.0)
    x[(t >= 0.34) & (t < 0.36)] = np.linspace(400, 1200, np.sum((t >= 0.34) & (t < 0.36)))
    samples = np.zeros(len(t), foveal.gaze.SAMPLE_DTYPE)
    samples["t_s"], samples["x"], samples["y"], samples["confidence"], samples["valid"] = t, x, 500.0, 1.0, True
    fix, labels = foveal.gaze.fixations(samples, screen=(1680, 1050), labels=True)
    assert len(fix) == 2
    assert fix["x"][0] == pytest.approx(400) and fix["x"][1] == pytest.approx(1200)
    assert labels.shape == t.shape and labels.max() == 1
    with pytest.raises(ValueError, match="unknown parameter"):
        foveal.gaze.fixations(samples, screen=(1680, 1050), speed=3)
    with pytest.raises(ValueError, match="screen"):
        foveal.gaze.fixations(samples)


def test_malformed_recordings_raise_the_command_lines_message(cli, tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("t,x,y\n0.0,10,20\n0.1,abc,30\n")
    with pytest.raises(ValueError) as e:
        foveal.gaze.read(str(bad))
    assert str(e.value) == cli_error(cli, "gaze", bad, "--no-scanpath")
    assert "bad.csv:3" in str(e.value)
    with pytest.raises(FileNotFoundError):
        foveal.gaze.read(str(tmp_path / "none.asc"))
    with pytest.raises(ValueError, match="time_unit"):
        foveal.gaze.read(str(bad), time_unit="minutes")


def test_a_pupil_that_does_not_answer_raises_within_its_timeout():
    import socket
    import time
    # A port nobody listens on (bound and closed)
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    start = time.monotonic()
    with pytest.raises(ValueError, match="Pupil|answer|timeout|SUB_PORT"):
        foveal.gaze.PupilSource(f"pupil://127.0.0.1:{port}?timeout=0.5")
    assert time.monotonic() - start < 5


def test_a_truncated_eyelink_file_warns(tmp_path):
    cut = tmp_path / "cut.asc"
    lines = ["MSG\t1000 DISPLAY_COORDS 0 0 799 599", "START\t1000 \tLEFT\tSAMPLES\tEVENTS",
             "SAMPLES\tGAZE\tLEFT\tRATE\t 500.00\tTRACKING\tCR\tFILTER\t2"]
    lines += [f"{t}\t  400.0\t  300.0\t 1000.0\t..." for t in range(1000, 1100, 2)]
    cut.write_text("\n".join(lines) + "\n")
    with pytest.warns(UserWarning, match="has no END: the file may be truncated"):
        rec = foveal.gaze.read(str(cut))
    assert len(rec) == 50 and len(rec.warnings) == 1
