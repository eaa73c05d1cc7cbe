"""The study workflow (workflows/study, Snakemake) on a two-subject BIDS dataset made from the
shared recordings: every target made, a second run does nothing, touching one recording reruns
only its targets, a run killed midway completes when rerun with nothing partial left, and the
group summary's numbers are what `foveal gaze --json` prints for each recording."""
import csv
import gzip
import json
import math
import os
import pathlib
import signal
import subprocess
import sys
import time

import pytest

from conftest import REPO, run_cli, shared

SNAKEFILE = REPO / "workflows" / "study" / "Snakefile"
SUBJECTS = {"01": ("gaze", "eyelink", "monoRemote500.asc"), "02": ("gaze", "tobii", "tx300_participant1_trial2.tsv")}
SMALL = "{scene: builtin:box, size: 96x60, max_rays: 8, fps: 30, frames: 8}"


LOCAL_ENV = dict(os.environ)


@pytest.fixture(scope="module", autouse=True)
def local_runs_do_not_probe_slurm(tmp_path_factory):
    """The environment of the local (not Slurm) runs. Snakemake's Slurm executor plugin, once
    installed, runs `scontrol show config` whenever snakemake starts, whatever the executor; where
    Slurm's client is installed but no controller runs (this machine between the Slurm test's
    starts), that waits 10 s for its timeout on every call. Here `scontrol` fails at once instead,
    as on a machine without Slurm; the Slurm test runs with the real one."""
    shim = tmp_path_factory.mktemp("no-slurm")
    (shim / "scontrol").write_text("#!/bin/sh\nexit 1\n")
    (shim / "scontrol").chmod(0o755)
    LOCAL_ENV["PATH"] = f"{shim}:{os.environ['PATH']}"
    yield
    LOCAL_ENV["PATH"] = os.environ["PATH"]


def snakemake(cli, cwd, *args, check=True, replay=SMALL, config=()):
    pytest.importorskip("snakemake")
    command = [sys.executable, "-m", "snakemake", "-s", str(SNAKEFILE), "--cores", "2", "--config", f"foveal={cli}",
               f"replay={replay}", *config, "--rerun-incomplete", *args]
    result = subprocess.run(command, cwd=cwd, env=LOCAL_ENV, capture_output=True, text=True, timeout=900)
    if check and result.returncode != 0:
        raise AssertionError(result.stdout[-3000:] + result.stderr[-3000:])
    return result


@pytest.fixture()
def study(cli, tmp_path):
    for subject, parts in SUBJECTS.items():
        run_cli(cli, "gaze", shared(*parts), "--to-bids", tmp_path / "bids", "--subject", subject, "--task", "free", "--no-scanpath", "-q")
    return tmp_path


def outputs(root):
    out = root / "derivatives" / "foveal-study"
    return {p.relative_to(out).as_posix(): p.stat().st_mtime_ns for p in out.rglob("*") if p.is_file()}


