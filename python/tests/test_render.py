"""Renderer.render against the command line: the same pixels, stats and errors; arrays are views."""
import gc
import threading
import time

import numpy as np
import pytest

import foveal
from conftest import cli_error, read_pfm, run_cli


@pytest.fixture(scope="module")
def box():
    return foveal.Scene("builtin:box")


@pytest.mark.parametrize("mode,gaze,seed", [("foveated", (100, 60), 1), ("full", (30, 90), 7)])
def test_render_equals_the_command_lines_pfm_bit_for_bit(cli, box, tmp_path, mode, gaze, seed):
    out, depth, stats = tmp_path / "cli.pfm", tmp_path / "depth.pfm", tmp_path / "stats.json"
    run_cli(cli, "render", "--scene", "builtin:box", "--size", "200x120", "--mode", mode, "--gaze", f"{gaze[0]},{gaze[1]}",
            "--max-rays", 64, "--seed", seed, "--device", "cpu", "-o", out, "--aov", f"depth={depth}", "--stats", stats, "-q")
    frame = foveal.Renderer(box, device="cpu").render(size=(200, 120), mode=mode, gaze=gaze, max_rays=64, seed=seed)
    expected = read_pfm(out)
    assert frame.image.shape == expected.shape == (120, 200, 3)
    assert np.array_equal(frame.image.view(np.uint32), expected.view(np.uint32)), "pixels differ from the CLI's"
    np.testing.assert_array_equal(np.nan_to_num(frame.aov("depth"), nan=-1), np.nan_to_num(read_pfm(depth)[:, :, 0], nan=-1))
    import json
    cli_stats = json.loads(stats.read_text())
    assert frame.stats.keys() == cli_stats.keys()
    assert frame.stats["rays"] == cli_stats["rays"]
    assert frame.stats["gaze_px"] == cli_stats["gaze_px"]


def test_the_image_is_a_view_of_the_frames_buffer(box):
    frame = foveal.Renderer(box, device="cpu").render(size=(64, 40), max_rays=8)
    a, b = frame.image, frame.image
    assert a.__array_interface__["data"][0] == b.__array_interface__["data"][0]
    assert not a.flags["OWNDATA"] and np.shares_memory(a, b)
    a[0, 0, 0] = 123.0
    assert frame.image[0, 0, 0] == 123.0  # the same memory, not a copy
    copy = a.copy()
    del frame, b
    gc.collect()
    assert np.array_equal(a, copy)  # the view keeps the frame alive


def test_scene_cameras_and_named_camera(box, tmp_path, cli):
    names = [c.name for c in box.cameras]
    assert "corner" in names
    frame = foveal.Renderer(box, device="cpu").render(size=(80, 50), camera="corner", max_rays=4)
    run_cli(cli, "render", "--scene", "builtin:box", "--camera", "corner", "--size", "80x50", "--max-rays", 4, "--device", "cpu",
            "-o", tmp_path / "c.pfm", "-q")
    assert np.array_equal(frame.image, read_pfm(tmp_path / "c.pfm"))
    cam = foveal.Camera(eye=(0, 1.3, 6), look=(0, 1, 0), fov=40)
    f2 = foveal.Renderer(box, device="cpu").render(size=(80, 50), camera=cam, max_rays=4)
    assert not np.array_equal(frame.image, f2.image)


