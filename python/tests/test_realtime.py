"""foveal.Loop: frames within the budget, the fovea refined and converged, the saccade predictor fed
sample by sample, the GIL released while rendering, and clear errors."""
import json
import math
import os
import subprocess
import sys
import threading
import time
import warnings

import numpy as np
import pytest

import foveal
from conftest import shared


@pytest.fixture(scope="module")
def box():
    return foveal.Scene("builtin:box")


def test_a_still_gaze_converges_the_fovea_within_budget(box):
    loop = foveal.Loop(box, size=(320, 200), max_rays=400, refresh_hz=60, device="cpu", predict=False)
    assert loop.size == [320, 200] and loop.scale == 1.0 and loop.note == ""
    assert loop.budget_ms == pytest.approx(1000 / 60)
    frames = [loop.frame(gaze=(160, 100), t=k / 60) for k in range(60)]
    first, last = frames[0], frames[-1]
    assert first.image.shape == (200, 320, 3) and first.image.dtype == np.float32
    assert first.fovea == "refining" and first.fovea_converged < 1
    assert last.fovea == "converged" and last.fovea_converged == 1.0
    assert all(f.fovea in ("refining", "converged") for f in frames)
    assert tuple(last.gaze) == pytest.approx((160, 100)) and not last.predicted
    # The loop renders within its budget (the machine may be busy: most frames, not every one)
    assert sum(f.ms <= f.budget_ms + 1 for f in frames) >= 0.8 * len(frames)
    # The image changes as rays arrive
    assert not np.array_equal(first.image, last.image)
    # A frame that left chunks to a paused thread is followed by one that says when they ended
    for before, after in zip(frames, frames[1:]):
        assert (before.chunks_left_behind > 0) == (not np.isnan(after.left_behind_ms))
    # The estimate of the pixels without rays has room in these frames (it waits only where a frame
    # has none before its deadline: the machine may pause one)
    assert all(isinstance(f.estimate_deferred, bool) for f in frames)
    assert sum(f.estimate_deferred for f in frames) <= 0.2 * len(frames)


def test_a_converged_views_spare_time_casts_rays_ahead_of_the_gaze(box):
    """rays_ahead (the default): once every pixel has its n(E), frames go on tracing, every pixel on to n_max, then
    stop; False: a converged view casts nothing."""
    ahead = foveal.Loop(box, size=(84, 52), max_rays=64, device="cpu", predict=False)
    plain = foveal.Loop(box, size=(84, 52), max_rays=64, device="cpu", predict=False, rays_ahead=False)
    assert ahead.rays_ahead is True and plain.rays_ahead is False
    rays = {"ahead": [], "plain": []}
    for k in range(400):
        rays["ahead"].append(ahead.frame(gaze=(20, 15), t=k / 60).rays)
        rays["plain"].append(plain.frame(gaze=(20, 15), t=k / 60).rays)
    # Both finish: the last frames trace nothing
    assert rays["ahead"][-20:] == [0] * 20 and rays["plain"][-20:] == [0] * 20
    # With them every pixel that sees a surface went on to n_max = 64; without, the periphery stopped at its n(E)
    assert sum(rays["ahead"]) > sum(rays["plain"]) * 1.2
    with pytest.raises(TypeError):
        foveal.Loop(box, size=(84, 52), rays_ahead="no")


def test_a_saccade_pushed_sample_by_sample_is_predicted(box):
    loop = foveal.Loop(box, size=(200, 125), max_rays=32, device="cpu", predict=True)
    # 1000 Hz samples: a fixation, a saccade across the screen (a smooth bell of velocity), a fixation
    start, end, onset, duration = np.array([20.0, 60.0]), np.array([180.0, 70.0]), 0.2, 0.065
    predicted = []
    for k in range(600):
        t = k / 1000
        tau = np.clip((t - onset) / duration, 0, 1)
        loop.push(t, tuple(start + (end - start) * (tau - np.sin(2 * np.pi * tau) / (2 * np.pi))))
        if k % 8 == 0:
            f = loop.frame()
            if f.predicted:
                predicted.append((t, f.gaze))
    assert predicted, "no frame placed the fovea at a predicted landing"
    assert all(onset <= t <= onset + duration + 0.01 for t, _ in predicted)
    assert predicted[-1][1][0] > 120  # towards the landing, ahead of the eye
    f = loop.frame()
    assert not f.predicted and tuple(f.gaze) == pytest.approx(tuple(end))  # landed: the measured gaze again


def test_a_moving_camera_keeps_the_ao_it_still_sees(box):
    def orbit(keep_history):
        loop = foveal.Loop(box, size=(160, 100), max_rays=64, device="cpu", frame_budget_ms=40, keep_history=keep_history)
        first = loop.frame(gaze=(80, 50), t=0)
        for k in range(30):
            f = loop.frame(gaze=(80, 50), t=(k + 1) / 60)
            if f.fovea == "converged":
                break
        assert f.fovea == "converged"
        camera = box.cameras[0]  # the loop's view: the scene's first camera
        moved = [loop.frame(gaze=(80, 50), t=1 + k / 60, camera=camera.orbit(0.5 * k)) for k in range(1, 4)]
        return first, moved

    _, kept = orbit(True)
    assert all(f.new_view for f in kept)
    assert all(f.kept_pixels > 0 for f in kept) and kept[-1].fovea_converged > 0.9
    _, fresh = orbit(False)
    assert all(f.kept_pixels == 0 for f in fresh)  # (how soon a fresh fovea converges depends on the machine)
    with pytest.raises(ValueError, match="camera"):
        foveal.Loop(box, size=(16, 10), max_rays=4, device="cpu").frame(camera="no such camera")


def test_a_resting_camera_gets_its_size_back_over_several_frames():
    # The sphere over the plane at 1280x800 with a 10 ms budget: an orbiting camera renders smaller,
    # and at rest the full size is built over several frames, the smaller image shown meanwhile
    scene = foveal.Scene("builtin:sphere-plane")
    loop = foveal.Loop(scene, size=(1280, 800), max_rays=16, device="cpu", frame_budget_ms=10)
    camera = scene.cameras[0]
    frames = [loop.frame(gaze=(640, 400), t=k / 100, camera=camera.orbit(0.5 * k)) for k in range(9)]
    if frames[-1].image.shape[1] == 1280:
        pytest.skip("this machine traces 1280x800 surfaces within the 10 ms budget: nothing to lower")
    assert not any(f.rebuilding for f in frames)  # a moving camera builds no full size
    loop.budget_ms = 40  # (a budget the smaller view leaves time in, as in the C++ test)
    rest = camera.orbit(4)
    shown = []
    for k in range(400):
        f = loop.frame(gaze=(640, 400), t=1 + k / 25, camera=rest)
        shown.append((f.rebuilding, f.image.shape[1], f.new_view))
        if f.image.shape[1] == 1280:
            break
    building = [w for r, w, _ in shown if r]
    assert len(building) > 1 and all(w < 1280 for w in building)  # several frames, the smaller image shown
    assert shown[-1][1] == 1280 and shown[-1][2]  # then the full size, as a new view
    assert 500 <= 40 * shown.index(next(s for s in shown if s[0]))  # after half a second at rest


