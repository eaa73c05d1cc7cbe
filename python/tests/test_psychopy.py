"""Both PsychoPy examples run headless (Xvfb); QUEST finds the simulated observer's threshold."""
import csv
import json
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
EXAMPLES = REPO / "examples" / "psychopy"


def run_example(script, args, cwd, screen="1024x768"):
    if shutil.which("xvfb-run") is None:
        pytest.skip("xvfb-run is not installed")
    try:
        import psychopy  # noqa: F401
    except ImportError:
        pytest.skip("psychopy is not installed (scripts/python-env.sh installs it)")
    command = ["xvfb-run", "-a", "-s", f"-screen 0 {screen}x24", sys.executable, str(EXAMPLES / script), *map(str, args)]
    result = subprocess.run(command, cwd=cwd, capture_output=True, text=True, timeout=600, env={**os.environ, "PYTHONUNBUFFERED": "1"})
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    return result


def test_gaze_contingent_follows_the_mouse_gaze_and_logs_latency(tmp_path):
    flips = 60
    run_example("gaze_contingent.py", ["--size", "320x200", "--frames", flips, "--device", "cpu", "--fullscreen", "--refresh-hz", 60,
                                       "--move-mouse", "--log", "frames.csv", "--summary", "summary.json", "--probe-stalls", 0.3,
                                       "--margin-ms", 3, "--periphery-share", 0.8, "--plot", "session.png"], tmp_path,
                screen="320x200")
    rows = list(csv.DictReader(open(tmp_path / "frames.csv")))
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert len(rows) == summary["flips"] == flips
    # The session drawn from its log at the end (session_plot.py; its own tests below)
    from PIL import Image
    with Image.open(tmp_path / "session.png") as picture:
        assert picture.format == "PNG" and picture.size == (1000, 900)
    assert not (tmp_path / "frames.csv.partial").exists()  # logged as it ran, then given its name
    # ioHub's times are seconds; MouseGaze is read about once a flip, so where that is under 90 Hz
    # the loop says its landings come too late to predict with gain (docs/realtime.md, "Slower trackers")
    assert "milliseconds" not in summary["gaze_note"]
    rate = summary["gaze_sample_hz"]  # as the loop measured it, over the latest 16 samples
    assert 20 < rate < 2000
    assert ("too late to gain much" in summary["gaze_note"]) == (rate < 90), (summary["gaze_note"], rate)
    # The frames followed a moving gaze (MouseGaze driven by the moving pointer), every flip logged
    assert summary["gaze_positions"] > flips // 3
    for r in rows[1:]:
        assert float(r["flip_time_s"]) > float(r["render_start_s"]) >= float(r["sample_time_s"])
        assert r["fovea"] in ("refining", "converged")
        assert 0 <= float(r["fovea_converged"]) <= 1
    # Each flip's budget (the refresh less the script's own work, from the second flip) and the size
    # the loop rendered at (smaller than asked only where the base shading did not fit)
    assert float(rows[0]["budget_ms"]) == pytest.approx(1000 / 60)
    assert all(0 < float(r["budget_ms"]) <= 1000 / 60 for r in rows)
    assert any(float(r["budget_ms"]) < 1000 / 60 for r in rows[2:])
    sizes = [(int(r["width"]), int(r["height"])) for r in rows]
    assert all(0 < w <= 320 and 0 < h <= 200 and abs(w / h - 1.6) < 0.05 for w, h in sizes)
    assert sizes[-1] == tuple(summary["render_size"])
    # Chunks of rays left to threads the machine paused, per flip, and the flips that left any
    assert summary["frames_left_behind"] == sum(int(r["chunks_left_behind"]) > 0 for r in rows)
    # The loop answers within what the script's own work leaves of the 60 Hz refresh, so the image
    # shown is at most two refreshes behind the gaze
    assert summary["refresh_hz"] == 60 and 0 < summary["budget_ms"] <= 1000 / 60
    # the margin given (within half the budget the script leaves the loop) and share, as the loop took them
    assert summary["margin_ms"] == pytest.approx(min(3, summary["budget_ms"] / 2)) and summary["periphery_share"] == 0.8
    assert summary["min_scale"] == 0.25  # (the loop's default)
    assert summary["refresh_measured"] is False and summary["refresh_note"] == ""  # (given: nothing to doubt)
    assert 0 < summary["gaze_to_flip_ms_median"] <= summary["gaze_to_flip_ms_p95"]
    assert summary["gaze_to_flip_refreshes_median"] <= 2.0
    # The machine's own pauses, probed first (foveal.stalls)
    stalls = summary["machine_stalls"]
    assert stalls["duration_s"] >= 0.25 and stalls["chunks"] > 0 and "stalls" not in stalls
    assert set(stalls["on_cpu"]) == {"count", "per_minute", "worst_ms", "beyond_margin"}
    # … and what else ran during the session (foveal.machine_snapshot, foveal.busiest_others): other
    # processes only (Xvfb and ioHub's server among them, as a rule), the busiest first
    others = summary["other_processes"]
    assert isinstance(others, list) and len(others) <= 5
    assert all(set(o) == {"pid", "name", "kernel", "cpu_ms", "slices"} and o["cpu_ms"] > 0 for o in others)
    assert [o["cpu_ms"] for o in others] == sorted((o["cpu_ms"] for o in others), reverse=True)