def test_a_scene_is_also_taken_as_what_the_command_lines_scene_takes(box, tmp_path):
    """Wherever a Scene is taken, its path or builtin:NAME is too (as --scene), loaded then; a bad one is named."""
    frame = foveal.Renderer(box, device="cpu").render(size=(64, 40), max_rays=8)
    by_name = foveal.Renderer("builtin:box", device="cpu").render(size=(64, 40), max_rays=8)
    assert np.array_equal(by_name.image.view(np.uint32), frame.image.view(np.uint32))
    obj = tmp_path / "tri.obj"
    obj.write_text("v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n")
    assert foveal.Renderer(obj, device="cpu").render(size=(16, 10), max_rays=2).image.shape == (10, 16, 3)  # an os.PathLike
    loop = foveal.Loop("builtin:sphere-plane", size=(32, 20), max_rays=4, device="cpu")
    assert loop.frame(gaze=(16, 10), t=0.0).image.shape == (20, 32, 3)
    assert foveal.VisionSimulation(str(obj), size=(16, 10), device="cpu").step().perceived.shape == (10, 16, 3)
    missing = tmp_path / "no-such-scene.obj"
    makers = {
        "Renderer": lambda scene: foveal.Renderer(scene, device="cpu"),
        "Loop": lambda scene: foveal.Loop(scene, size=(32, 20)),
        "VisionSimulation": lambda scene: foveal.VisionSimulation(scene, size=(16, 10)),
        "bench_latency": lambda scene: foveal.bench_latency([], scene),
    }
    for name, make in makers.items():
        with pytest.raises(FileNotFoundError, match="no-such-scene.obj"):
            make(missing)
        with pytest.raises(TypeError, match="scene: a foveal.Scene, a path or builtin:box"):
            make(3)


def test_errors_carry_the_command_lines_message_in_pythons_words(cli, box, tmp_path):
    missing = str(tmp_path / "missing.obj")
    with pytest.raises(FileNotFoundError) as e:
        foveal.Scene(missing)
    assert str(e.value) == cli_error(cli, "render", "--scene", missing, "-o", tmp_path / "x.png")
    renderer = foveal.Renderer(box, device="cpu")
    with pytest.raises(ValueError) as e:
        renderer.render(mode="sideways")
    assert str(e.value).startswith("mode: unknown mode 'sideways'")  # the keyword argument, not the CLI's --mode
    assert str(e.value) == cli_error(cli, "render", "--mode", "sideways", "-o", tmp_path / "x.png").replace("--mode", "mode", 1)
    with pytest.raises(ValueError) as e:
        renderer.render(camera="nowhere")
    assert str(e.value) == cli_error(cli, "render", "--camera", "nowhere", "-o", tmp_path / "x.png")
    with pytest.raises(ValueError, match="size"):
        renderer.render(size=(0, 10))
    with pytest.raises(ValueError, match="Camera"):
        foveal.Camera(eye=(1, 2, 3), look=(1, 2, 3))
    with pytest.raises(ValueError):
        foveal.Display(-1, 30, 60, 100, 100)


def test_no_gpu_is_a_runtime_error_when_cuda_is_asked_for(box):
    if foveal.device_available():
        pytest.skip("a GPU is present")
    with pytest.raises(RuntimeError, match="cuda"):
        foveal.Renderer(box, device="cuda")


def test_choose_device_is_the_rule_every_device_argument_follows(box):
    # What a session checks before it starts: the device it would render on, or the error it would get
    gpu = foveal.device_available()
    assert foveal.choose_device("cpu") == "cpu"
    assert foveal.choose_device("auto") == ("cuda" if gpu else "cpu")
    assert foveal.Renderer(box, device="auto").device_description.startswith(foveal.choose_device("auto"))
    with pytest.raises(ValueError, match="unknown device 'tpu' \\(known: auto, cpu, cuda\\)"):
        foveal.choose_device("tpu")
    if gpu:
        assert foveal.choose_device("cuda") == "cuda"
    else:
        with pytest.raises(RuntimeError, match="cuda"):
            foveal.choose_device("cuda")


def test_the_gil_is_released_while_rendering(box):
    renderer = foveal.Renderer(box, device="cpu", threads=1)
    done = threading.Event()

    def work():
        renderer.render(size=(320, 200), mode="full", max_rays=64)
        done.set()

    thread = threading.Thread(target=work)
    thread.start()
    ticks = 0
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    thread.join()
    assert ticks > 20, "the main thread did not run while the frame rendered"