def test_a_still_view_made_smaller_is_the_larger_one_sampled(box):
    # A budget its fixed part does not fit lowers a still view's size from the view at hand: no
    # surface traced, each smaller pixel one of the larger pixels nearest it, with its rays so far
    loop = foveal.Loop(box, size=(320, 200), max_rays=64, device="cpu", predict=False)
    frame = None
    for k in range(30):
        frame = loop.frame(gaze=(160, 100), t=k / 60)
    assert not frame.lowered and frame.image.shape == (200, 320, 3)
    loop.budget_ms = 0.05  # (less than composing alone takes)
    for k in range(30):
        before, frame = frame, loop.frame(gaze=(160, 100), t=(30 + k) / 60)
        if frame.image.shape[1] < 320:
            break
    assert frame.lowered and frame.new_view and frame.kept_pixels > 0
    assert "frame budget" in loop.note
    h, w = frame.image.shape[:2]
    assert (w, h) == tuple(loop.size) and w < 320
    assert before.scale == 1 and frame.scale == loop.scale < 1 and round(320 * frame.scale) == w
    # each smaller pixel's colour is one of the larger pixels' whose nearest smaller pixel it is
    ys = ((np.arange(200) + 0.5) * h / 200).astype(int)
    xs = ((np.arange(320) + 0.5) * w / 320).astype(int)
    diff = np.abs(frame.image[ys][:, xs] - before.image).max(axis=2)  # each larger pixel against its smaller one
    nearest = np.full((h, w), np.inf)
    np.minimum.at(nearest, (ys[:, None].repeat(320, axis=1), xs[None, :].repeat(200, axis=0)), diff)
    same = nearest < 1e-5
    assert same.mean() > 0.9, same.mean()
    after = loop.frame(gaze=(160, 100), t=1.0)  # (the next frame goes on at that size, nothing traced)
    assert not after.lowered and not after.new_view and after.image.shape == frame.image.shape


def test_frames_release_the_gil(box):
    loop = foveal.Loop(box, size=(320, 200), max_rays=400, device="cpu", frame_budget_ms=40)
    ticks = []
    stop = threading.Event()

    def tick():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    thread = threading.Thread(target=tick)
    thread.start()
    for k in range(5):
        loop.frame(gaze=(100 + 20 * k, 100), t=k)
    stop.set()
    thread.join()
    assert len(ticks) > 50  # ~200 ms of frames: the other thread ran meanwhile


def test_an_image_held_is_never_composed_into(box):
    """A frame's buffer goes back to the loop once neither the frame nor a view of its image is held:
    an image still viewed keeps what it showed while later frames are made, whether its frame is held
    or only the view; the loop goes on with buffers handed back and with new ones."""
    loop = foveal.Loop(box, size=(160, 100), max_rays=400, device="cpu", predict=False)
    kept_frame = loop.frame(gaze=(40, 50), t=0.0)
    view_only = loop.frame(gaze=(120, 50), t=0.1).image  # its frame released, the view held
    kept = np.array(kept_frame.image)
    viewed = np.array(view_only)
    for k in range(12):  # frames released as they come: their buffers go back to the loop
        f = loop.frame(gaze=(40 + 8 * k, 50), t=0.2 + 0.1 * k)
        assert f.image.shape == (100, 160, 3) and np.isfinite(f.image).all()
        del f
    assert np.array_equal(kept_frame.image, kept)
    assert np.array_equal(view_only, viewed)
    assert not np.array_equal(kept, viewed)  # (two frames of different gazes, so each check could fail)
    # Frames outliving their loop keep their images too
    last = loop.frame(gaze=(80, 50), t=2.0)
    shown = np.array(last.image)
    del loop
    assert np.array_equal(last.image, shown)


def test_bad_arguments_are_clear_errors(box):
    with pytest.raises(ValueError, match="refresh_hz"):
        foveal.Loop(box, refresh_hz=0)
    with pytest.raises(ValueError, match="frame_budget_ms"):
        foveal.Loop(box, frame_budget_ms=-1)
    with pytest.raises(ValueError, match="clock"):
        foveal.Loop(box, clock="model")
    with pytest.raises(ValueError, match="size"):
        foveal.Loop(box, size=(0, 10))
    with pytest.raises(ValueError, match=r"periphery_share: must be in \(0, 1\]"):
        foveal.Loop(box, size=(64, 40), periphery_share=0)
    with pytest.raises(ValueError, match=r"min_scale: must be in \(0, 1\]"):
        foveal.Loop(box, size=(64, 40), min_scale=0)
    for bad in (-1.0, 16.7, float("nan")):
        with pytest.raises(ValueError, match=r"margin_ms: must be in \[0, the frame budget 16.6667 ms\)"):
            foveal.Loop(box, size=(64, 40), margin_ms=bad)
    kept = foveal.Loop(box, size=(64, 40), max_rays=8, device="cpu", margin_ms=5, periphery_share=0.6)
    assert (kept.margin_ms, kept.periphery_share) == (5.0, 0.6)
    kept.budget_ms = 8  # a margin given, within half of a shorter budget
    assert kept.margin_ms == 4.0
    kept.budget_ms = 16  # … and again as given once the budget allows it
    assert kept.margin_ms == 5.0
    loop = foveal.Loop(box, size=(64, 40), max_rays=8, device="cpu")
    assert (loop.margin_ms, loop.periphery_share, loop.min_scale) == (2.0, 1.0, 0.25)  # the loop's defaults
    # A stimulus that keeps its resolution (min_scale=1): a budget no base shading fits leaves the
    # size as asked, its frames late, and the note says why
    held = foveal.Loop(box, size=(64, 40), max_rays=8, device="cpu", frame_budget_ms=0.001, min_scale=1)
    frames = [held.frame((32, 20), t=k / 60) for k in range(8)]
    assert held.min_scale == 1.0 and all(f.image.shape[:2] == (40, 64) and f.late for f in frames)
    assert "(min_scale): frames come late" in held.note, held.note
    del frames
    with pytest.raises(ValueError, match="t: must be a finite"):
        loop.push(float("nan"), (1, 2))
    loop.push(1.0, None)  # a lost sample is fine, and so is NaN
    loop.push(1.5, (float("nan"), float("nan")))
    with pytest.raises(ValueError, match="gaze: .*NaN marks a lost sample"):  # an infinity is no lost sample
        loop.push(2.0, (float("inf"), 3))
    assert loop.frame().image.shape == (40, 64, 3)
    for bad in (0.0, -1.0, float("nan"), 1e300):  # the attribute's own name, and the budget kept
        with pytest.raises(ValueError, match=r"budget_ms: must be in \(0, 10000\] ms") as caught:
            loop.budget_ms = bad
        assert "frame_budget_ms" not in str(caught.value)
        assert loop.budget_ms == pytest.approx(1000 / 60)
    for camera in (3, [1, 2], object()):  # a camera of the wrong type: named, not a bare std::bad_cast
        with pytest.raises(TypeError, match="camera: a camera name"):
            foveal.Loop(box, size=(64, 40), camera=camera)
        with pytest.raises(TypeError, match="camera: a camera name"):
            loop.frame(camera=camera)
    with pytest.raises(TypeError, match="camera: a camera name"):
        foveal.Renderer(box, device="cpu").render(size=(16, 10), camera=3)


