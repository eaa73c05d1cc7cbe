"""Arrays and arguments checked at the boundary: a wrong array raises a clear TypeError or
ValueError naming the argument, in Python's words (never a command-line flag), before any work."""
import numpy as np
import pytest

import foveal

IMAGE = np.full((8, 12, 3), 0.25, np.float32)


@pytest.fixture(scope="module")
def box():
    return foveal.Scene("builtin:box")


@pytest.mark.parametrize("bad, kind", [
    (np.full((8, 12, 3), 128, np.uint8), TypeError),             # display-encoded bytes, not linear floats
    (np.zeros((8, 12), np.float32), ValueError),                 # 2-D
    (np.zeros((8, 24, 3), np.float32)[:, ::2], ValueError),      # not contiguous
    (np.full((8, 12, 3), np.nan, np.float32), ValueError),       # NaN pixels into an 8-bit file
    (np.zeros((8, 12, 5), np.float32), ValueError),              # 5 channels
    ("not an image", TypeError),
])
def test_save_image_refuses_what_it_would_write_wrong(tmp_path, bad, kind):
    with pytest.raises(kind) as error:
        foveal.save_image(bad, tmp_path / "x.png")
    assert str(error.value).startswith("image:"), str(error.value)
    assert not (tmp_path / "x.png").exists()


def test_save_image_keeps_nan_in_float_files_and_writes_uint8_free_pngs(tmp_path):
    depth = np.full((8, 12, 1), np.nan, np.float32)
    foveal.save_image(depth, tmp_path / "d.pfm")
    assert np.isnan(foveal.load_image(tmp_path / "d.pfm")).all()
    foveal.save_image(IMAGE, tmp_path / "ok.png")
    assert np.allclose(foveal.load_image(tmp_path / "ok.png"), round(0.25 ** (1 / 2.4) * 1.055 * 255 - 0.055 * 255) / 255,
                       atol=1 / 255)


@pytest.mark.parametrize("a, b, name, kind", [
    (np.full((8, 12, 3), 128, np.uint8), IMAGE, "a", TypeError),
    (IMAGE, np.full((8, 12, 3), np.nan, np.float32), "b", ValueError),
    (IMAGE, np.zeros((8, 12, 7), np.float32), "b", ValueError),
    (IMAGE, [[1, 2], [3, "x"]], "b", TypeError),
])
def test_compare_names_the_wrong_argument(a, b, name, kind):
    with pytest.raises(kind) as error:
        foveal.compare(a, b)
    assert str(error.value).startswith(name + ":"), str(error.value)


def test_srgb_to_linear_is_the_png_decoding(tmp_path):
    foveal.save_image(np.linspace(0, 1, 8 * 12 * 3, dtype=np.float32).reshape(8, 12, 3), tmp_path / "g.png")
    raw = foveal.load_image(tmp_path / "g.png")  # the file's values, 0–1 (PNG values are sRGB-encoded)
    as_bytes = np.round(raw * 255).astype(np.uint8)
    linear = foveal.srgb_to_linear(as_bytes)
    assert linear.dtype == np.float32 and linear.shape == as_bytes.shape
    assert np.array_equal(foveal.srgb_to_linear(raw), linear)
    assert linear[0, 0, 0] == 0 and linear[-1, -1, -1] == 1
    assert np.isclose(foveal.srgb_to_linear(np.array([[128]], np.uint8))[0, 0], ((128 / 255 + 0.055) / 1.055) ** 2.4)


def test_linear_to_srgb_is_the_png_encoding_for_a_window():
    # The PNG's bytes are the same curve rounded: foveal.linear_to_srgb's floats round to them
    linear = np.linspace(0, 1, 9 * 16 * 3, dtype=np.float32).reshape(9, 16, 3)
    srgb = foveal.linear_to_srgb(linear)
    assert srgb.dtype == np.float32 and srgb.shape == linear.shape
    curve = np.where(linear <= 0.0031308, 12.92 * linear.astype(np.float64), 1.055 * linear.astype(np.float64) ** (1 / 2.4) - 0.055)
    assert np.abs(srgb - curve).max() < 1e-6
    assert np.allclose(foveal.srgb_to_linear(srgb), linear, atol=1e-5)  # and back
    # PsychoPy's texture: [−1, 1], rows bottom-up, into one buffer, the same buffer returned
    texture = np.empty_like(linear)
    assert foveal.linear_to_srgb(linear, texture, low=-1, high=1, bottom_up=True) is texture
    assert np.allclose(texture, (2 * curve - 1)[::-1], atol=2e-6)
    # Clipped; grey 2-D images keep their shape; a 4th channel (alpha) is clipped and mapped, not encoded
    assert np.array_equal(foveal.linear_to_srgb(np.array([[-2.0, 0.0, 1.0, 9.0]])), [[0, 0, 1, 1]])
    rgba = np.full((2, 2, 4), 0.5, np.float32)
    encoded = foveal.linear_to_srgb(rgba)
    assert np.allclose(encoded[..., :3], 1.055 * 0.5 ** (1 / 2.4) - 0.055) and np.all(encoded[..., 3] == 0.5)
    # In place, top-down
    copy = linear.copy()
    assert foveal.linear_to_srgb(copy, copy) is copy and np.array_equal(copy, srgb)


