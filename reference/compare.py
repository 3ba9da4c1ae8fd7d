"""Render one scene with rtlab and the references, compare, and report.

Used by ``rtlab compare`` and ``make demo``: each renderer's image (EXR, and PNG to look at), a
heat map of |difference| for each reference against rtlab, a table, and a JSON file.
"""

from __future__ import annotations

import json
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from reference.metrics import (
    FLOAT32_SLACK,
    MAX_SHARE_OVER,
    MAX_SHARE_TESSELLATED,
    MITSUBA_TOLERANCE,
    agrees,
    compare,
    heat_map,
)
from tracer.image import atomic_path, save_image
from tracer.render import eye_scene, render_with_stats
from tracer.scene import Scene, Torus

REFERENCES = ("povray", "mitsuba")


@dataclass
class Run:
    renderer: str
    image: npt.NDArray[np.float32]
    trace_seconds: float  # the render itself (POV-Ray's Trace Time; Mitsuba's warm render)
    whole_seconds: float  # everything: start-up, parsing or loading, JIT, writing aside
    tolerance: float | npt.NDArray[np.floating] = 0.0
    notes: dict[str, Any] = field(default_factory=dict)


def run_rtlab(scene: Scene, threads: int | None = None, progress: bool | None = False) -> Run:
    start = time.perf_counter()
    result = render_with_stats(scene, threads=threads, progress=progress)
    return Run("rtlab", result.image, result.seconds, time.perf_counter() - start,
               notes={"rays": result.rays, "threads": result.threads})  # fmt: skip


def run_reference(name: str, scene: Scene, threads: int | None = None) -> Run:
    if name == "povray":
        from reference.povray import run_povray

        pov = run_povray(scene, threads=threads or os.cpu_count() or 1)
        return Run("povray", pov.image, pov.trace_seconds, pov.total_seconds,
                   pov.error_bound + FLOAT32_SLACK, notes={"rays": pov.rays})  # fmt: skip
    if name == "mitsuba":
        from reference.mitsuba import run_mitsuba

        start = time.perf_counter()
        mi = run_mitsuba(scene, threads=threads)
        whole = mi.load_seconds + mi.compile_seconds + mi.render_seconds
        return Run(f"mitsuba-{mi.variant.split('_')[0]}", mi.image, mi.render_seconds, whole,
                   MITSUBA_TOLERANCE,
                   notes={"variant": mi.variant, "compile_seconds": mi.compile_seconds,
                          "measured_seconds": time.perf_counter() - start})  # fmt: skip
    raise ValueError(f"unknown reference renderer {name!r}; expected one of {REFERENCES}")


def share_bound(scene: Scene, renderer: str) -> float:
    """The share of pixels over tolerance the agreement rule allows (reference/metrics.py):
    tori are tessellated for Mitsuba, so their silhouettes get the larger, argued bound."""
    tori = any(isinstance(obj, Torus) for obj in scene.objects)
    return MAX_SHARE_TESSELLATED if tori and renderer.startswith("mitsuba") else MAX_SHARE_OVER


def verdict(scene: Scene, run: Run, ours: Run) -> tuple[bool | None, str]:
    """Whether ``run`` agrees with rtlab's image by the rule of the reference tests
    (metrics.agrees), and why. None, no verdict, where the images differ by their sampling
    noise: a path-traced scene (compared statistically instead, reference/stats.py) and a
    classic one at spp > 1 (each renderer jitters its own samples; POV-Ray here takes one)."""
    if scene.render.integrator == "path":
        return None, "no verdict: path-traced images are compared statistically (stats.py)"
    if scene.render.spp > 1:
        return None, "no verdict: antialiased images differ by their jittered samples"
    return agrees(run.image, ours.image, run.tolerance, share_bound(scene, run.renderer))