def test_a_refresh_rate_no_display_runs_at_is_said_to_be_doubtful():
    # PsychoPy measures the pace of the flips; where they do not wait for the vertical blank (Xvfb,
    # vsync off) that is the drawing's pace — about 490 Hz under Xvfb at 840x525, a 4-ms budget —
    # and the session says so, naming the option that gives the display's rate
    sys.path.insert(0, str(EXAMPLES))
    try:
        from session_checks import FASTEST_USUAL_HZ, refresh_rate
    finally:
        sys.path.remove(str(EXAMPLES))
    assert refresh_rate(60.0, None) == (60.0, "")  # given: used, whatever PsychoPy would measure
    assert refresh_rate(1440.0, None) == (1440.0, "")  # (a projector's 1440 Hz, given, is not doubted)
    for usual in (59.94, 60.0, 120.0, 144.0, FASTEST_USUAL_HZ):
        assert refresh_rate(None, usual) == (usual, "")
    hz, note = refresh_rate(None, 489.7)
    assert hz == 489.7 and "490 Hz" in note and "vertical blank" in note and "--refresh-hz" in note
    for unmeasured in (None, 0.0, float("nan")):
        hz, note = refresh_rate(None, unmeasured)
        assert hz == 60.0 and "60 Hz assumed" in note and "--refresh-hz" in note


def test_a_failed_gaze_contingent_session_keeps_its_flips(tmp_path):
    # Stopped mid-session (SIGTERM: a session manager's kill, a cluster's time limit), the flips
    # logged so far stay in LOG.partial and it says so; LOG itself is written only by a session that ends
    if shutil.which("xvfb-run") is None:
        pytest.skip("xvfb-run is not installed")
    pytest.importorskip("psychopy", reason="psychopy is not installed (scripts/python-env.sh installs it)")
    command = ["xvfb-run", "-a", "-s", "-screen 0 320x200x24", sys.executable, str(EXAMPLES / "gaze_contingent.py"), "--size",
               "320x200", "--frames", "0", "--device", "cpu", "--fullscreen", "--refresh-hz", "60", "--move-mouse", "--log", "frames.csv"]
    run = subprocess.Popen(command, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                           env={**os.environ, "PYTHONUNBUFFERED": "1"})
    partial = tmp_path / "frames.csv.partial"
    try:
        deadline = time.monotonic() + 300
        while time.monotonic() < deadline and (not partial.exists() or partial.read_text().count("\n") < 62):
            assert run.poll() is None, run.communicate()[1][-3000:]
            time.sleep(0.2)
        # the script's own process: xvfb-run's child (/proc: no tool needed)
        children = [int(d) for d in os.listdir("/proc") if d.isdigit() and _parent(int(d)) == run.pid]
        script = next(pid for pid in children if "gaze_contingent.py" in pathlib.Path(f"/proc/{pid}/cmdline").read_text())
        os.kill(script, signal.SIGTERM)
        _, err = run.communicate(timeout=120)
    finally:
        if run.poll() is None:  # (the whole session: xvfb-run, Xvfb, the script, ioHub's server)
            os.killpg(run.pid, signal.SIGKILL)
            run.communicate()
    assert run.returncode != 0
    assert "the session failed after" in err and "frames.csv.partial" in err, err[-3000:]
    rows = list(csv.DictReader(open(partial)))
    assert len(rows) >= 61 and [int(r["flip"]) for r in rows[:61]] == list(range(61))
    assert not (tmp_path / "frames.csv").exists()