def test_the_workflow_makes_every_target_and_reruns_only_what_changed(cli, study):
    snakemake(cli, study)
    made = outputs(study)
    for subject in SUBJECTS:
        stem = f"sub-{subject}_task-free_recording-eye1"
        for name in ("gaze.json", "events.tsv", "replay.mp4", "eye-healthy.mp4", "eye-cataract.mp4"):
            assert f"{stem}/{stem}_{name}" in made, (stem, name)
        assert not any(k.startswith(f"{stem}/{stem}_replay_frames") for k in made), "the replay's frames are temporary"
    assert "group/summary.tsv" in made and "group/summary.png" in made
    # The summary's numbers are foveal gaze --json's
    rows = {r["subject"]: r for r in csv.DictReader(open(study / "derivatives" / "foveal-study" / "group" / "summary.tsv"), delimiter="\t")}
    for subject in SUBJECTS:
        physio = study / "bids" / f"sub-{subject}" / "beh" / f"sub-{subject}_task-free_recording-eye1_physio.tsv.gz"
        run_cli(cli, "gaze", physio, "--events", "auto", "--json", study / "check.json", "--no-scanpath", "-q")
        report = json.loads((study / "check.json").read_text())
        row = rows[subject]
        assert int(row["samples"]) == report["samples"]
        for name, count in report["events"]["counts"].items():
            assert int(row[f"{name}_events"]) == count, (subject, name)
    # A second run does nothing
    again = snakemake(cli, study, "--dry-run")
    assert "Nothing to be done" in again.stdout + again.stderr
    assert outputs(study) == made
    # Changing one recording (its last sample lost) reruns its targets and the summary, nothing of the
    # other's (Snakemake compares the inputs' checksums: a bare touch is no change)
    touched = study / "bids" / "sub-02" / "beh" / "sub-02_task-free_recording-eye1_physio.tsv.gz"
    rows = gzip.open(touched, "rt").read().splitlines()
    fields = rows[-1].split("\t")
    rows[-1] = "\t".join([fields[0], "n/a", "n/a"] + fields[3:])
    with gzip.open(touched, "wt") as f:
        f.write("\n".join(rows) + "\n")
    snakemake(cli, study)
    now = outputs(study)
    changed = {k for k in now if now[k] != made.get(k)}
    assert changed and all(k.startswith("sub-02") or k.startswith("group/") for k in changed), changed
    assert any(k.startswith("sub-02") for k in changed) and not any(k.startswith("sub-01") for k in changed)


def test_a_run_killed_midway_completes_when_rerun_with_nothing_partial_left(cli, study):
    pytest.importorskip("snakemake")
    slow = "{scene: builtin:box, size: 320x200, max_rays: 64, fps: 30, frames: 90}"
    command = [sys.executable, "-m", "snakemake", "-s", str(SNAKEFILE), "--cores", "1", "--config", f"foveal={cli}",
               f"replay={slow}"]
    process = subprocess.Popen(command, cwd=study, env=LOCAL_ENV, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                               start_new_session=True)
    frames = study / "derivatives" / "foveal-study"
    deadline = time.time() + 120
    while time.time() < deadline and not any(frames.rglob("frame_*.png")):  # a replay is under way
        time.sleep(0.1)
    os.killpg(process.pid, signal.SIGKILL)  # snakemake and its jobs, at once: no clean-up of theirs
    process.wait()
    snakemake(cli, study, "--unlock", replay=SMALL)  # the killed run's lock (Snakemake's own rule after a kill)
    snakemake(cli, study, replay=SMALL)
    made = outputs(study)
    assert "group/summary.png" in made
    leftovers = [k for k in made if ".partial" in k or "_replay_frames" in k or pathlib.Path(k).name.startswith(".")]
    assert not leftovers, leftovers
    again = snakemake(cli, study, "--dry-run", replay=SMALL)
    assert "Nothing to be done" in again.stdout + again.stderr


def _free_port():
    import socket
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture()
def slurm(tmp_path):
    """A one-node Slurm on this machine (workflows/study/tests/slurm-single-node.sh), stopped after."""
    import shutil
    tools = ("slurmctld", "slurmd", "sbatch", "squeue", "sacct", "munged", "runuser")
    missing = [t for t in tools if shutil.which(t) is None and not os.path.exists(f"/usr/sbin/{t}")]
    if missing:
        pytest.skip(f"no Slurm here ({', '.join(missing)} missing: scripts/deps.sh installs slurmctld, slurmd, slurm-client, munge)")
    if os.geteuid() != 0:
        pytest.skip("starting slurmctld, slurmd and munged needs root")
    script = REPO / "workflows" / "study" / "tests" / "slurm-single-node.sh"
    folder = tmp_path / "slurm"
    started = subprocess.run([str(script), "start", str(folder), str(_free_port()), str(_free_port())], capture_output=True, text=True,
                             timeout=120)
    try:
        assert started.returncode == 0, started.stderr
        yield started.stdout.strip()
    finally:
        subprocess.run([str(script), "stop", str(folder)], timeout=60)


