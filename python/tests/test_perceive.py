"""foveal.perceive: the command line's perceive through the same library code, bit for bit, on
images, folders and videos, with a fixed gaze and with a recording; arrays checked at the door."""
import filecmp
import shutil
import subprocess
import warnings

import numpy as np
import pytest

import foveal
from conftest import run_cli, shared

EYE = "myopia:-2+cataract:0.4+cvd:deutan:0.6"


def _grating(width, height, seed=0):
    rng = np.random.default_rng(seed)
    x = np.arange(width)[None, :, None]
    image = 0.5 + 0.4 * np.sign(np.sin(x / 6.0)) * np.ones((height, 1, 3))
    return np.clip(image + 0.05 * rng.random((height, width, 3)), 0, 1).astype(np.float32)


@pytest.fixture()
def image_png(tmp_path):
    path = tmp_path / "in.png"
    foveal.save_image(_grating(160, 100), path)
    return path


def test_an_image_equals_the_command_lines_bit_for_bit(cli, image_png, tmp_path):
    run_cli(cli, "perceive", image_png, "-o", tmp_path / "cli.png", "--eye", EYE, "--gaze", "40,30", "-q")
    # The path, written as the command line writes it
    foveal.perceive(image_png, eye=EYE, gaze=(40, 30), output=tmp_path / "py.png")
    assert filecmp.cmp(tmp_path / "cli.png", tmp_path / "py.png", shallow=False)
    # The path, returned as linear floats, written by save_image
    seen = foveal.perceive(image_png, eye=EYE, gaze=(40, 30))
    assert seen.dtype == np.float32 and seen.shape == (100, 160, 3)
    foveal.save_image(seen, tmp_path / "array.png")
    assert filecmp.cmp(tmp_path / "cli.png", tmp_path / "array.png", shallow=False)
    # The same pixels as uint8 sRGB (what an imaging library reads) give the same frame
    srgb8 = np.round(foveal.load_image(image_png) * 255).astype(np.uint8)
    assert np.array_equal(foveal.perceive(srgb8, eye=EYE, gaze=(40, 30)), seen)
    # ... and as linear floats, stated explicitly
    assert np.array_equal(foveal.perceive(foveal.srgb_to_linear(srgb8), eye=EYE, gaze=(40, 30), encoding="linear"), seen)


def test_a_folder_with_a_recording_equals_the_command_lines(cli, tmp_path):
    frames = tmp_path / "frames"
    frames.mkdir()
    arrays = []
    for k in range(4):
        arrays.append(_grating(200, 100, seed=k))
        foveal.save_image(arrays[-1], frames / f"f{k}.png")
    # a fixation at x = 50 for 0.45 s, then at x = 150
    recording = tmp_path / "gaze.csv"
    recording.write_text("t,x,y\n" + "".join(f"{i * 0.01:.2f},{50 if i < 45 else 150},50\n" for i in range(100)))
    run_cli(cli, "perceive", frames, "-o", tmp_path / "cli", "--fps", 4, "--gaze", recording, "--screen", "200x100",
            "--eye", "field:hemianopia:left:20", "-q")
    rec = foveal.gaze.read(recording, screen=(200, 100))
    foveal.perceive(frames, eye="field:hemianopia:left:20", gaze=rec, fps=4, output=tmp_path / "py")
    for k in range(4):
        assert filecmp.cmp(tmp_path / "cli" / f"f{k}.png", tmp_path / "py" / f"f{k}.png", shallow=False), k
    # Frames as arrays (uint8 sRGB, as read from the files) with the recording's path
    srgb8 = [np.round(foveal.load_image(frames / f"f{k}.png") * 255).astype(np.uint8) for k in range(4)]
    seen = foveal.perceive(srgb8, eye="field:hemianopia:left:20", gaze=rec, fps=4)
    assert isinstance(seen, list) and len(seen) == 4
    for k in range(4):
        foveal.save_image(seen[k], tmp_path / f"a{k}.png")
        assert filecmp.cmp(tmp_path / "cli" / f"f{k}.png", tmp_path / f"a{k}.png", shallow=False), k
    # The field moved with the fixation: right of x = 50 is seen in frame 0, left of x = 150 lost in frame 3
    assert seen[0][:, 120:140].std() > 1.5 * seen[3][:, 120:140].std()
    # One point per frame moves it the same way
    by_points = foveal.perceive(srgb8, eye="field:hemianopia:left:20", gaze=[(50, 50), (50, 50), (150, 50), (150, 50)])
    assert all(np.array_equal(a, b) for a, b in zip(by_points, seen))


def test_a_short_video_equals_the_command_lines(cli, tmp_path):
    if shutil.which("ffmpeg") is None:
        pytest.skip("no ffmpeg")
    video = tmp_path / "in.mp4"
    subprocess.run(["ffmpeg", "-v", "error", "-f", "lavfi", "-i", "testsrc=size=96x64:rate=10", "-t", "0.5", "-pix_fmt",
                    "yuv420p", str(video)], check=True)
    run_cli(cli, "perceive", video, "-o", tmp_path / "cli.mp4", "--eye", "cvd:protanopia", "--gaze", "20,20", "-q")
    foveal.perceive(video, eye="cvd:protanopia", gaze=(20, 20), output=tmp_path / "py.mp4")
    assert filecmp.cmp(tmp_path / "cli.mp4", tmp_path / "py.mp4", shallow=False)
    frames = foveal.perceive(video, eye="cvd:protanopia", gaze=(20, 20))
    assert len(frames) == 5 and frames[0].shape == (64, 96, 3)