def _parent(pid):
    try:
        return int(pathlib.Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[1])
    except (OSError, IndexError, ValueError):
        return -1


def test_gaze_contingent_refuses_bad_options_before_the_session(tmp_path):
    """A log in a missing folder was lost at the session's end; now it fails at once, as argparse does."""
    cases = [(["--log", str(tmp_path / "missing" / "frames.csv")], "--log"), (["--summary", str(tmp_path)], "--summary"),
             (["--size", "320"], "--size"), (["--display", "47.5,0,60"], "--display"), (["--frames", "-1"], "--frames"),
             (["--refresh-hz", "0"], "--refresh-hz"), (["--landing", "speed=3"], "--landing"),
             (["--landing", "onset_deg_s=fast"], "--landing"), (["--landing", "skew=9"], "--landing"),
             (["--margin-ms", "-1"], "--margin-ms"), (["--margin-ms", "nan"], "--margin-ms"),
             (["--periphery-share", "0"], "--periphery-share"), (["--periphery-share", "1.5"], "--periphery-share"),
             (["--min-scale", "0"], "--min-scale"), (["--min-scale", "2"], "--min-scale"),
             (["--plot", "session.txt"], "--plot"), (["--plot", str(tmp_path / "missing" / "session.png")], "--plot"),
             (["--plot", str(tmp_path)], "--plot")]
    for args, name in cases:
        result = subprocess.run([sys.executable, str(EXAMPLES / "gaze_contingent.py"), *args], cwd=tmp_path, capture_output=True,
                                text=True, timeout=60)
        assert result.returncode == 2, (args, result.stderr)
        assert f"error: {name}" in result.stderr.splitlines()[-1], (args, result.stderr)
    assert not (tmp_path / "missing").exists()
    # A read-only log or summary is not replaced (by root either), nor a failed session's kept flips
    locked = tmp_path / "locked.csv"
    locked.write_text("kept\n")
    locked.chmod(0o444)
    kept = tmp_path / "frames.csv.partial"
    kept.write_text("flip\n0\n")
    for args, words in ((["--log", str(locked)], "--log: " + str(locked) + ": is read-only"),
                        (["--summary", str(locked)], "--summary: " + str(locked) + ": is read-only"),
                        (["--log", str(tmp_path / "frames.csv")], "frames.csv.partial holds the flips of a session that failed")):
        result = subprocess.run([sys.executable, str(EXAMPLES / "gaze_contingent.py"), *args], cwd=tmp_path, capture_output=True,
                                text=True, timeout=60)
        assert result.returncode == 2 and words in result.stderr, (args, result.stderr)
    assert locked.read_text() == "kept\n" and kept.read_text() == "flip\n0\n"
    # foveal's own checks come before the stall probe and the window too; an input is never an output
    scene = tmp_path / "scene.obj"
    scene.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    for args, words in ((["--device", "tpu"], "--device: unknown device 'tpu'"),
                        (["--scene", str(tmp_path / "none.obj")], "--scene: "),
                        (["--camera", "nope"], "--camera: scene 'builtin:box' has no camera named 'nope'"),
                        (["--scene", str(scene), "--log", str(scene)], "--log: " + str(scene) + ": is --scene"),
                        (["--log", "a.csv", "--summary", "./a.csv"], "two outputs into one file"),
                        (["--summary", "s.png", "--plot", "./s.png"], "--summary s.png and --plot ./s.png: two outputs into one file")):
        result = subprocess.run([sys.executable, str(EXAMPLES / "gaze_contingent.py"), *args], cwd=tmp_path, capture_output=True,
                                text=True, timeout=60)
        assert result.returncode == 2 and words in result.stderr.splitlines()[-1], (args, result.stderr)
    assert scene.read_text().startswith("v 0 0 0")
    # No display: one line saying so (it was pyglet's traceback, after the scene and the stall probe)
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    result = subprocess.run([sys.executable, str(EXAMPLES / "gaze_contingent.py")], cwd=tmp_path, capture_output=True, text=True,
                            timeout=60, env=env)
    assert result.returncode == 2 and "no display to open the window on" in result.stderr and "Traceback" not in result.stderr


