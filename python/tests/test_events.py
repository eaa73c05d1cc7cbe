"""foveal.gaze.events and evaluate: the command line's detectors, scores and BIDS events table."""
import csv
import json

import numpy as np
import pytest

import foveal
from conftest import run_cli, shared

IRF_DISPLAY = ("53.3,30.1,56.5,1920,1080", foveal.Display(53.3, 30.1, 56.5, 1920, 1080))
LUND_DISPLAY = ("38,30,67,1024,768", foveal.Display(38, 30, 67, 1024, 768))


def _cli_events(cli, tmp_path, recording, display, method, *extra):
    samples, events, report = tmp_path / "s.csv", tmp_path / "e.tsv", tmp_path / "r.json"
    run_cli(cli, "gaze", recording, "--display", display, *extra, "--events", method, "--samples-out", samples,
            "--events-out", events, "--json", report, "--no-scanpath", "-q")
    labels = np.asarray([row["label"] for row in csv.DictReader(open(samples))])
    return labels, events.read_text(), json.loads(report.read_text())["events"]


@pytest.mark.parametrize("parts, options", [
    (("eye-movements", "lund2013-train", "video", "TH38_video_dolphin_fov_labelled_MN.csv"),
     ["--display", LUND_DISPLAY[0], "--coords", "px"]),
    (("gaze", "eyelink", "monoRemote500.asc"), []),
    (("gaze", "pupil_labs", "gaze_positions.csv"), []),
    (("gaze", "tobii", "tx300_participant1_trial2.tsv"), []),
])
def test_events_equal_the_command_lines_on_the_shared_recordings(cli, tmp_path, parts, options):
    recording = shared(*parts)
    samples, events = tmp_path / "s.csv", tmp_path / "e.tsv"
    run_cli(cli, "gaze", recording, *options, "--events", "auto", "--samples-out", samples, "--events-out", events,
            "--no-scanpath", "-q")
    labels = np.asarray([row["label"] for row in csv.DictReader(open(samples))])
    display = LUND_DISPLAY[1] if options else None
    rec = foveal.gaze.read(recording, **({"coords": "px", "display": display} if options else {}))
    found = foveal.gaze.events(rec, display=display)
    assert np.array_equal(found.label_names, labels)
    assert found.tsv == events.read_text()


@pytest.mark.parametrize("method", ["auto", "nhp", "ek", "ivt"])
def test_events_equal_the_command_lines_on_an_irf_recording(cli, tmp_path, method):
    recording = shared("eye-movements", "irf", "lookAtPoint_EL_S1.csv")
    labels, tsv, report = _cli_events(cli, tmp_path, recording, IRF_DISPLAY[0], method, "--coords", "deg")
    rec = foveal.gaze.read(recording, coords="deg", display=IRF_DISPLAY[1])
    found = foveal.gaze.events(rec, method=method, display=IRF_DISPLAY[1])
    assert np.array_equal(found.label_names, labels)
    assert found.tsv == tsv and found.method == report["detector"]
    assert found.counts() == {k: v for k, v in report["counts"].items()}
    assert len(found) == sum(report["counts"].values())
    # The table's rows are the TSV's
    rows = list(csv.DictReader(tsv.splitlines(), delimiter="\t"))
    assert [r["trial_type"] for r in rows] == list(found.table["label"])
    assert np.allclose([float(r["onset"]) for r in rows], found.table["onset_s"] - rec.samples["t_s"][0], atol=1e-6)
    path = tmp_path / "sub-01_events.tsv"
    found.write_bids(path)
    assert path.read_text() == tsv


def test_landings_equal_the_command_lines_on_an_irf_recording(cli, tmp_path):
    """Each saccade's landing as the live predictor saw it: gaze --events --landings-out, from Python."""
    recording = shared("eye-movements", "irf", "lookAtPoint_EL_S2.csv")
    landings_out = tmp_path / "landings.tsv"
    run_cli(cli, "gaze", recording, "--display", IRF_DISPLAY[0], "--coords", "deg", "--events", "auto", "--landings-out",
            landings_out, "--no-scanpath", "-q")
    rec = foveal.gaze.read(recording, coords="deg", display=IRF_DISPLAY[1])
    found = foveal.gaze.events(rec, display=IRF_DISPLAY[1])
    assert found.landings_tsv == landings_out.read_text()
    landings = found.landings
    assert landings.dtype == foveal.gaze.LANDINGS_DTYPE
    # One row per detected saccade, in order, pointing at its event
    assert list(found.table["label"][landings["event"]]) == ["saccade"] * len(landings)
    assert len(landings) == found.counts()["saccade"] and np.all(np.diff(landings["onset_s"]) > 0)
    # A predicted row's error is the distance from its first prediction to where the saccade ended
    seen = landings[landings["predicted"]]
    assert len(seen) > 0.5 * len(landings)
    error = np.hypot(seen["predicted_x_deg"] - seen["end_x_deg"], seen["predicted_y_deg"] - seen["end_y_deg"])
    assert np.allclose(error, seen["error_deg"])
    assert np.all(np.isnan(landings[~landings["predicted"]]["error_deg"]))
    # The large saccades are predicted, and two thirds in the prediction is closer than at first (median)
    large = seen[seen["amplitude_deg"] >= 5]
    assert len(large) > 10 and np.median(large["two_thirds_error_deg"]) < np.median(large["error_deg"])
    path = tmp_path / "landings-again.tsv"
    found.write_landings(path)
    assert path.read_text() == landings_out.read_text()