def test_stats_and_gaze(box):
    frame = foveal.Renderer(box, device="cpu").render(size=(120, 80), gaze=(10, 20), max_rays=16, min_rays=2)
    assert frame.gaze == (10.0, 20.0) or list(frame.gaze) == [10.0, 20.0]
    assert frame.stats["width"] == 120 and frame.stats["height"] == 80
    budget = frame.aov("budget")
    assert budget.max() == 16 and budget.min() >= 2
    assert frame.library_ms > 0


@pytest.mark.parametrize("device", ["cpu", "cuda"])
def test_quality_per_ray_options_equal_the_command_lines(cli, box, tmp_path, device):
    # Three temporal frames of a still view with adaptive rays and the filter: the CLI's
    # `render --frames 3` image on the same device bit for bit; after reset_history() the first
    # temporal frame is the paper's
    if device == "cuda" and not foveal.device_available():
        pytest.skip("no usable GPU")
    out = tmp_path / "reuse.pfm"
    common = dict(size=(160, 100), gaze=(60, 40), max_rays=64)
    run_cli(cli, "render", "--scene", "builtin:box", "--size", "160x100", "--gaze", "60,40", "--max-rays", 64, "--device", device,
            "--adaptive", "--denoise", "--temporal", "--frames", 3, "-o", out, "-q")
    renderer = foveal.Renderer(box, device=device)
    for _ in range(3):
        frame = renderer.render(adaptive=True, denoise=True, temporal=True, **common)
    assert np.array_equal(frame.image.view(np.uint32), read_pfm(out).view(np.uint32)), "pixels differ from the CLI's"
    assert frame.stats["reuse"]["history_pixels"] > 0
    renderer.reset_history()
    first = renderer.render(temporal=True, **common)
    paper = renderer.render(**common)
    assert np.array_equal(first.image, paper.image)
    assert first.stats["rays"]["ao"] == paper.stats["rays"]["ao"]
    second = renderer.render(temporal=True, **common)
    assert second.stats["rays"]["ao"] < paper.stats["rays"]["ao"] / 2  # n/F rays where history was kept
    with pytest.raises(ValueError) as e:
        renderer.render(temporal=True, temporal_frames=0)
    assert str(e.value) == cli_error(cli, "render", "--temporal", "--temporal-frames", "0", "-o", tmp_path / "x.png").replace(
        "--temporal-frames", "temporal_frames")


@pytest.mark.parametrize("call, keyword, cli_args, option", [
    (lambda box: foveal.Renderer(box, device="cpu").render(size=(40, 30), ellipse=-1), "ellipse", ["--ellipse", "-1"], "--ellipse"),
    (lambda box: foveal.Renderer(box, device="cpu").render(size=(40, 30), gaze=(float("nan"), 1.0)), "gaze", None, None),
    (lambda box: foveal.Renderer(box, device="cpu").render(size=(40, 30), gamma=0), "gamma", ["--gamma", "0"], "--gamma"),
    (lambda box: foveal.Renderer(box, device="cpu").render(size=(40, 30), max_rays=-3), "max_rays", ["--max-rays", "-3"], "--max-rays"),
    (lambda box: foveal.VisionSimulation(box, size=(40, 30), device="cpu", pupil_mm=20), "pupil_mm", None, None),
])
def test_errors_name_the_keyword_argument_and_the_command_line_its_option(cli, box, tmp_path, call, keyword, cli_args, option):
    """The library names its parameters; Python says them as keyword arguments, the command line as options."""
    with pytest.raises(ValueError) as e:
        call(box)
    assert str(e.value).startswith(keyword + ":"), str(e.value)
    assert "--" not in str(e.value)
    if cli_args:
        message = cli_error(cli, "render", "--size", "40x30", *cli_args, "-o", tmp_path / "x.png")
        assert message.startswith(option + ":"), message
        assert message[len(option):] == str(e.value)[len(keyword):]