def test_foveation_threshold_quest_converges_to_the_model_observers_threshold(tmp_path):
    # The model observer detects the rendered difference (acuity-weighted RMSE against the
    # reference); its threshold is the difference the frame at γ = 3 (then 6) makes
    threshold = 3.0
    trials = 40
    run_example("foveation_threshold.py", ["--simulate", threshold, "--trials", trials, "--size", "840x525", "--max-rays", 16,
                                           "--device", "cpu", "--seed", 1, "--out", "data"], tmp_path)
    summary = json.loads((tmp_path / "data" / "sim_summary.json").read_text())
    assert summary["trials"] == trials and summary["observer"].startswith("model")
    assert abs(summary["threshold_gamma"] - threshold) <= 0.2 * threshold
    # PsychoPy's standard data files: one row per trial, the γ QUEST chose on each and what the observer saw
    rows = list(csv.DictReader(open(tmp_path / "data" / "sim_foveation_threshold.csv", encoding="utf-8-sig")))
    assert len(rows) == trials
    gammas = [float(r["gamma"]) for r in rows]
    assert min(gammas) >= 1.0 and max(gammas) <= 12.0 and len(set(gammas)) > 5
    # The visible difference grows with γ (the observer's evidence comes from the images)
    differences = [float(r["visible_difference"]) for r in rows]
    order = sorted(range(trials), key=lambda i: gammas[i])
    assert differences[order[-1]] > differences[order[0]] > 0
    assert (tmp_path / "data" / "sim_foveation_threshold.psydat").exists()
    # Another threshold moves the estimate with it
    run_example("foveation_threshold.py", ["--simulate", 6.0, "--trials", trials, "--size", "840x525", "--max-rays", 16,
                                           "--device", "cpu", "--seed", 2, "--out", "data6", "--participant", "s6"], tmp_path)
    six = json.loads((tmp_path / "data6" / "s6_summary.json").read_text())
    assert abs(six["threshold_gamma"] - 6.0) <= 0.2 * 6.0


def test_foveation_threshold_refuses_a_display_where_foveation_changes_no_pixel(tmp_path):
    if shutil.which("xvfb-run") is None:
        pytest.skip("xvfb-run is not installed")
    pytest.importorskip("psychopy")
    command = ["xvfb-run", "-a", sys.executable, str(EXAMPLES / "foveation_threshold.py"), "--simulate", "3", "--trials", "5",
               "--size", "320x200", "--max-rays", "16", "--device", "cpu", "--out", "data"]
    result = subprocess.run(command, cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert result.returncode != 0
    assert "foveation changes no pixel" in result.stderr and "320x200" in result.stderr
    assert not (tmp_path / "data").exists()


def test_foveation_threshold_refuses_bad_options_before_any_rendering(tmp_path):
    """Each bad option is one line naming it, before the reference renders or a window opens (a bad
    size was a traceback, a missing scene surfaced after the window), and a participant's earlier
    session is never written over."""
    (tmp_path / "data").mkdir()
    earlier = tmp_path / "data" / "p1_summary.json"
    earlier.write_text('{"threshold_gamma": 3}')
    cases = [(["--size", "0x0"], "--size"), (["--size", "abc"], "--size"), (["--display", "1,2"], "--display"),
             (["--trials", "0"], "--trials"), (["--start-gamma", "20"], "--start-gamma"), (["--interval-s", "-1"], "--interval-s"),
             (["--simulate", "nan"], "--simulate"), (["--participant", "a/b"], "--participant"),
             (["--max-rays", "0"], "--max-rays"), (["--scene", str(tmp_path / "none.obj")], "--scene"),
             (["--device", "tpu"], "--device"), (["--participant", "p1"], "--participant p1: "),
             (["--out", str(earlier)], "--out")]
    for args, name in cases:
        result = subprocess.run([sys.executable, str(EXAMPLES / "foveation_threshold.py"), *args], cwd=tmp_path,
                                capture_output=True, text=True, timeout=60)
        assert result.returncode == 2, (args, result.stderr)
        assert f"error: {name}" in result.stderr.splitlines()[-1] and "Traceback" not in result.stderr, (args, result.stderr)
    assert earlier.read_text() == '{"threshold_gamma": 3}'


def _session_plot():
    pytest.importorskip("matplotlib", reason="matplotlib is not installed (scripts/python-env.sh installs it)")
    sys.path.insert(0, str(EXAMPLES))
    try:
        import session_plot
    finally:
        sys.path.remove(str(EXAMPLES))
    return session_plot


def _write_log(path, flips=120, late=(10, 50, 51), predicted=(20, 21, 22, 80, 81), refresh_hz=60.0, header=None):
    """A log as gaze_contingent.py writes it (its columns, in its order), with known late and predicted flips."""
    columns = header or ["flip", "gaze_x", "gaze_y", "sample_time_s", "fovea_x", "fovea_y", "predicted", "fovea", "fovea_converged",
                         "rays", "render_start_s", "render_ms", "library_ms", "late", "flip_time_s", "gaze_to_flip_ms", "budget_ms",
                         "width", "height", "chunks_left_behind"]
    latencies = [40.0] + [12.0 + (k * 7) % 11 for k in range(1, flips)]  # (the first flip waits for the tracker)
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns, extrasaction="ignore")
        w.writeheader()
        for k in range(flips):
            flip_t = 5.0 + k / refresh_hz
            w.writerow({"flip": k, "gaze_x": 400 + k, "gaze_y": 260 - k / 2, "sample_time_s": flip_t - latencies[k] / 1000,
                        "fovea_x": 400 + k + (30 if k in predicted else 0), "fovea_y": 260 - k / 2, "predicted": int(k in predicted),
                        "fovea": "refining", "fovea_converged": min(1.0, k / 100), "rays": 1000, "render_start_s": flip_t - 0.01,
                        "render_ms": 9.0 + (6.0 if k in late else 0.0), "library_ms": 8.0, "late": int(k in late),
                        "flip_time_s": flip_t, "gaze_to_flip_ms": latencies[k], "budget_ms": 12.0, "width": 840 if k < 60 else 756,
                        "height": 525 if k < 60 else 472, "chunks_left_behind": 0})
    return latencies