def test_the_same_workflow_runs_through_a_single_node_slurm(cli, study, slurm, tmp_path):
    env = {**os.environ, "SLURM_CONF": slurm, "PATH": f"{pathlib.Path(sys.executable).parent}:{os.environ['PATH']}"}
    profile = REPO / "workflows" / "study" / "profiles" / "slurm"
    command = [sys.executable, "-m", "snakemake", "-s", str(SNAKEFILE), "--profile", str(profile), "--config", f"foveal={cli}",
               f"replay={SMALL}", "--default-resources", "slurm_partition=debug", "mem_mb=500", "runtime=10",
               "--set-threads", "replay=1", "perceive=1", "--set-resources", "replay:mem_mb=500", "perceive:mem_mb=500",
               "--slurm-no-account", "--slurm-status-command", "squeue", "--slurm-init-seconds-before-status-checks", "1"]
    result = subprocess.run(command, cwd=study, env=env, capture_output=True, text=True, timeout=900)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    # sacct (from Slurm's job-completion records) shows every job of the run completed
    jobs = 2 * (1 + 1 + 2) + 1  # per recording: events, replay, two eye profiles; then the summary
    listing = subprocess.run(["sacct", "-c", "-n", "-P", "-o", "jobid,jobname,state"], env=env, capture_output=True, text=True, timeout=60)
    rows = [line.split("|") for line in listing.stdout.splitlines() if line.strip()]
    assert len(rows) == jobs and all(r[2] == "COMPLETED" for r in rows), listing.stdout
    # The outputs are the local run's
    local = tmp_path / "local"
    local.mkdir()
    os.symlink(study / "bids", local / "bids")
    snakemake(cli, local)
    for relative in outputs(study):
        a, b = study / "derivatives" / "foveal-study" / relative, local / "derivatives" / "foveal-study" / relative
        if relative.endswith("_gaze.json"):  # its detect_ms is a timing
            ja, jb = json.loads(a.read_text()), json.loads(b.read_text())
            ja["events"].pop("detect_ms"), jb["events"].pop("detect_ms")
            assert ja == jb, relative
        elif not relative.endswith(".png"):  # the figure: matplotlib's metadata
            assert a.read_bytes() == b.read_bytes(), relative


def test_a_recording_with_expert_labels_is_scored(cli, tmp_path):
    irf = shared("eye-movements", "irf", "lookAtPoint_EL_S1.csv")
    run_cli(cli, "gaze", irf, "--display", "53.3,30.1,56.5,1920,1080", "--to-bids", tmp_path / "bids", "--subject", "irf1",
            "--task", "fixate", "--no-scanpath", "-q")
    stem = "sub-irf1_task-fixate_recording-eye1"
    target = f"derivatives/foveal-study/{stem}/{stem}_gaze.json"
    snakemake(cli, tmp_path, target, config=[f"events={{method: auto, labels: {{{stem}: {irf}}}}}"])
    report = json.loads((tmp_path / target).read_text())["events"]
    # The same score as foveal gaze --evaluate on the original recording (BENCHMARKS.md: kappa 0.82 on S1)
    run_cli(cli, "gaze", irf, "--display", "53.3,30.1,56.5,1920,1080", "--events", "auto", "--evaluate", irf, "--json",
            tmp_path / "direct.json", "--no-scanpath", "-q")
    direct = json.loads((tmp_path / "direct.json").read_text())["events"]
    assert report["kappa"] == pytest.approx(direct["kappa"]) and report["kappa"] > 0.7


def test_the_summarys_main_sequence_fit_recovers_a_known_power_law():
    import importlib.util
    spec = importlib.util.spec_from_file_location("summary", REPO / "workflows" / "study" / "scripts" / "summary.py")
    summary = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(summary)
    amplitudes = [0.5, 1, 2, 4, 8, 16, float("nan"), -1]
    velocities = [100 * a ** 0.6 if a > 0 else 50 for a in amplitudes]  # V = 100·A^0.6, plus two unusable saccades
    a, b = summary.power_law(amplitudes, velocities)
    assert a == pytest.approx(100) and b == pytest.approx(0.6)
    assert summary.median([3, float("nan"), 1, 2]) == 2
    assert all(math.isnan(v) for v in summary.power_law([1, 1], [2, 2]))
