"""Which objects may be shared between Python threads (docs/python.md, "Threads"): every one either
serialises its calls or is immutable; the GIL is released while the library works."""
import threading

import numpy as np
import pytest

import foveal


@pytest.fixture(scope="module")
def box():
    return foveal.Scene("builtin:box")


def _run(workers):
    errors = []

    def wrap(work):
        def run():
            try:
                work()
            except BaseException as error:  # noqa: BLE001 - reported below
                errors.append(error)
        return run

    threads = [threading.Thread(target=wrap(w)) for w in workers]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    if errors:
        raise errors[0]


def test_three_threads_stepping_one_simulation_each_get_their_own_step(box):
    # Each step's result must be the step the thread asked for: its fixation, and the very images a
    # simulation stepped alone through the same fixations in the same order gives (no other
    # thread's step in between, no state torn by two steps at once)
    size, seed = (128, 96), 5
    sim = foveal.VisionSimulation(box, size=size, seed=seed, device="cpu", threads=1)
    results = []

    def worker(k):
        def work():
            for i in range(5):
                target = (10.0 + 30.0 * k + i, 12.0 + 20.0 * k)
                step = sim.step(fixation=target)
                results.append((step.stats["step"], target, tuple(step.fixation), step.perceived.copy()))
        return work

    _run([worker(k) for k in range(3)])
    results.sort(key=lambda r: r[0])
    assert [r[0] for r in results] == list(range(1, 16)), "every step taken once"
    alone = foveal.VisionSimulation(box, size=size, seed=seed, device="cpu", threads=1)
    for number, target, fixation, perceived in results:
        assert fixation == target, f"step {number} asked for {target}, got {fixation}"
        assert np.array_equal(alone.step(fixation=target).perceived, perceived), f"step {number}'s image is not its own"


def test_one_renderer_shared_by_threads_renders_what_each_asked(box):
    renderer = foveal.Renderer(box, device="cpu", threads=1)
    alone = {k: renderer.render(size=(64, 40), gaze=(8.0 + 20 * k, 20.0), max_rays=8, seed=k).image.copy() for k in range(3)}
    together = {}

    def worker(k):
        def work():
            together[k] = renderer.render(size=(64, 40), gaze=(8.0 + 20 * k, 20.0), max_rays=8, seed=k).image.copy()
        return work

    _run([worker(k) for k in range(3)])
    for k in range(3):
        assert np.array_equal(alone[k], together[k])


def test_perceive_and_events_run_in_threads_alike(box):
    image = np.random.default_rng(1).random((48, 64, 3), dtype=np.float32)
    alone = foveal.perceive(image, eye="cataract:0.5", gaze=(20, 20), threads=1)
    out = [None] * 3

    def worker(k):
        def work():
            out[k] = foveal.perceive(image, eye="cataract:0.5", gaze=(20, 20), threads=1)
        return work

    _run([worker(k) for k in range(3)])
    for k in range(3):
        assert np.array_equal(out[k], alone)