def test_a_gaze_or_fixation_far_from_the_image_is_refused(box):
    """Issue 36, findings 6 and 7: one rule for every gaze point (finite, near the image)."""
    with pytest.raises(ValueError, match="gaze"):
        foveal.Renderer(box, device="cpu").render(size=(64, 40), gaze=(1e155, 1e155), max_rays=4)
    loop = foveal.Loop(box, size=(64, 40), max_rays=8, device="cpu")
    with pytest.raises(ValueError, match="gaze"):
        loop.push(1.0, (1e155, 1e155))
    sim = foveal.VisionSimulation(box, size=(64, 48), device="cpu")
    for fixation in [(float("nan"), float("nan")), (1e200, 1e200)]:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # the refusal alone: no "far periphery" warning before it
            with pytest.raises(ValueError, match="fixation"):
                sim.step(fixation=fixation)
    with pytest.warns(UserWarning, match="fixation: .* off the frame: the whole image is far periphery"):
        sim.step(fixation=(300, 20))  # off the frame, yet near enough: taken, with a word
    assert sim.step(fixation=(30, 20)).fixation == pytest.approx((30, 20))


def test_stalls_probe_the_machine_as_bench_stalls_does():
    r = foveal.stalls(duration_s=0.3, threads=2)
    assert r["threads"] == 2 and r["duration_s"] >= 0.25 and r["chunks"] > 100
    assert r["margin_ms"] == 2.0 and r["threshold_ms"] == 1.0
    for kind in ("off_cpu", "on_cpu"):
        assert set(r[kind]) == {"count", "per_minute", "worst_ms", "beyond_margin"}
    assert len(r["stalls"]) == r["off_cpu"]["count"] + r["on_cpu"]["count"]
    for s in r["stalls"]:
        assert s["wall_ms"] >= 1.0 and s["on_cpu"] == (s["cpu_ms"] >= 0.5 * s["wall_ms"])
    # what else ran meanwhile: other processes, the busiest first
    assert len(r["others"]) <= 5
    assert all(set(o) == {"pid", "name", "kernel", "cpu_ms", "slices"} and o["cpu_ms"] > 0 for o in r["others"])
    assert all(o["pid"] != os.getpid() for o in r["others"])
    assert set(r["kernel"]) == {"release", "hz", "preempt", "source"}
    assert r["kernel"]["release"] == os.uname().release  # the tick where the kernel's config states it
    assert r["kernel"]["hz"] is None or (isinstance(r["kernel"]["hz"], int) and r["kernel"]["hz"] >= 24)
    assert [o["cpu_ms"] for o in r["others"]] == sorted((o["cpu_ms"] for o in r["others"]), reverse=True)
    with pytest.raises(ValueError, match="duration_s"):
        foveal.stalls(duration_s=0)
    with pytest.raises(ValueError, match="margin_ms"):
        foveal.stalls(duration_s=0.1, margin_ms=-1)


def _two_saccades(path):
    """500 Hz t,x,y: the eye jumps 800 px right at 0.4 s and back at 1.0 s (65 ms saccades)."""
    t = np.arange(800) / 500.0

    def bell(tau):
        tau = np.clip(tau, 0, 1)
        return tau - np.sin(2 * np.pi * tau) / (2 * np.pi)
    x = 400 + 800 * bell((t - 0.4) / 0.065) - 800 * bell((t - 1.0) / 0.065) + 0.3 * (np.arange(800) % 3)
    y = 520 + 0.2 * (np.arange(800) % 2)
    with open(path, "w") as f:
        f.write("t,x,y\n")
        for row in zip(t, x, y):
            f.write("%.6f,%.6f,%.6f\n" % row)