def test_a_recording_drives_the_shared_eyelink_frames(cli, tmp_path):
    asc = shared("gaze", "eyelink", "monoRemote500.asc")
    frames = tmp_path / "frames"
    frames.mkdir()
    for k in range(3):
        foveal.save_image(_grating(168, 105, seed=k), frames / f"f{k}.png")
    run_cli(cli, "perceive", frames, "-o", tmp_path / "cli", "--fps", 2, "--gaze", asc, "--start", 1, "--eye", "amd:5", "-q")
    foveal.perceive(frames, eye="amd:5", gaze=asc, fps=2, start_s=1, output=tmp_path / "py")
    for k in range(3):
        assert filecmp.cmp(tmp_path / "cli" / f"f{k}.png", tmp_path / "py" / f"f{k}.png", shallow=False), k


def test_rgba_keeps_its_alpha_and_grey_becomes_rgb():
    rgba = np.dstack([_grating(64, 40), np.linspace(0, 1, 64 * 40, dtype=np.float32).reshape(40, 64, 1)])
    seen = foveal.perceive(rgba, eye="cataract:0.5")
    assert seen.shape == (40, 64, 4) and np.array_equal(seen[:, :, 3], rgba[:, :, 3])
    assert foveal.perceive(rgba[:, :, 0], eye="healthy").shape == (40, 64, 3)


def test_wrong_stimuli_and_arguments_raise_naming_the_argument(tmp_path):
    image = _grating(64, 40)
    cases = [
        (lambda: foveal.perceive(image.astype(bool)), TypeError, "stimulus"),
        (lambda: foveal.perceive(np.zeros((4, 4, 5), np.float32)), ValueError, "stimulus"),
        (lambda: foveal.perceive(np.where(np.ones_like(image, bool), np.nan, image)), ValueError, "stimulus"),
        (lambda: foveal.perceive([image, image.astype(np.uint8)]), TypeError, "stimulus"),
        (lambda: foveal.perceive(image, eye="glaucoma:0.5+"), ValueError, "eye"),
        (lambda: foveal.perceive(image, eye="cvd:purple"), ValueError, "eye"),
        (lambda: foveal.perceive(image, gaze=(np.nan, 3)), ValueError, "gaze"),
        (lambda: foveal.perceive(image, gaze=(1e6, 3)), ValueError, "gaze"),
        (lambda: foveal.perceive([image, image], gaze=[(1, 2)] * 3), ValueError, "gaze"),
        (lambda: foveal.perceive(image, depth=np.zeros((40, 64), np.float32)), ValueError, "depth"),
        (lambda: foveal.perceive(image, depth=np.ones((10, 10), np.float32)), ValueError, "depth"),
        (lambda: foveal.perceive(image, blur_taps=0), ValueError, "blur_taps"),
        (lambda: foveal.perceive(image, fps=0), ValueError, "fps"),
        (lambda: foveal.perceive(image, encoding="gamma"), ValueError, "encoding"),
        (lambda: foveal.perceive(image, output=tmp_path / "o.png"), ValueError, "output"),
        (lambda: foveal.perceive(image, display=(47.5, 30)), ValueError, "display"),
        (lambda: foveal.perceive(image, pupil_mm=40), ValueError, "pupil_mm"),
        (lambda: foveal.perceive(tmp_path / "none.png"), FileNotFoundError, "none.png"),
    ]
    for call, kind, name in cases:
        with pytest.raises(kind) as error:
            call()
        message = str(error.value)
        assert name in message and "--" not in message, message


def test_a_gaze_far_off_the_frame_warns():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        foveal.perceive(_grating(64, 40), gaze=(64 * 3, 20))
    assert any("off the frame" in str(w.message) for w in caught)


def test_the_output_is_never_written_over_the_input(image_png):
    before = image_png.read_bytes()
    with pytest.raises(ValueError, match="is the input"):
        foveal.perceive(image_png, eye="cataract:0.5", output=image_png)
    assert image_png.read_bytes() == before


def test_a_read_only_file_or_folder_is_never_written(image_png, tmp_path):
    # Root may replace a read-only file; foveal refuses it for every user
    before = image_png.read_bytes()
    image_png.chmod(0o444)
    with pytest.raises(ValueError, match="is read-only"):
        foveal.save_image(_grating(16, 10), image_png)
    other = tmp_path / "other.png"
    foveal.save_image(_grating(64, 40), other)
    with pytest.raises(ValueError, match="is read-only"):
        foveal.perceive(other, eye="cataract:0.5", output=image_png)
    assert image_png.read_bytes() == before
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o555)
    with pytest.raises(ValueError, match="read-only folder"):
        foveal.save_image(_grating(16, 10), locked / "a.png")
    assert not any(locked.iterdir())
    locked.chmod(0o755)
    image_png.chmod(0o644)