def test_a_session_log_is_drawn_with_its_figures(tmp_path):
    session_plot = _session_plot()
    from PIL import Image
    log = tmp_path / "frames.csv"
    latencies = _write_log(log)
    figures = session_plot.draw_session(session_plot.read_log(str(log)), str(tmp_path / "session.png"))
    # What the titles state, against the log's own numbers: late and predicted flips, the latency from
    # the second flip (the summary's rule), read against the refresh the flips came at
    assert figures["flips"] == 120 and figures["late"] == 3 and figures["predicted"] == 5
    assert figures["gaze_to_flip_ms_median"] == pytest.approx(float(np.median(latencies[1:])))
    assert figures["gaze_to_flip_ms_p95"] == pytest.approx(float(np.percentile(latencies[1:], 95)))
    assert figures["refresh_from"] == "flips" and figures["refresh_hz"] == pytest.approx(60.0)
    assert figures["gaze_to_flip_refreshes_median"] == pytest.approx(figures["gaze_to_flip_ms_median"] * 60 / 1000)
    given = session_plot.session_figures(session_plot.read_log(str(log)), refresh_hz=120.0)
    assert given["refresh_from"] == "given" and given["gaze_to_flip_refreshes_median"] == pytest.approx(
        figures["gaze_to_flip_ms_median"] * 120 / 1000)
    with Image.open(tmp_path / "session.png") as picture:
        assert picture.format == "PNG" and picture.size == (1000, 900)
        # the late flips' red markers are drawn (matplotlib's tab:red, #d62728), and only where some are late
        pixels = np.asarray(picture.convert("RGB")).reshape(-1, 3).astype(int)
        red = np.sum(np.all(np.abs(pixels - [214, 39, 40]) <= 12, axis=1))
    assert red > 20
    for ext, magic in ((".svg", b"<svg"), (".pdf", b"%PDF")):
        session_plot.draw_session(session_plot.read_log(str(log)), str(tmp_path / ("session" + ext)))
        assert magic in (tmp_path / ("session" + ext)).read_bytes()[:400]
    _write_log(log, late=())
    session_plot.draw_session(session_plot.read_log(str(log)), str(tmp_path / "none_late.png"))
    with Image.open(tmp_path / "none_late.png") as picture:
        pixels = np.asarray(picture.convert("RGB")).reshape(-1, 3).astype(int)
        legend_only = np.sum(np.all(np.abs(pixels - [214, 39, 40]) <= 12, axis=1))
    assert 0 < legend_only and red >= 3 * legend_only  # (three late flips' markers beside the legend's one)
    assert not list(tmp_path.glob(".session_plot.*"))  # (each written beside, then given its name)
    umask = os.umask(0)
    os.umask(umask)
    assert os.stat(tmp_path / "session.png").st_mode & 0o777 == 0o666 & ~umask  # (a file as any other, not the owner's alone)