def test_bench_latency_from_python_equals_the_command_lines(cli, box, tmp_path):
    """foveal.bench_latency: bench latency's figures, under a given cost model the same as the command line's."""
    from conftest import run_cli
    recording = tmp_path / "saccades.csv"
    _two_saccades(recording)
    model = ["--clock", "model", "--model-rays-per-ms", "2000", "--model-fixed-ms", "3"]
    run_cli(cli, "bench", "latency", "--scene", "builtin:box", "--size", "168x105", "--max-rays", "64", "--recording", recording,
            "--duration", "1.5", *model, "--min-amplitude", "5", "--loops", "deadline,deadline+prediction", "--json",
            tmp_path / "cli.json")
    import json
    expected = json.loads((tmp_path / "cli.json").read_text())
    got = foveal.bench_latency(str(recording), box, size=(168, 105), max_rays=64, duration_s=1.5, clock="model",
                               model_rays_per_ms=2000, model_fixed_ms=3, min_amplitude_deg=5,
                               loops=("deadline", "deadline+prediction"), timeline=tmp_path / "timeline.svg")
    assert "| deadline+prediction |" in got["markdown"] and (tmp_path / "timeline.svg").exists()
    # The picture's note, as the command line prints it: '' where the drawn saccade (the first) shows a wait
    assert got["recordings"][0]["deadline"]["saccades"][0]["landing_to_converged_ms"] > 0
    assert got["timeline_note"] == ""
    # The second saccade's fovea was ready at its landing in both loops (the first waited 17 ms): named
    second = foveal.bench_latency(str(recording), box, size=(168, 105), max_rays=64, duration_s=1.5, clock="model",
                                  model_rays_per_ms=2000, model_fixed_ms=3, min_amplitude_deg=5,
                                  loops=("deadline", "deadline+prediction"), timeline=tmp_path / "second.svg", timeline_saccade=1)
    assert [s["landing_to_converged_ms"] for s in second["recordings"][0]["deadline"]["saccades"]][1] == 0
    assert second["timeline_note"].endswith("the deadline loop waited longest for saccade 0 (17 ms): timeline_saccade=0")
    past = foveal.bench_latency(str(recording), box, size=(168, 105), max_rays=64, duration_s=1.5, clock="model",
                                model_rays_per_ms=2000, model_fixed_ms=3, min_amplitude_deg=5, loops="deadline",
                                timeline=tmp_path / "past.svg", timeline_saccade=9)
    assert past["timeline_note"].startswith("saccade 9 was asked for, and ") and "judged 2 (0–1): the last is drawn" in past["timeline_note"]
    assert got["clock"] == "model" and got["size"] == [168, 105]
    a, b = got["recordings"][0], expected["recordings"][0]
    assert a["recording"] == b["recording"] and a["tracker_latency_ms"] == b["tracker_latency_ms"]
    assert a["segment_s"] == b["segment_s"] == [0, 1.5] and a["segment_cut"] is False
    for loop in ("deadline", "deadline+prediction"):
        strip = lambda saccades: [{k: v for k, v in s.items() if k != "ray_bound_ms"} for s in saccades]  # noqa: E731 (measured)
        assert strip(a[loop]["saccades"]) == strip(b[loop]["saccades"]), loop
        assert a[loop]["timeline"] == b[loop]["timeline"], loop
        # Each frame's own account: rays, size, the fovea's converged share (the model clock times no part)
        frame = a[loop]["timeline"][-1]
        assert frame["scale"] == 1 and 0 <= frame["fovea_converged"] <= 1
        assert frame["maps_ms"] is None and frame["plan_ms"] is None and frame["trace_ms"] is None and frame["compose_ms"] is None
        assert sum(f["rays"] for f in a[loop]["timeline"]) > 0 and sum(f["sweeps"] for f in a[loop]["timeline"]) > 0
        assert len(a[loop]["saccades"]) == 2 and a[loop]["frames_late"] == 0
        assert a[loop]["frames_left_behind"] == a[loop]["late_had_they_waited"] == 0  # (the model clock waits for every chunk)
        # (every frame at the full size: none left unjudged)
        assert a[loop]["frames_lowered"] == a[loop]["frames_not_judged"] == 0
    # A fixed part past the budget: frames at a lowered size, taken from the view at full size, counted
    # and judged on the pixels they show (docs/realtime.md)
    lowered = foveal.bench_latency(str(recording), box, size=(168, 105), max_rays=64, duration_s=1.5, clock="model",
                                   model_rays_per_ms=2000, model_fixed_ms=30, min_amplitude_deg=5, loops="deadline")
    low = lowered["recordings"][0]["deadline"]
    assert low["frames_lowered"] == sum(f["scale"] < 1 for f in low["timeline"]) > 0 and low["frames_not_judged"] == 0
    assert all(f["fovea_error"] is not None for f in low["timeline"])
    assert all(s["frames_not_judged"] == 0 for s in low["saccades"]) and "Frames at a lowered size" in lowered["markdown"]
    assert any(s["landing_to_converged_ms"] is not None for s in low["saccades"])
    # A Recording object does as well as its path; bad arguments are named
    again = foveal.bench_latency(foveal.gaze.read(str(recording)), box, size=(168, 105), max_rays=64, duration_s=1.5,
                                 clock="model", model_rays_per_ms=2000, model_fixed_ms=3, min_amplitude_deg=5, loops="deadline")
    assert again["recordings"][0]["deadline"]["timeline"] == a["deadline"]["timeline"]
    # A segment asked past the recording's end (1.598 s) ends there, and says so
    longer = foveal.bench_latency(str(recording), box, size=(168, 105), max_rays=64, duration_s=5, clock="model",
                                  model_rays_per_ms=2000, model_fixed_ms=3, loops="deadline")
    r = longer["recordings"][0]
    assert r["segment_cut"] is True and r["segment_s"] == [0, pytest.approx(1.598)]
    assert r["deadline"]["frames"] <= 97 and ", where the recording ends (5 s asked for from 0 s)" in longer["markdown"]
    with pytest.raises(ValueError, match="loops"):
        foveal.bench_latency(str(recording), box, size=(168, 105), loops=("sometimes",))
    with pytest.raises(TypeError, match=r"recordings\[0\]"):
        foveal.bench_latency([3], box)
    with pytest.raises(ValueError, match="timeline"):
        foveal.bench_latency(str(recording), box, size=(168, 105), loops="deadline", timeline=tmp_path / "t.gif")
    # Errors name the keywords given: a run of no loop, the tracker's latency, a recording that is no list
    with pytest.raises(ValueError, match="loops: give at least one"):
        foveal.bench_latency(str(recording), box, size=(168, 105), loops=[])
    with pytest.raises(ValueError, match=r"^latency_ms: must be in \[0, 1000\) ms, got -1"):
        foveal.bench_latency(str(recording), box, size=(168, 105), latency_ms=-1)
    with pytest.raises(ValueError, match=r"margin_ms: must be in \[0, the frame budget 16.6667 ms\)"):
        foveal.bench_latency(str(recording), box, size=(168, 105), margin_ms=100)
    with pytest.raises(ValueError, match=r"^periphery_share: must be in \(0, 1\]"):
        foveal.bench_latency(str(recording), box, size=(168, 105), periphery_share=1.5)
    with pytest.raises(ValueError, match=r"^min_scale: must be in \(0, 1\]"):
        foveal.bench_latency(str(recording), box, size=(168, 105), min_scale=1.5)
    with pytest.raises(TypeError, match="recordings: a path, a foveal.gaze.Recording or a list of them, got int"):
        foveal.bench_latency(5, box)