def compare_scene(
    scene: Scene,
    against: tuple[str, ...] = REFERENCES,
    *,
    out_dir: str | os.PathLike[str] | None = None,
    json_path: str | os.PathLike[str] | None = None,
    threads: int | None = None,
    stem: str | None = None,
    progress: bool | None = False,
    written: list[Path] | None = None,
) -> list[dict[str, Any]]:
    """Render with rtlab and each reference; one row per renderer (rtlab first). A reference's
    row says whether it ``agrees`` with rtlab (True, False, or None: no verdict) and why
    (``verdict``). ``progress`` shows a bar for rtlab's render; every file written is appended
    to ``written``, each complete (written atomically)."""
    stem = stem or Path(scene.source).stem or "scene"
    written = [] if written is None else written
    st = scene.camera.stereo
    if st is not None and st.layout not in ("left", "right"):
        # A stereo pair: each eye compared on its own, as the references render one camera
        # (tracer.render.eye_scene); the rows say which eye.
        rows = []
        for eye in ("left", "right"):
            rows += compare_scene(eye_scene(scene, eye), against, out_dir=out_dir,
                                  threads=threads, stem=f"{stem}-{eye}", progress=progress,
                                  written=written)  # fmt: skip
        _write_json(rows, json_path, written)
        return rows
    ours = run_rtlab(scene, threads, progress)
    runs = [ours] + [run_reference(name, scene, threads) for name in against]
    rows: list[dict[str, Any]] = []
    out = Path(out_dir) if out_dir is not None else None
    for run in runs:
        row: dict[str, Any] = {
            "scene": scene.source,
            "renderer": run.renderer,
            "width": scene.camera.width,
            "height": scene.camera.height,
            "trace_seconds": run.trace_seconds,
            "whole_seconds": run.whole_seconds,
            **run.notes,
        }
        if st is not None:
            row["eye"] = st.layout
        if run is not ours:
            row.update(compare(run.image, ours.image, run.tolerance).as_dict())
            row["tolerance"] = (
                "per-pixel output precision" if run.renderer == "povray" else (MITSUBA_TOLERANCE)
            )
            row["agrees"], row["verdict"] = verdict(scene, run, ours)
            if st is not None:
                row["verdict"] = f"{st.layout} eye: {row['verdict']}"
        if out is not None:
            for suffix in (".exr", ".png"):
                written.append(save_image(out / f"{stem}-{run.renderer}{suffix}", run.image))
            row["image"] = str(out / f"{stem}-{run.renderer}.exr")
            if run is not ours:
                diff = out / f"{stem}-diff-{run.renderer}.png"
                heat_map(run.image, ours.image, diff)
                written.append(diff)
                row["heat_map"] = str(diff)
        rows.append(row)
    _write_json(rows, json_path, written)
    return rows


def _write_json(
    rows: list[dict[str, Any]], json_path: str | os.PathLike[str] | None, written: list[Path]
) -> None:
    if json_path is not None:
        with atomic_path(json_path) as tmp:
            tmp.write_text(json.dumps(_jsonable(rows), indent=2) + "\n")
        written.append(Path(json_path))


def _jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)  # JSON has no inf (a PSNR of identical images)
    if isinstance(value, np.generic):
        return value.item()
    return value


def format_table(rows: list[dict[str, Any]]) -> str:
    """The comparison as a plain-text table, rtlab's time first, each reference against it."""
    eyes = any("eye" in r for r in rows)  # a stereo pair: the renderer column names the eye
    head = (f"{'renderer':<14}{'RMSE':>10}{'max abs':>10}{'PSNR dB':>9}{'SSIM':>8}{'FLIP':>8}"
            f"{'over tol':>10}{'trace s':>9}{'whole s':>9}{'agrees':>8}")  # fmt: skip
    lines = [head, "-" * len(head)]
    for r in rows:
        if "rmse" in r:
            over = 100 * r["over_tolerance"]
            metrics = (f"{r['rmse']:>10.2e}{r['max_abs']:>10.2e}{r['psnr']:>9.1f}"
                       f"{r['ssim']:>8.5f}{r['flip']:>8.5f}{over:>9.3f}%")  # fmt: skip
        else:
            metrics = f"{'(reference of the comparison)':>55}"
        agreed = {True: "yes", False: "NO", None: "-"}[r.get("agrees")]
        name = f"{r['eye'][0].upper()} {r['renderer']}" if eyes else r["renderer"]
        lines.append(
            f"{name:<14}{metrics}{r['trace_seconds']:>9.3f}{r['whole_seconds']:>9.3f}{agreed:>8}"
        )
    return "\n".join(lines)