def test_a_log_that_cannot_be_drawn_is_refused_by_name_and_line(tmp_path):
    session_plot = _session_plot()
    log = tmp_path / "frames.csv"
    _write_log(log)
    lines = log.read_text().splitlines()
    cases = {"empty.csv": ("", "the file is empty"),
             "no_flips.csv": ("flip\n", "no flips logged"),
             "header_only.csv": (lines[0] + "\n", "no flips logged"),
             "columns.csv": ("flip,gaze_x\n0,1\n", "line 1: no column 'gaze_y'"),
             "word.csv": ("\n".join(lines[:4] + [",".join(lines[4].split(",")[:8] + ["fast"] + lines[4].split(",")[9:])] + lines[5:])
                          + "\n",
                          "line 5: column 'fovea_converged': 'fast' is no number"),
             "inf.csv": ("\n".join(lines[:3] + [",".join(["inf"] + lines[3].split(",")[1:])] + lines[4:]) + "\n",
                         "line 4: column 'flip': 'inf' is not a finite number"),
             "width.csv": ("\n".join(lines[:6] + [",".join(lines[6].split(",")[:17] + ["0"] + lines[6].split(",")[18:])] + lines[7:])
                           + "\n", "line 7: column 'width': '0' is not above 0"),
             "short.csv": ("\n".join(lines[:2] + ["1,2,3"]) + "\n", "line 3: 3 values where the header names 20")}
    for name, (text, words) in cases.items():
        (tmp_path / name).write_text(text)
        with pytest.raises(session_plot.LogError) as error:
            session_plot.read_log(str(tmp_path / name))
        assert str(error.value).startswith(str(tmp_path / name) + ": ") and words in str(error.value), (name, error.value)
    # The command line: one line naming the file and what is wrong, and no picture
    script = str(EXAMPLES / "session_plot.py")
    for args, words in (([str(tmp_path / "word.csv")], "line 5: column 'fovea_converged'"),
                        ([str(tmp_path / "none.csv")], "none.csv: no such file"),
                        ([str(tmp_path), "-o", str(tmp_path / "d.png")], "is a folder; give a session's log"),
                        ([str(log), "-o", str(tmp_path / "s.txt")], "--output: "),
                        ([str(log), "-o", str(tmp_path / "missing" / "s.png")], "does not exist"),
                        ([str(log), "--refresh-hz", "0"], "--refresh-hz"),
                        ([str(log), "-o", str(log)], "--output: ")):
        result = subprocess.run([sys.executable, script, *args], cwd=tmp_path, capture_output=True, text=True, timeout=120)
        assert result.returncode == 2 and words in result.stderr.splitlines()[-1], (args, result.stderr)
        assert "Traceback" not in result.stderr
    assert not (tmp_path / "word.png").exists() and not (tmp_path / "frames.png").exists()
    # A log whose name is a picture's is an input: never drawn over
    picture_log = tmp_path / "frames.png"
    picture_log.write_text(log.read_text())
    result = subprocess.run([sys.executable, script, str(picture_log)], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert result.returncode == 2 and "an input; it is never written over" in result.stderr
    assert picture_log.read_text() == log.read_text()
    # A read-only picture is kept; a failed session's LOG.partial is drawn, by default beside it
    locked = tmp_path / "locked.png"
    locked.write_bytes(b"kept")
    locked.chmod(0o444)
    result = subprocess.run([sys.executable, script, str(log), "-o", str(locked)], cwd=tmp_path, capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 2 and "is read-only" in result.stderr and locked.read_bytes() == b"kept"
    partial = tmp_path / "run.csv.partial"
    partial.write_text(log.read_text())
    result = subprocess.run([sys.executable, script, str(partial)], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0 and (tmp_path / "run.csv.png").exists(), result.stderr
    assert "120 flips, 3 late" in result.stdout