@pytest.mark.parametrize("image, out, keywords, kind, says", [
    (np.full((2, 3, 3), 128, np.uint8), None, {}, TypeError, "image: uint8 pixels"),
    (np.zeros((2, 3, 5), np.float32), None, {}, ValueError, "image: expected an H×W×C image"),
    (IMAGE, np.empty((3, 3), np.float32), {}, ValueError, "out: expected a writable C-contiguous float32 array of shape (8, 12, 3)"),
    (IMAGE, np.empty((8, 12, 3), np.float64), {}, ValueError, "got float64"),
    (IMAGE, np.empty((8, 24, 3), np.float32)[:, ::2], {}, ValueError, "not C-contiguous"),
    (IMAGE, "buffer", {}, ValueError, "got str"),
    (IMAGE, None, {"low": float("nan")}, ValueError, "low: expected a finite number"),
    (IMAGE, None, {"high": "1"}, ValueError, "high: expected a finite number"),
])
def test_linear_to_srgb_names_what_is_wrong(image, out, keywords, kind, says):
    with pytest.raises(kind) as error:
        foveal.linear_to_srgb(image, out, **keywords)
    assert says in str(error.value), str(error.value)


def test_linear_to_srgb_names_a_pixel_that_is_not_finite_and_never_reverses_rows_into_its_own_image():
    bad = np.full((4, 5, 3), 0.5, np.float32)
    bad[2, 3, 1] = np.inf
    out = np.full_like(bad, -7)
    with pytest.raises(ValueError, match=r"image: pixel \(3, 2\) channel 1 is inf"):
        foveal.linear_to_srgb(bad, out)
    assert np.all(out == -7)  # nothing written
    read_only = np.empty_like(IMAGE)
    read_only.flags.writeable = False
    with pytest.raises(ValueError, match="read-only"):
        foveal.linear_to_srgb(IMAGE, read_only)
    same = IMAGE.copy()
    with pytest.raises(ValueError, match="out: shares memory with image"):
        foveal.linear_to_srgb(same, same, bottom_up=True)
    assert np.array_equal(same, IMAGE)


def test_every_error_speaks_pythons_words(box, tmp_path):
    """A sweep over the public API's arguments: each message starts with the argument's name."""
    renderer = foveal.Renderer(box, device="cpu")
    cases = [
        ("size", lambda: renderer.render(size=(0, 10))),
        ("max_rays", lambda: renderer.render(size=(16, 10), max_rays=-1)),
        ("gaze", lambda: renderer.render(size=(16, 10), gaze=(1e7, 0))),
        ("mode", lambda: renderer.render(size=(16, 10), mode="fast")),
        ("temporal_frames", lambda: renderer.render(size=(16, 10), temporal=True, temporal_frames=0)),
        ("device", lambda: foveal.Renderer(box, device="quantum")),
        ("threads", lambda: foveal.Renderer(box, threads=-2)),
        ("eye", lambda: foveal.VisionSimulation(box, eye="glaucoma:0.5+", size=(16, 10))),
        ("eye", lambda: foveal.VisionSimulation(box, eye="cvd:purple", size=(16, 10))),
        ("pupil_mm", lambda: foveal.VisionSimulation(box, size=(16, 10), pupil_mm=-1)),
        ("refresh_hz", lambda: foveal.Loop(box, size=(16, 10), refresh_hz=0)),
        ("ellipse", lambda: foveal.compare(IMAGE, IMAGE, ellipse=0)),
        ("ellipse", lambda: foveal.compare(IMAGE, IMAGE, ellipse=float("inf"))),
        ("ssim_border", lambda: foveal.compare(IMAGE, IMAGE, ssim_border="wrap")),
        ("time_unit", lambda: foveal.gaze.read(tmp_path / "x.csv", time_unit="h")),
        ("coords", lambda: foveal.gaze.read(tmp_path / "x.csv", coords="cm")),
        ("method", lambda: foveal.gaze.fixations(np.zeros(3, foveal.gaze.SAMPLE_DTYPE), screen=(10, 10), method="auto")),
        ("display", lambda: foveal.Display(width_cm=-1)),
        ("stimulus", lambda: foveal.perceive(np.zeros((4, 4, 2), np.float32))),
        ("encoding", lambda: foveal.perceive(IMAGE, encoding="hdr")),
    ]
    for name, call in cases:
        with pytest.raises((TypeError, ValueError, RuntimeError)) as error:
            call()
        message = str(error.value)
        assert message.startswith(name), f"{name}: {message}"
        assert "--" not in message, message


def test_a_gaze_far_off_the_frame_warns_and_beyond_reach_raises(box):
    renderer = foveal.Renderer(box, device="cpu")
    with pytest.warns(UserWarning, match="^gaze: .* off the frame"):
        renderer.render(size=(32, 20), gaze=(32 * 4, 10), max_rays=4)
    with pytest.warns(UserWarning, match="^fixation: .* off the frame"):
        foveal.VisionSimulation(box, size=(32, 20), device="cpu").step(fixation=(-100.0, 10.0))
    with pytest.raises(ValueError, match="^gaze"):
        renderer.render(size=(32, 20), gaze=(32 * 40, 10), max_rays=4)
