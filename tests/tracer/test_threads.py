"""The same image whatever the thread count: per-pixel seeds, no shared random stream."""

from __future__ import annotations

import numpy as np

import tracer
from tracer.cli import demo_scene_path


def test_thread_count_does_not_change_the_image():
    scene = tracer.load_scene(demo_scene_path()).with_overrides(width=97, height=61, spp=5, seed=7)
    images = [tracer.render(scene, threads=t) for t in (1, 2, 3, 8)]
    for image in images[1:]:
        assert np.array_equal(image, images[0])


def test_jittered_samples_depend_on_the_seed():
    """So the test above is not vacuous: spp > 1 is random, and the seed changes the image."""
    scene = tracer.load_scene(demo_scene_path()).with_overrides(width=97, height=61, spp=5)
    a = tracer.render(scene.with_overrides(seed=1), threads=2)
    b = tracer.render(scene.with_overrides(seed=2), threads=2)
    assert not np.array_equal(a, b)
    assert np.abs(a - b).max() < 0.5  # but the same picture


def test_one_sample_is_the_pixel_centre_and_needs_no_seed():
    scene = tracer.load_scene(demo_scene_path()).with_overrides(width=64, height=48)
    a = tracer.render(scene.with_overrides(seed=1), threads=2)
    b = tracer.render(scene.with_overrides(seed=2), threads=1)
    assert np.array_equal(a, b)


def test_render_releases_the_gil():
    """While the core renders, other Python threads run: the render does not hold the GIL."""
    import threading

    scene = tracer.load_scene(demo_scene_path()).with_overrides(width=1600, height=1200, spp=4)
    done = threading.Event()
    ticks = 0

    def work():
        tracer.render(scene, threads=1, progress=False)
        done.set()

    worker = threading.Thread(target=work)
    worker.start()
    while not done.is_set():  # pure Python: it only advances while the GIL is free
        ticks += 1
    worker.join()
    assert ticks > 10_000