def test_what_else_ran_on_the_machine_is_named():
    """A child process that spins for 0.2 s of CPU time is found since the snapshot, with that time; this one is not."""
    import subprocess
    import sys
    snapshot = foveal.machine_snapshot()
    if len(snapshot) == 0:
        pytest.skip("no /proc here")
    child = subprocess.Popen([sys.executable, "-c",
                              "import time, sys\nt = time.process_time()\nwhile time.process_time() - t < 0.2: pass\n"
                              "sys.stdout.write('spun\\n'); sys.stdout.flush(); time.sleep(30)"], stdout=subprocess.PIPE, text=True)
    try:
        assert child.stdout.readline().strip() == "spun"
        others = foveal.busiest_others(snapshot, most=1000)
    finally:
        child.kill()
        child.wait()
    found = [o for o in others if o["pid"] == child.pid]
    assert len(found) == 1 and found[0]["cpu_ms"] >= 150 and not found[0]["kernel"]
    assert all(o["pid"] != os.getpid() for o in others)
    assert len(foveal.busiest_others(snapshot, most=2)) <= 2
    with pytest.raises(ValueError, match="most"):
        foveal.busiest_others(snapshot, most=0)


def test_the_paced_loop_script_reports_every_frame(tmp_path):
    # bench/paced_loop.py: a frame at each refresh of the wall clock, then a wait (BENCHMARKS.md)
    recording = shared("gaze", "eyelink", "monoRemote500.asc")
    script = os.path.join(os.path.dirname(__file__), "..", "..", "bench", "paced_loop.py")
    out = tmp_path / "paced.json"
    run = subprocess.run([sys.executable, script, "--recording", str(recording), "--scene", "builtin:box", "--size", "64x40",
                          "--duration", "0.5", "--max-rays", "16", "--json", str(out)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    figures = json.loads(out.read_text())
    assert figures["frames"] == 30 and figures["budget_ms"] == pytest.approx(1000 / 60)
    assert 0 <= figures["frames_late"] <= 30 and figures["frame_ms_p50"] > 0
    assert "30 frames at 60 Hz" in run.stdout and figures["device"].startswith("cpu")
    assert figures["rays_per_frame"] >= 0 and "AO rays a frame" in run.stdout
    # --frame-budget-ms: what an experiment's own drawing leaves the loop of each refresh
    short = subprocess.run([sys.executable, script, "--recording", str(recording), "--scene", "builtin:box", "--size", "64x40",
                            "--duration", "0.2", "--max-rays", "16", "--frame-budget-ms", "8", "--json", str(tmp_path / "short.json")],
                           capture_output=True, text=True, timeout=120)
    assert short.returncode == 0, short.stderr
    assert json.loads((tmp_path / "short.json").read_text())["budget_ms"] == pytest.approx(8)
    # --device: what foveal.Loop takes, an unknown one refused by name before any frame
    unknown = subprocess.run([sys.executable, script, "--recording", str(recording), "--device", "gpu"], capture_output=True, text=True)
    assert unknown.returncode != 0 and "--device" in unknown.stderr and "unknown device 'gpu'" in unknown.stderr
    bad = subprocess.run([sys.executable, script, "--recording", str(recording), "--start", "1e6"], capture_output=True, text=True)
    assert bad.returncode != 0 and "--start" in bad.stderr and "past the recording's end" in bad.stderr
    # Each refusal names the option that set it (a bad size was said to be --device's), in one line, no traceback
    for args, said in ((["--size", "0x0"], "--size: width and height must be in 1..16384"),
                       (["--max-rays", "-1"], "--max-rays: must be in [0, 65535]"),
                       (["--frame-budget-ms", "0"], "--frame-budget-ms: must be in (0, 10000] ms"),
                       (["--scene", str(tmp_path / "none.obj")], "--scene: "),
                       (["--scene", script], "--scene: "), (["--recording", script], "--recording: ")):
        bad = subprocess.run([sys.executable, script, "--recording", str(recording)] + args, capture_output=True, text=True)
        assert bad.returncode == 2 and said in bad.stderr and "Traceback" not in bad.stderr, (args, bad.stderr)
    # Its output is checked before any frame, as foveal's commands check theirs
    locked = tmp_path / "locked.json"
    locked.write_text("kept")
    locked.chmod(0o444)
    refused = subprocess.run([sys.executable, script, "--recording", str(recording), "--json", str(locked)], capture_output=True,
                             text=True)
    assert refused.returncode != 0 and "--json" in refused.stderr and "is read-only" in refused.stderr
    assert locked.read_text() == "kept"
    locked.chmod(0o644)


def test_the_segments_script_pools_every_judged_saccade(tmp_path):
    # bench/latency_segments.py: bench latency on consecutive segments, each a fresh loop, pooled
    recording = shared("eye-movements", "irf", "lookAtPoint_EL_S1.csv")
    script = os.path.join(os.path.dirname(__file__), "..", "..", "bench", "latency_segments.py")
    out = tmp_path / "segments.json"
    args = [sys.executable, script, "--recording", str(recording), "--scene", "builtin:box", "--size", "64x40", "--segment", "3",
            "--count", "2", "--model-rays-per-ms", "2000", "--model-fixed-ms", "3", "--json", str(out)]
    run = subprocess.run(args, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    pooled = json.loads(out.read_text())["recordings"][0]
    assert pooled["segments"] == 2
    # Every judged saccade of both segments, the same ones in each loop
    per_segment = [foveal.bench_latency([str(recording)], foveal.Scene("builtin:box"), size=(64, 40), start_s=start, duration_s=3,
                                        clock="model", model_rays_per_ms=2000, model_fixed_ms=3,
                                        loops=("deadline", "deadline+prediction"))["recordings"][0] for start in (2, 5)]
    judged = [s["landing_to_converged_ms"] for seg in per_segment for s in seg["deadline"]["saccades"]]
    assert [s["landing_to_converged_ms"] for s in pooled["saccade_list"]["deadline"]] == judged
    assert pooled["saccades"] == len(judged) > 0
    gain = pooled["gain_ms"]["deadline+prediction"]
    medians = pooled["median_landing_to_converged_ms"]
    assert gain == pytest.approx(medians["deadline"] - medians["deadline+prediction"])
    low, high = pooled["gain_interval_ms"]["deadline+prediction"]  # (the segments resampled: bootstrap_gain's test below)
    assert low <= high and "(95 %: " in run.stdout
    assert "lookAtPoint_EL_S1.csv (2, " in run.stdout
    bad = subprocess.run([sys.executable, script, "--recording", str(recording), "--loops", "deadline+prediction"],
                         capture_output=True, text=True)
    assert bad.returncode != 0 and "--loops" in bad.stderr
    # --landing: the prediction loops' predictor parameters, checked before any work and kept in the JSON
    bad = subprocess.run([sys.executable, script, "--recording", str(recording), "--landing", "speed=1"], capture_output=True, text=True)
    assert bad.returncode != 0 and "--landing: speed: no parameter of the landing predictor" in bad.stderr
    # Each refusal names its option in one line, no traceback (the library's keyword was shown, with one)
    for args, said in ((["--size", "0x0"], "--size: width and height must be in 1..16384"),
                       (["--model-rays-per-ms", "-1"], "--model-rays-per-ms: must be > 0"),
                       (["--count", "-1"], "--count: must be 0"), (["--scene", script], "--scene: "),
                       (["--periphery-share", "2"], "--periphery-share: must be in (0, 1]"),
                       (["--recording", script], "--recording: ")):
        bad = subprocess.run([sys.executable, script, "--recording", str(recording), "--segment", "1", "--count", "1"] + args,
                             capture_output=True, text=True, timeout=120)
        assert bad.returncode == 2 and said in bad.stderr and "Traceback" not in bad.stderr, (args, bad.stderr)
    assert json.loads(out.read_text())["landing"] == foveal.gaze.landing_params()
    # Two outputs into one file (the Markdown would have replaced the JSON): refused before any work
    both = tmp_path / "both.txt"
    bad = subprocess.run([sys.executable, script, "--recording", str(recording), "--json", str(both), "--markdown",
                          str(tmp_path / "." / "both.txt")], capture_output=True, text=True, timeout=60)
    assert bad.returncode != 0 and "two outputs into one file" in bad.stderr and not both.exists()


def test_the_segments_scripts_interval_resamples_whole_segments():
    # bench/latency_segments.py's 95 % interval of the gain in the median: a cluster bootstrap over segments
    sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "bench"))
    try:
        import latency_segments
    finally:
        sys.path.pop(0)
    gain = latency_segments.bootstrap_gain
    rng = np.random.default_rng(5)
    base = list(rng.choice([0.0, 50.0, 400.0, 900.0], 60))
    segment_of = [k // 10 for k in range(60)]
    # The same loop gains nothing, in every resample; a loop 30 ms sooner at every landing, exactly 30
    assert gain(base, base, segment_of) == [0.0, 0.0]
    assert gain(base, [b - 30 for b in base], segment_of) == pytest.approx([30, 30])
    # Reproducible (a fixed seed), and wider where the gain differs from segment to segment
    mixed = [b - (120 if k // 10 % 2 else 0) for k, b in enumerate(base)]
    assert gain(base, mixed, segment_of) == gain(base, mixed, segment_of)
    low, high = gain(base, mixed, segment_of)
    assert low < high and low >= 0 and high <= 120
    # Whole segments are drawn: two that trade places between the loops have the same pooled median (no
    # gain), but a resample of one of them twice gains or loses all of it
    assert gain([0, 0, 500, 500], [500, 500, 0, 0], [0, 0, 1, 1]) == [-500, 500]
    assert gain([0, 500], [0, 500], [0, 1]) == [0.0, 0.0]
    # A landing never converged (None) counts as the longest; one never converged in one loop only is an unbounded gain
    assert gain([None, None, None], [None, None, None], [0, 1, 2]) == [0.0, 0.0]
    assert gain([None, None, None], [10, 10, 10], [0, 1, 2]) == [math.inf, math.inf]
    assert latency_segments.interval_text([-12.4, math.inf]) == " (95 %: −12 to ∞)"
    assert gain([], [], []) is None


def _min_jerk(t, t0, duration, amplitude):
    """Position along a minimum-jerk saccade of `amplitude` degrees from t0 (a smooth main-sequence-like profile)."""
    tau = np.clip((np.asarray(t) - t0) / duration, 0, 1)
    return amplitude * (10 * tau ** 3 - 15 * tau ** 4 + 6 * tau ** 5)


def test_the_loop_takes_the_landing_predictors_parameters(box):
    # Loop(landing=…): the same predictor's parameters; an onset threshold above the saccade's velocity predicts nothing
    def predicted_frames(**kw):
        loop = foveal.Loop(box, size=(320, 200), max_rays=16, refresh_hz=60, device="cpu", **kw)
        count = 0
        for k in range(400):  # 1000 Hz: a fixation, a 120-px saccade (a smooth bell of velocity), a fixation
            t = k / 1000
            tau = min(max((t - 0.1) / 0.06, 0), 1)
            loop.push(t, (60 + 120 * (tau - np.sin(2 * np.pi * tau) / (2 * np.pi)), 100))
            if k % 8 == 0:
                count += loop.frame().predicted
        return count
    assert predicted_frames() > 0
    assert predicted_frames(landing={"onset_deg_s": 999, "offset_deg_s": 30}) == 0
    assert predicted_frames(landing="onset_deg_s=999, offset_deg_s=30") == 0  # or the text of --landing
    # bench_latency takes them too, and its report says which it used
    report = foveal.bench_latency(shared("gaze", "eyelink", "monoRemote500.asc"), box, size=(64, 40), duration_s=0.5,
                                  loops=("deadline+prediction",), clock="model", model_rays_per_ms=2000, model_fixed_ms=3,
                                  landing={"onset_deg_s": 55})
    assert report["landing"]["onset_deg_s"] == 55 and report["landing"]["skew_per_deg"] == pytest.approx(0.03)
    with pytest.raises(ValueError, match="speed: no parameter of the landing predictor"):
        foveal.Loop(box, size=(64, 40), landing={"speed": 1})
    with pytest.raises(ValueError, match="onset_deg_s: expected a number, got str"):
        foveal.Loop(box, size=(64, 40), landing={"onset_deg_s": "fast"})
    with pytest.raises(ValueError, match="speed: no parameter of the landing predictor"):
        foveal.bench_latency(shared("gaze", "eyelink", "monoRemote500.asc"), box, landing={"speed": 1})
    with pytest.raises(ValueError, match="speed: no parameter of the landing predictor"):
        foveal.bench_latency(shared("gaze", "eyelink", "monoRemote500.asc"), box, landing="speed=1")
    with pytest.raises(ValueError, match="skew: given twice"):
        foveal.Loop(box, size=(64, 40), landing="skew=1, skew=2")
    for bad in (5, ["skew=1"]):
        with pytest.raises(TypeError, match="landing: expected a dict of the landing predictor's parameters or their text"):
            foveal.Loop(box, size=(64, 40), landing=bad)
        with pytest.raises(TypeError, match="landing: expected a dict of the landing predictor's parameters or their text"):
            foveal.bench_latency(shared("gaze", "eyelink", "monoRemote500.asc"), box, landing=bad)
    # landing_params: every parameter, the defaults with a text's (as --landing) and keywords over them
    d = foveal.gaze.landing_params("onset_deg_s=60, skew=1.2", skew=1.5, max_skew=np.float32(3))
    assert d["onset_deg_s"] == 60 and d["skew"] == 1.5 and d["max_skew"] == 3 and d["offset_deg_s"] == 30
    assert set(foveal.gaze.landing_params()) == set(d) and len(d) == 13
    with pytest.raises(ValueError, match="skew: '1x' is no number"):
        foveal.gaze.landing_params("skew=1x")
    with pytest.raises(ValueError, match="min_flight_deg: must be a finite number"):
        foveal.gaze.landing_params(min_flight_deg=float("inf"))


def test_the_loop_names_samples_too_far_apart_to_predict_from(box):
    # Times in milliseconds (an EyeLink's clock) where the loop takes seconds: every saccade would go
    # unpredicted without a word; gaze_note says why
    def note(unit, samples=40, **kw):
        loop = foveal.Loop(box, size=(64, 40), max_rays=16, device="cpu", **kw)
        assert loop.gaze_sample_hz == 0
        for k in range(samples):  # 500 Hz
            loop.push(k * 0.002 * unit, (30 + k % 3, 20))
        assert loop.gaze_sample_hz == pytest.approx(500 / unit)  # the rate the note judges
        return loop.gaze_note
    assert note(1) == ""
    assert "come 2 s apart" in note(1000) and "times in milliseconds" in note(1000)
    assert "come 0.1 s apart" in note(50) and "milliseconds" not in note(50)  # 10 Hz in seconds: too slow, no more
    # 60 Hz: followed, but a saccade spans a few samples and its landing is known too late to gain much
    assert "come 16.7 ms apart (60 Hz)" in note(1000 / 120) and "too late to gain much" in note(1000 / 120)
    assert note(5) == ""  # 100 Hz
    assert note(1000, predict=False) == ""
    assert note(1000, samples=10) == ""  # not before 16 intervals


def test_a_gaze_clock_that_goes_back_is_taken_and_named(box):
    # A trial clock that restarts (psychopy's trialClock.reset()): every later sample was ignored as
    # older than the latest, and the fovea stayed where the first trial left it, without a word
    loop = foveal.Loop(box, size=(64, 40), max_rays=16, device="cpu")
    for k in range(300):  # the first trial: 3 s at 100 Hz
        loop.push(k * 0.01, (10, 10))
    loop.push(2.8, (50, 30))  # a sample out of order (older than what is shown): ignored
    assert loop.frame().measured_gaze == pytest.approx((10, 10)) and loop.gaze_note == ""
    loop.push(0.0, (50, 30))  # the second trial's clock starts again
    frame = loop.frame(gaze=(52, 30), t=0.01)
    assert frame.measured_gaze == pytest.approx((52, 30))
    assert "clock went back once, the latest time by 2.99 s" in loop.gaze_note
    assert "one increasing clock" in loop.gaze_note
    frame = loop.frame(gaze=(40, 20))  # no time: just after the latest
    assert frame.measured_gaze == pytest.approx((40, 20))
    with pytest.raises(ValueError, match="t: must be a finite time"):
        loop.push(float("nan"), (10, 10))


def test_predict_landings_gives_every_prediction_of_each_flight():
    # foveal.gaze.predict_landings: the loop's live predictor over a stream (gaze/landing.h)
    t = np.arange(0, 0.6, 0.001)
    x = _min_jerk(t, 0.1, 0.06, 15.0) + _min_jerk(t, 0.4, 0.05, -10.0)
    flights = foveal.gaze.predict_landings(t, np.stack([x, np.zeros_like(x)], 1))
    assert len(flights) == 2
    first, second = flights
    assert first["landing_deg"][0] == pytest.approx(15, abs=0.2) and second["landing_deg"][0] == pytest.approx(5, abs=0.2)
    for f, onset, landed in ((first, 0.1, 0.16), (second, 0.4, 0.45)):
        assert onset <= f["onset_s"] < f["detected_s"] < f["first_prediction_s"] < f["landing_s"] <= landed + 0.01
        assert len(f["prediction_s"]) == len(f["prediction_x_deg"]) == len(f["prediction_y_deg"]) > 0
        assert np.all(np.diff(f["prediction_s"]) > 0) and f["prediction_s"][0] >= f["detected_s"]
        # the predictions close in on the landing: the last within 1°, and within 1° for good before it
        assert abs(f["prediction_x_deg"][-1] - f["landing_deg"][0]) < 1 and f["settled_s"] < f["landing_s"]
    # a parameter moves the detection: a threshold above the saccades' velocity finds none
    assert foveal.gaze.predict_landings(t, np.stack([x, np.zeros_like(x)], 1), onset_deg_s=999) == []
    with pytest.raises(ValueError, match="t_s: must rise"):
        foveal.gaze.predict_landings(t[::-1], np.stack([x, x], 1))
    with pytest.raises(ValueError, match="deg: 5 positions for 600 times"):
        foveal.gaze.predict_landings(t, np.zeros((5, 2)))
    with pytest.raises(ValueError, match="deg: expected an"):
        foveal.gaze.predict_landings(t, x)
    with pytest.raises(ValueError, match="speed: no parameter of the landing predictor"):
        foveal.gaze.predict_landings(t, np.stack([x, x], 1), speed=3)
    with pytest.raises(ValueError, match="skew: must be in"):
        foveal.gaze.predict_landings(t, np.stack([x, x], 1), skew=9)
    # times in milliseconds (an EyeLink's own clock) found nothing, without a word; now they are named
    with pytest.raises(ValueError, match=r"t_s: samples come 1 s apart .*are the times in milliseconds"):
        foveal.gaze.predict_landings(t * 1000, np.stack([x, np.zeros_like(x)], 1))
    with pytest.raises(ValueError, match=r"t_s: samples come 0\.06 s apart .*under 20 Hz"):  # 16.7 Hz: no onset shows
        foveal.gaze.predict_landings(t[::60], np.stack([x, np.zeros_like(x)], 1)[::60])
    assert len(foveal.gaze.predict_landings(t[::20], np.stack([x, np.zeros_like(x)], 1)[::20])) == 2  # 50 Hz: taken, both seen


def test_the_landing_rays_script_bounds_each_strategy_by_the_oracle(tmp_path):
    # bench/landing_rays.py on a made-up Lund-format recording (t, x, y px, label): two labelled saccades
    t = np.arange(0, 2.0, 0.002)
    deg = _min_jerk(t, 0.5, 0.05, 12.0) + _min_jerk(t, 1.2, 0.045, -9.0)
    x_px = (np.tan(np.radians(deg)) * 67 / 38 + 0.5) * 1024
    y_px = np.full_like(x_px, 384.0)
    label = np.where(((t >= 0.5) & (t <= 0.55)) | ((t >= 1.2) & (t <= 1.245)), 2, 1)
    rec = tmp_path / "made_up_labelled_MN.csv"
    rec.write_text("t,x,y,label\n" + "".join(f"{a:.3f},{b:.2f},{c:.2f},{d}\n" for a, b, c, d in zip(t, x_px, y_px, label)))
    script = os.path.join(os.path.dirname(__file__), "..", "..", "bench", "landing_rays.py")
    out = tmp_path / "rays.json"
    run = subprocess.run([sys.executable, script, "--recording", str(rec), "--strategies",
                          "eye,prediction,region:2,oracle,oracle-pre,oracle-post", "--json", str(out)], capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 0, run.stderr
    rows = json.loads(out.read_text())["saccades"]
    assert len(rows) == 2 and [round(r["amplitude_deg"]) for r in rows] == [12, 9]
    for r in rows:
        share = r["share"]
        # the oracle casts every ray of the flight's frames into the landed fovea: no strategy casts more
        assert share["oracle"] > share["eye"] >= 0
        assert share["oracle"] >= max(share["prediction"], share["region:2"])
        assert share["prediction"] >= share["eye"]  # a clean saccade's prediction lands its rays
        # the oracle for part of the flight only: between the prediction and the oracle
        for part in ("oracle-pre", "oracle-post"):
            assert share["prediction"] <= share[part] <= share["oracle"]
    assert "| oracle |" in run.stdout
    assert json.loads(out.read_text())["sample_hz"] == [pytest.approx(500)]
    assert json.loads(out.read_text())["landing"] == foveal.gaze.landing_params()  # the predictor's parameters, kept with the figures
    # as a 100-Hz tracker would deliver it: every fifth sample, and its latency one of their periods + 2 ms
    slow = tmp_path / "slow.json"
    run = subprocess.run([sys.executable, script, "--recording", str(rec), "--sample-hz", "100", "--strategies", "eye,prediction,oracle",
                          "--json", str(slow)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    report = json.loads(slow.read_text())
    assert report["sample_hz"] == [pytest.approx(100)] and report["labelled_saccades"] == 2
    assert "(samples at 100 Hz)" in run.stdout
    for fast, r in zip(rows, report["saccades"]):  # fewer samples, later known: no strategy gains by them
        assert r["share"]["oracle"] <= fast["share"]["oracle"] + 1e-9
    faster = subprocess.run([sys.executable, script, "--recording", str(rec), "--sample-hz", "1000"], capture_output=True, text=True,
                            timeout=60)
    assert faster.returncode != 0 and "--sample-hz: 1000 Hz is faster than made_up_labelled_MN.csv's own 500 Hz" in faster.stderr
    # a file that is no Lund recording is named, with its line
    bad = tmp_path / "bad.csv"
    bad.write_text("time,x,y\n0,1,2\n")
    wrong = subprocess.run([sys.executable, script, "--recording", str(bad)], capture_output=True, text=True, timeout=60)
    assert wrong.returncode != 0 and "bad.csv: line 1" in wrong.stderr
    bad.write_text("t,x,y,label\n0,1,2,1\n0.002,abc,3,1\n")  # an empty x or y is a lost sample; anything else no number
    wrong = subprocess.run([sys.executable, script, "--recording", str(bad)], capture_output=True, text=True, timeout=60)
    assert wrong.returncode != 0 and "bad.csv: line 3: expected numbers" in wrong.stderr
    nope = subprocess.run([sys.executable, script, "--recording", str(rec), "--strategies", "region:0.5"], capture_output=True,
                          text=True, timeout=60)
    assert nope.returncode != 0 and "--strategies: region:0.5" in nope.stderr
    negative = subprocess.run([sys.executable, script, "--recording", str(rec), "--min-amplitude", "-1"], capture_output=True, text=True,
                              timeout=60)
    assert negative.returncode != 0 and "--min-amplitude: must be a finite number >= 0" in negative.stderr
    # --landing reaches the predictor: an onset above both saccades' velocities sees neither; a wrong one is named
    blind = subprocess.run([sys.executable, script, "--recording", str(rec), "--landing", "onset_deg_s=900"], capture_output=True,
                           text=True, timeout=60)
    assert blind.returncode != 0 and "no labelled saccade the predictor saw" in blind.stderr
    bad_landing = subprocess.run([sys.executable, script, "--recording", str(rec), "--landing", "skew=9"], capture_output=True,
                                 text=True, timeout=60)
    assert bad_landing.returncode != 0 and "--landing: skew: must be in [0.25, 4]" in bad_landing.stderr


def test_the_landing_rays_script_measures_what_the_flight_says_of_its_amplitude():
    # bench/landing_rays.py's regression of log amplitude on the flight before the peak: an amplitude the
    # flight fixes is found exactly, one it does not leaves R² near 0 and the error of the usual amplitude
    sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "bench"))
    try:
        import landing_rays
    finally:
        sys.path.pop(0)
    rng = np.random.default_rng(3)
    distance, velocity, since = rng.uniform(0.5, 5, 300), rng.uniform(50, 400, 300), rng.uniform(0.004, 0.03, 300)
    groups = np.repeat(["a", "b", "c"], 100)
    fixed = landing_rays.amplitude_regression(np.column_stack([distance, velocity, since, 2.5 * distance ** 1.2]), groups)
    assert fixed["r2"] == pytest.approx(1) and fixed["slopes"][0] == pytest.approx(1.2)
    assert fixed["held_out_error_deg_median"] < 1e-9 < fixed["constant_error_deg_median"]
    unrelated = landing_rays.amplitude_regression(np.column_stack([distance, velocity, since, rng.uniform(5, 20, 300)]), groups)
    assert unrelated["r2"] < 0.05 and unrelated["predictions"] == 300
    assert unrelated["held_out_error_deg_median"] == pytest.approx(unrelated["constant_error_deg_median"], rel=0.25)
