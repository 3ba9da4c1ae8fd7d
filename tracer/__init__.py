"""rtlab's ray tracer: the course's classic algorithm, in C++, with a Python face."""

import os as _os
import sys as _sys

# numpy's BLAS (OpenBLAS) starts a worker thread per core when numpy is first imported, and each
# worker spins for a while after start-up and after every threaded BLAS call, on the cores the
# render's own threads need. Measured on 2 cores (issue 12): 30-55 ms of spinning during
# `import tracer`, and 150-310 ms after each anaglyph composition (render.py anaglyph(), a
# (pixels, 3) @ (3, 3) product, the one BLAS call here large enough to be threaded), which
# itself took 220-520 ms on two BLAS threads and 14-25 ms on one (the same bits). Nothing in
# rtlab gains from BLAS threads, so one is the default; a user's own OPENBLAS_NUM_THREADS,
# GOTO_NUM_THREADS or OMP_NUM_THREADS (which OpenBLAS reads in that order) wins, and once numpy
# is imported OpenBLAS has read them already, so they are left alone.
if "numpy" not in _sys.modules and not any(
    v in _os.environ for v in ("OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "OMP_NUM_THREADS")
):
    _os.environ["OPENBLAS_NUM_THREADS"] = "1"

from tracer.display import Picture, picture, show
from tracer.image import load_exr_channels, load_image, save_aov, save_image
from tracer.render import ImageTooLargeError, RenderResult, aov_channels, render, render_with_stats
from tracer.scene import Scene, SceneError, load_scene

__all__ = [
    "ImageTooLargeError",
    "Picture",
    "RenderResult",
    "Scene",
    "SceneError",
    "aov_channels",
    "load_exr_channels",
    "load_image",
    "load_scene",
    "picture",
    "render",
    "render_with_stats",
    "save_aov",
    "save_image",
    "show",
]
