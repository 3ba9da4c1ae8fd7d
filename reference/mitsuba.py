"""Running Mitsuba 3 in-process on a converted scene, with its timings.

The first render of a scene in a process JIT-compiles its kernels (llvm variants); the second
is warm. ``compile_seconds`` is the first render's time beyond the warm one, ``render_seconds``
the warm render: report them apart (the compile costs 0.2-0.5 s a process, which would swamp a
small render's time).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

import converters.mitsuba as cm
from tracer.scene import Scene


@dataclass(frozen=True)
class MitsubaResult:
    image: npt.NDArray[np.float32]  # linear RGB, (height, width, 3)
    variant: str
    render_seconds: float  # a warm render
    compile_seconds: float  # the first render's extra time: JIT compilation
    load_seconds: float  # building the Mitsuba scene


def run_mitsuba(
    scene: Scene,
    *,
    variant: str | None = None,
    threads: int | None = None,
    warm: bool = True,
    edit: Callable[[dict[str, Any]], None] | None = None,
) -> MitsubaResult:
    """Render ``scene`` with Mitsuba's ``rtlab_classic`` integrator; twice if ``warm``.

    ``edit`` may change the converted dict before loading (the tests feed wrong conversions).
    """
    import drjit as dr
    import mitsuba as mi

    variant = cm.use_variant(variant)
    if threads is not None:
        dr.set_thread_count(threads)
    start = time.perf_counter()
    scene_dict = cm.to_mitsuba_dict(scene)
    if edit is not None:
        edit(scene_dict)
    mi_scene = mi.load_dict(scene_dict)
    load = time.perf_counter() - start
    start = time.perf_counter()
    image = np.array(mi.render(mi_scene), dtype=np.float32)
    first = time.perf_counter() - start
    render, compile_ = first, 0.0
    if warm:
        start = time.perf_counter()
        image = np.array(mi.render(mi_scene), dtype=np.float32)
        render = time.perf_counter() - start
        compile_ = max(first - render, 0.0)
    return MitsubaResult(image[..., :3], variant, render, compile_, load)
