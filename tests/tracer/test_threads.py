"""The same image whatever the thread count: per-pixel seeds, no shared random stream."""

from __future__ import annotations

import numpy as np

import tracer
from tests.helpers import SCENES

SCENE = SCENES / "ex25.toml"  # the course's Ex 25, as the demo renders it


def test_thread_count_does_not_change_the_image():
    # 97 x 61 is 28 tiles of 16 x 16: enough for one thread, too few for two or more, which
    # get tiles of 8 x 8 (11_render.h tile_side()), so the tile size changes here too.
    scene = tracer.load_scene(SCENE).with_overrides(width=97, height=61, spp=5, seed=7)
    images = [tracer.render(scene, threads=t) for t in (1, 2, 3, 8)]
    for image in images[1:]:
        assert np.array_equal(image, images[0])


def test_jittered_samples_depend_on_the_seed():
    """So the test above is not vacuous: spp > 1 is random, and the seed changes the image."""
    scene = tracer.load_scene(SCENE).with_overrides(width=97, height=61, spp=5)
    a = tracer.render(scene.with_overrides(seed=1), threads=2)
    b = tracer.render(scene.with_overrides(seed=2), threads=2)
    assert not np.array_equal(a, b)
    assert np.abs(a - b).max() < 0.5  # but the same picture


def test_one_sample_is_the_pixel_centre_and_needs_no_seed():
    scene = tracer.load_scene(SCENE).with_overrides(width=64, height=48)
    a = tracer.render(scene.with_overrides(seed=1), threads=2)
    b = tracer.render(scene.with_overrides(seed=2), threads=1)
    assert np.array_equal(a, b)


def test_render_releases_the_gil():
    """While the core renders, other Python threads run: the render does not hold the GIL.

    The main thread counts in a loop that gives up the GIL at every turn (time.sleep), and the
    render's progress callback, which the core calls with the GIL every 100 ms, notes the
    count. If the render released the GIL, the count moves on between two calls; if it held it,
    the main thread could never take it back, since the callback only runs Python code and the
    switch interval is set longer than the test, so nothing forces the GIL away from it."""
    import sys
    import threading
    import time

    from tracer import _core
    from tracer.render import to_core

    scene = tracer.load_scene(SCENE).with_overrides(width=1600, height=1200, spp=4)
    core = to_core(scene)
    done = threading.Event()
    turns = 0
    seen: list[int] = []  # the main thread's count at each progress call during the render

    def progress(tiles_done: int, tiles_total: int) -> None:
        if tiles_done < tiles_total:
            seen.append(turns)

    def work() -> None:
        try:
            _core.render(core, 1, progress, _core.Integrator.classic)
        finally:
            done.set()

    interval = sys.getswitchinterval()
    sys.setswitchinterval(1000.0)  # seconds: no forced hand-over of the GIL during the test
    try:
        worker = threading.Thread(target=work)
        worker.start()
        while not done.is_set():
            turns += 1
            time.sleep(0.001)  # releases the GIL, and must take it back to go on
        worker.join()
    finally:
        sys.setswitchinterval(interval)
    assert len(seen) >= 3, f"the render took too few polls to tell ({len(seen)})"
    assert seen[-1] > seen[0], f"no Python ran while the core rendered: {seen}"


def _blas_env_after_import(env: dict[str, str], first: str) -> tuple[str, int]:
    """In a fresh interpreter: import `first`, then numpy; OPENBLAS_NUM_THREADS as it is then,
    and how many threads the process has (OpenBLAS starts one per extra BLAS thread)."""
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if not k.endswith("_NUM_THREADS")} | env
    code = (f"import {first}, numpy, os; print(os.environ.get('OPENBLAS_NUM_THREADS', '-'),"
            " len(os.listdir('/proc/self/task')))")  # fmt: skip
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, check=True).stdout.split()  # fmt: skip
    return out[0], int(out[1])


def test_import_tracer_keeps_blas_to_one_thread_unless_the_user_chose():
    """tracer/__init__.py: OpenBLAS's spinning workers would take the cores a render needs."""
    import os

    if not os.path.isdir("/proc/self/task"):
        import pytest

        pytest.skip("counts threads through Linux's /proc")
    assert _blas_env_after_import({}, "tracer") == ("1", 1)
    # The user's choice wins, and so (a check that OpenBLAS does start workers, so that the
    # count above could have been larger) does numpy imported before tracer.
    assert _blas_env_after_import({"OPENBLAS_NUM_THREADS": "2"}, "tracer") == ("2", 2)
    assert _blas_env_after_import({"OMP_NUM_THREADS": "2"}, "tracer")[0] == "-"
    blas, threads = _blas_env_after_import({}, "numpy, tracer")
    assert blas == "-" and (threads > 1 or (os.cpu_count() or 1) == 1)


def test_a_reused_image_buffer_never_changes_a_live_image():
    """bindings.cpp keeps the last image freed for the next render of its size: an image still
    held must not be written by the next render, and a reused buffer's old pixels never show."""
    scene = tracer.load_scene(SCENE).with_overrides(width=97, height=61, spp=1)
    first = tracer.render(scene, threads=2)
    kept = first.copy()
    other = tracer.render(scene.with_overrides(spp=3, seed=5), threads=2)  # same size
    assert not np.array_equal(other, kept)  # so an overwrite of `first` would show
    assert np.array_equal(first, kept)
    del first, other  # both buffers freed: the next render of this size reuses one
    assert np.array_equal(tracer.render(scene, threads=2), kept)
    small = scene.with_overrides(width=33, height=17)
    assert tracer.render(small, threads=2).shape == (17, 33, 3)  # another size: a fresh one


def test_the_convergence_suite_times_the_path_tracer_on_one_and_two_threads():
    """reference/bench.py cornell_scaling(): rows that thread_scaling() pairs (one case and
    metric, threads 1 and 2), so the convergence suite prints its gain from the second thread."""
    from reference.bench import cornell_scaling, thread_scaling

    rows = cornell_scaling(sizes=(8,), spp=2, repeats=1)
    assert sorted(r["threads"] for r in rows) == [1, 2]
    assert all(r["value"] > 0 and r["unit"] == "s" for r in rows)
    assert list(thread_scaling(rows)) == [("", "cornell_box-8x8-2spp", "rtlab")]


def test_every_tile_is_written_whatever_the_threads():
    """The workers take runs of tiles (11_render.h); a tile no run covered would keep what the
    image's memory held before. The core reuses the memory of the last image freed of the same
    size, so each render below starts from another scene's pixels: a tile left out shows them."""
    scene = tracer.load_scene(SCENE).with_overrides(width=203, height=157)
    other = scene.with_overrides(max_depth=1, background=(1.0, 0.0, 1.0))  # another picture
    expected = tracer.render(scene, threads=1)
    for threads in (2, 3, 8):
        stale = tracer.render(other, threads=threads)
        assert not np.array_equal(stale, expected)  # so a tile left out would show
        memory = stale.__array_interface__["data"][0]
        del stale  # its memory is the next render's
        image = tracer.render(scene, threads=threads)
        assert image.__array_interface__["data"][0] == memory  # it was: the stale pixels were there
        assert np.array_equal(image, expected)
