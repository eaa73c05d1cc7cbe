"""BIDS eye tracking (BIDS 1.10+ physio "eyetrack" files): every shared recording converted with
`foveal gaze --to-bids` and read back gives the same samples, fixations and events; the dataset
passes the BIDS validator's file-name rules and the schema's sidecar and column rules; pybids
finds every file with its entities; malformed sidecars are one-line errors naming file and key."""
import csv
import gzip
import json
import shutil

import numpy as np
import pytest

import foveal
from conftest import cli_error, run_cli, shared

RECORDINGS = [
    ("eyelinkmono", ("gaze", "eyelink", "monoRemote500.asc"), []),
    ("eyelinkbino", ("gaze", "eyelink", "bino1000.asc"), []),
    ("pupil", ("gaze", "pupil_labs", "gaze_positions.csv"), []),
    ("tobii", ("gaze", "tobii", "tx300_participant1_trial2.tsv"), []),
    ("irf", ("eye-movements", "irf", "lookAtPoint_EL_S1.csv"), ["--display", "53.3,30.1,56.5,1920,1080"]),
]


@pytest.fixture(scope="module")
def dataset(cli, tmp_path_factory):
    """The shared recordings as one BIDS dataset, a subject each, with their events as a derivative."""
    root = tmp_path_factory.mktemp("bids") / "study"
    made = {}
    for subject, parts, options in RECORDINGS:
        source = shared(*parts)
        run_cli(cli, "gaze", source, *options, "--to-bids", root, "--subject", subject, "--task", "free", "--events", "auto",
                "--no-scanpath", "-q")
        made[subject] = (source, options, root / f"sub-{subject}" / "beh" / f"sub-{subject}_task-free_recording-eye1_physio.tsv.gz")
    return root, made


def _read(path, options):
    if options:
        return foveal.gaze.read(path, display=foveal.Display(53.3, 30.1, 56.5, 1920, 1080))
    return foveal.gaze.read(path)


@pytest.mark.parametrize("subject", [r[0] for r in RECORDINGS])
def test_a_recording_read_back_from_bids_is_the_recording(cli, dataset, tmp_path, subject):
    root, made = dataset
    source, options, physio = made[subject]
    a, b = _read(source, options), foveal.gaze.read(physio)
    assert b.format == "bids" and len(a) == len(b)
    sa, sb = a.samples, b.samples
    assert np.max(np.abs(sa["t_s"] - sb["t_s"])) <= 1e-6
    assert np.array_equal(sa["valid"], sb["valid"])
    valid = sa["valid"]
    assert np.max(np.abs(sa["x"][valid] - sb["x"][valid]), initial=0) <= 1e-6
    assert np.max(np.abs(sa["y"][valid] - sb["y"][valid]), initial=0) <= 1e-6
    assert tuple(a.screen) == tuple(b.screen) and a.block_starts == b.block_starts
    assert len(a.fixations) == len(b.fixations) and len(a.blinks) == len(b.blinks)
    # The same fixations and events, from the library and from the command line
    display = foveal.Display(53.3, 30.1, 56.5, 1920, 1080) if options else None
    assert np.array_equal(foveal.gaze.fixations(a, display=display), foveal.gaze.fixations(b, display=display))
    ea, eb = foveal.gaze.events(a, display=display), foveal.gaze.events(b, display=display)
    assert np.array_equal(ea.labels, eb.labels) and ea.tsv == eb.tsv
    run_cli(cli, "gaze", physio, "--events", "auto", "--events-out", tmp_path / "b.tsv", "--no-scanpath", "-q")
    run_cli(cli, "gaze", source, *options, "--events", "auto", "--events-out", tmp_path / "a.tsv", "--no-scanpath", "-q")
    assert (tmp_path / "a.tsv").read_text() == (tmp_path / "b.tsv").read_text()
    # The screen travels with the recording: the BIDS copy needs no --display
    if options:
        assert b.screen_cm == pytest.approx((53.3, 30.1, 56.5))


def test_the_derivative_holds_the_detected_events_and_names_the_detector(dataset):
    root, made = dataset
    folder = root / "derivatives" / "foveal" / "sub-eyelinkmono" / "beh"
    events = folder / "sub-eyelinkmono_task-free_recording-eye1_desc-foveal_physioevents.tsv.gz"
    side = json.loads(events.with_name(events.name.replace(".tsv.gz", ".json")).read_text())
    assert side["Detector"] == "nhr" and side["OnsetSource"] == "timestamp" and "counts" in side["DetectorParameters"]
    rows = list(csv.reader(gzip.open(events, "rt"), delimiter="\t"))
    assert len(rows) == sum(side["DetectorParameters"]["counts"].values())
    assert {r[2] for r in rows} <= {"fixation", "saccade", "pso", "pursuit", "blink"}
    description = json.loads((root / "derivatives" / "foveal" / "dataset_description.json").read_text())
    assert description["DatasetType"] == "derivative" and description["GeneratedBy"][0]["Name"] == "foveal"


