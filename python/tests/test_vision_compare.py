"""VisionSimulation and compare against the command line and the models' own properties."""
import json

import numpy as np
import pytest

import foveal
from conftest import read_pfm, run_cli


@pytest.fixture(scope="module")
def box():
    return foveal.Scene("builtin:box")


def test_vision_steps_are_reproducible_and_follow_a_given_fixation(box):
    a = foveal.VisionSimulation(box, size=(160, 120), seed=3, device="cpu")
    b = foveal.VisionSimulation(box, size=(160, 120), seed=3, device="cpu")
    sa, sb = a.step(), b.step()
    assert sa.perceived.shape == (120, 160, 3) and sa.coc.shape == (120, 160)
    assert np.array_equal(sa.perceived, sb.perceived) and sa.fixation == sb.fixation
    assert 0 <= sa.sharp_fraction <= 1
    given = a.step(fixation=(20.0, 30.0))
    assert tuple(given.fixation) == (20.0, 30.0)
    assert given.stats["step"] == 2 and given.stats["focus_px"] == [20.0, 30.0]
    # The fixated pixel is seen sharply, the far corner is not (or less)
    assert given.coc[30, 20] <= given.coc[119, 159] + 1e-6


def test_vision_takes_the_command_lines_eye_and_its_impairments(box):
    grey = foveal.VisionSimulation(box, eye="achromatopsia", size=(96, 64), device="cpu").step(fixation=(48.0, 32.0))
    p = grey.perceived
    assert np.allclose(p[:, :, 0], p[:, :, 1], atol=1e-5) and np.allclose(p[:, :, 1], p[:, :, 2], atol=1e-5)
    colour = grey.color  # the ray-cast colour stays coloured
    assert not np.allclose(colour[:, :, 0], colour[:, :, 2], atol=1e-3)
    with pytest.raises(ValueError, match="eye|preset|unknown"):
        foveal.VisionSimulation(box, eye="cvd:purple")


def test_a_profiles_pupil_is_kept_and_pupil_mm_overrides_it_as_on_the_command_line(cli, tmp_path):
    """The one rule for an eye: pupil_mm, when given (3.5, the default's value, too), beats the
    profile's pupil_mm, which beats the default; simulate --stats reports the same optics."""
    profile = tmp_path / "patient.json"
    profile.write_text('{"age": 40, "eyes": {"OD": {"pupil_mm": 5.5, "refraction": -1}}}')
    plane = foveal.Scene("builtin:plane")
    kept = foveal.VisionSimulation(plane, eye=str(profile), size=(48, 32), device="cpu")
    assert kept.optics["pupil_mm"] == 5.5 and kept.optics["refraction_d"] == -1
    assert foveal.VisionSimulation(plane, eye=str(profile), size=(48, 32), device="cpu", pupil_mm=3.5).optics["pupil_mm"] == 3.5
    assert foveal.VisionSimulation(plane, size=(48, 32), device="cpu").optics["pupil_mm"] == 3.5
    run_cli(cli, "simulate", "--scene", "builtin:plane", "--size", "48x32", "--steps", "1", "-q", "--eye", profile,
            "-o", tmp_path / "sim", "--stats", tmp_path / "sim.json")
    assert json.loads((tmp_path / "sim.json").read_text())["optics"] == kept.optics


def test_compare_equals_foveal_compare(cli, box, tmp_path):
    renderer = foveal.Renderer(box, device="cpu")
    fov = renderer.render(size=(160, 100), gaze=(40, 50), max_rays=32, seed=1)
    ref = renderer.render(size=(160, 100), gaze=(40, 50), max_rays=32, mode="full", seed=1)
    ref2 = renderer.render(size=(160, 100), gaze=(40, 50), max_rays=32, mode="full", seed=2)
    for name, frame in (("a", fov), ("b", ref), ("b2", ref2)):
        frame.save(str(tmp_path / f"{name}.pfm"))
    run_cli(cli, "compare", tmp_path / "a.pfm", tmp_path / "b.pfm", "--reference2", tmp_path / "b2.pfm", "--gaze", "40,50",
            "--json", tmp_path / "c.json", "-q")
    expected = json.loads((tmp_path / "c.json").read_text())
    got = foveal.compare(fov.image, ref.image, gaze=(40, 50), reference2=ref2.image)
    assert got["whole"]["rmse"] == pytest.approx(expected["whole"]["rmse"], rel=1e-12)
    assert got["acuity_weighted_ratio"] == pytest.approx(expected["acuity_weighted_ratio"], rel=1e-12)
    assert [b["name"] for b in got["bands"]] == [b["name"] for b in expected["bands"]]
    for g, e in zip(got["bands"], expected["bands"]):
        assert g["error"]["pixels"] == e["error"]["pixels"]
        assert g["error"]["ssim"] == pytest.approx(e["error"]["ssim"], rel=1e-12)
    same = foveal.compare(ref.image, ref.image)
    assert same["whole"]["rmse"] == 0 and same["whole"]["psnr_db"] == float("inf")
    with pytest.raises(ValueError):
        foveal.compare(ref.image, ref.image[:50])