def test_evaluate_gives_the_command_lines_scores_and_ceiling_on_lund(cli, tmp_path):
    folder = shared("eye-movements", "lund2013-train", "video")
    mn = folder / "TH34_video_BergoDalbana_labelled_MN.csv"
    ra = folder / "TH34_video_BergoDalbana_labelled_RA.csv"
    report_path = tmp_path / "r.json"
    run_cli(cli, "gaze", mn, "--display", LUND_DISPLAY[0], "--coords", "px", "--events", "auto", "--evaluate", mn,
            "--coder2", ra, "--json", report_path, "--no-scanpath", "-q")
    report = json.loads(report_path.read_text())["events"]
    rec = foveal.gaze.read(mn, coords="px", display=LUND_DISPLAY[1])
    found = foveal.gaze.events(rec, display=LUND_DISPLAY[1])
    scores = foveal.gaze.evaluate(found, mn, coder2=ra)
    assert scores["kappa"] == pytest.approx(report["kappa"], abs=0) and scores["samples"] == report["samples"]
    assert scores["classes"] == report["classes"]
    assert scores["ceiling"]["classes"] == report["ceiling"]["classes"]
    assert scores["coder2"]["classes"] == report["coder2"]["classes"]
    # Against the second coder: what the first coder alone gives when the roles are swapped
    assert foveal.gaze.evaluate(found, ra, coder2=mn)["classes"] == scores["coder2"]["classes"]
    # Labels given as names and times, a coder as per-sample labels: the same scores
    coder = foveal.gaze.evaluate(found.label_names, found.labels, t_s=found.t_s)
    assert coder["kappa"] == pytest.approx(1.0) and coder["accuracy"] == 1.0


def test_events_from_a_bare_sample_array_and_its_errors():
    t = np.arange(0, 2, 0.002)
    x = 400 + 300 * np.clip((t - 1) / 0.03, 0, 1)  # one 30 ms saccade at 1 s
    samples = np.zeros(len(t), foveal.gaze.SAMPLE_DTYPE)
    samples["t_s"], samples["x"], samples["y"], samples["confidence"], samples["valid"] = t, x, 300.0, 1.0, True
    samples["pupil"] = np.nan
    found = foveal.gaze.events(samples, screen=(1680, 1050))
    assert found.counts()["saccade"] == 1 and found.labels.dtype == np.uint8
    with pytest.raises(ValueError, match="^screen"):
        foveal.gaze.events(samples)
    with pytest.raises(ValueError, match="^method"):
        foveal.gaze.events(samples, screen=(1680, 1050), method="magic")
    with pytest.raises(ValueError, match="^speed: unknown parameter"):
        foveal.gaze.events(samples, screen=(1680, 1050), speed=3)
    with pytest.raises(TypeError, match="^recording"):
        foveal.gaze.events(np.zeros(10), screen=(1680, 1050))
    with pytest.raises(ValueError, match="^method: 'nhp' is an event detector"):
        foveal.gaze.fixations(samples, screen=(1680, 1050), method="nhp")
    with pytest.raises(ValueError, match="^labels"):
        foveal.gaze.evaluate(np.full(len(t), 9), found.labels, t_s=t)
    with pytest.raises(ValueError, match="^coder"):
        foveal.gaze.evaluate(found, found.labels[:-1])


def test_the_events_table_as_a_dataframe():
    pd = pytest.importorskip("pandas")
    t = np.arange(0, 1, 0.002)
    samples = np.zeros(len(t), foveal.gaze.SAMPLE_DTYPE)
    samples["t_s"], samples["x"], samples["y"], samples["confidence"], samples["valid"] = t, 500.0, 300.0, 1.0, True
    frame = foveal.gaze.events(samples, screen=(1680, 1050)).to_dataframe()
    assert isinstance(frame, pd.DataFrame) and list(frame.columns) == list(foveal.gaze.EVENTS_DTYPE.names)


def test_a_binary_file_given_as_a_recording_names_the_file_and_the_problem():
    image = shared("images", "baboon.jpg")
    with pytest.raises(ValueError) as error:
        foveal.gaze.read(image)
    assert str(image) in str(error.value) and "binary" in str(error.value)


def test_a_message_quoting_bytes_that_are_not_utf8_keeps_them_escaped(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_bytes(b"t,x,\xff\xfe\n1,2,3\n")
    with pytest.raises(ValueError) as error:
        foveal.gaze.read(path)
    assert str(path) in str(error.value) and "\\xff\\xfe" in str(error.value)