def test_the_dataset_passes_the_validators_rules(dataset):
    bids_validator = pytest.importorskip("bids_validator")
    schema_module = pytest.importorskip("bidsschematools.schema")
    root, made = dataset
    validator = bids_validator.BIDSValidator()
    raw = [p for p in root.rglob("*") if p.is_file() and "derivatives" not in p.parts]
    for path in raw:
        assert validator.is_bids("/" + path.relative_to(root).as_posix()), path
    schema = schema_module.load_schema().to_dict()
    rules = schema["rules"]
    required = [k for k, v in rules["sidecars"]["continuous"]["EyeTrack"]["fields"].items() if v == "required"]
    events_required = [k for k, v in rules["sidecars"]["continuous"]["PhysioEvents"]["fields"].items() if v == "required"]
    initial = [schema["objects"]["columns"][c]["name"] for c in rules["tabular_data"]["physio"]["PhysioEyeTracking"]["initial_columns"]]
    for subject, (_, _, physio) in made.items():
        side = json.loads(physio.with_name(physio.name.replace(".tsv.gz", ".json")).read_text())
        for key in required + ["SamplingFrequency", "StartTime", "Columns"]:
            assert key in side, (subject, key)
        assert side["PhysioType"] == "eyetrack" and side["Columns"][:len(initial)] == initial
        assert side["RecordedEye"] in schema["objects"]["metadata"]["RecordedEye"]["enum"]
        rows = [line.split("\t") for line in gzip.open(physio, "rt").read().splitlines()]
        assert {len(r) for r in rows} == {len(side["Columns"])}
        events = physio.with_name(physio.name.replace("_physio.tsv.gz", "_physioevents.json"))
        events_side = json.loads(events.read_text())
        for key in events_required:
            assert key in events_side, (subject, key)
        assert events_side["OnsetSource"] in side["Columns"]
        task = json.loads((physio.parent / f"sub-{subject}_task-free_events.json").read_text())["StimulusPresentation"]
        for key in ("ScreenDistance", "ScreenOrigin", "ScreenResolution", "ScreenSize"):
            assert key in task and task[key] != "n/a", (subject, key)
    description = json.loads((root / "dataset_description.json").read_text())
    assert description["BIDSVersion"] and description["Name"]


def test_pybids_finds_every_file_with_its_entities(dataset):
    bids = pytest.importorskip("bids")
    root, made = dataset
    layout = bids.BIDSLayout(str(root), validate=False, derivatives=True)
    assert sorted(layout.get_subjects()) == sorted(made)
    physio = layout.get(suffix="physio", extension=".tsv.gz")
    assert len(physio) == len(made)
    for f in physio:
        entities = f.get_entities()
        assert entities["task"] == "free" and entities["recording"] == "eye1" and entities["datatype"] == "beh"
    events = layout.get(suffix="physioevents", extension=".tsv.gz", desc="foveal")
    assert len(events) == len(made)


def _bids_copy(dataset, tmp_path):
    root, made = dataset
    physio = made["eyelinkmono"][2]
    target = tmp_path / physio.name
    shutil.copy(physio, target)
    side = json.loads(physio.with_name(physio.name.replace(".tsv.gz", ".json")).read_text())
    return target, target.with_name(target.name.replace(".tsv.gz", ".json")), side


@pytest.mark.parametrize("edit, key", [
    (lambda s: s.pop("SamplingFrequency"), "SamplingFrequency"),
    (lambda s: s.pop("Columns"), "Columns"),
    (lambda s: s.update(PhysioType="cardiac"), "PhysioType"),
    (lambda s: s.pop("PhysioType"), "PhysioType"),
    (lambda s: s.update(Columns=s["Columns"] + ["extra"]), "Columns"),
    (lambda s: s.update(SamplingFrequency="fast"), "SamplingFrequency"),
])
def test_a_malformed_sidecar_is_one_line_naming_the_file_and_the_key(cli, dataset, tmp_path, edit, key):
    physio, sidecar, side = _bids_copy(dataset, tmp_path)
    edit(side)
    sidecar.write_text(json.dumps(side))
    with pytest.raises(ValueError) as error:
        foveal.gaze.read(physio)
    message = str(error.value)
    assert key in message and (sidecar.name in message or physio.name in message), message
    line = cli_error(cli, "gaze", physio, "--no-scanpath")
    assert key in line and "\n" not in line


def test_a_missing_sidecar_and_a_bad_cell_name_the_file(cli, dataset, tmp_path):
    physio, sidecar, side = _bids_copy(dataset, tmp_path)
    with pytest.raises(FileNotFoundError, match="_physio.json"):
        foveal.gaze.read(physio)
    sidecar.write_text(json.dumps(side))
    rows = gzip.open(physio, "rt").read().splitlines()
    fields = rows[2].split("\t")
    rows[2] = "\t".join([fields[0], "abc"] + fields[2:])
    with gzip.open(physio, "wt") as f:
        f.write("\n".join(rows) + "\n")
    with pytest.raises(ValueError, match=r":3: x_coordinate: 'abc' is not a number"):
        foveal.gaze.read(physio)


def test_to_bids_refuses_to_replace_a_recording_and_bad_entities(cli, dataset):
    root, made = dataset
    source = made["eyelinkmono"][0]
    message = cli_error(cli, "gaze", source, "--to-bids", root, "--subject", "eyelinkmono", "--task", "free", "--no-scanpath")
    assert "exists already" in message
    assert cli_error(cli, "gaze", source, "--to-bids", root, "--subject", "p_01", "--task", "free",
                     "--no-scanpath").startswith("--subject: 'p_01'")
    assert cli_error(cli, "gaze", source, "--to-bids", root, "--subject", "p01", "--no-scanpath").startswith("--task")
    assert cli_error(cli, "gaze", source, "--subject", "p01", "--no-scanpath").startswith("--subject")
