"""Speed, side by side: ``rtlab bench SUITE --json FILE`` (a benchmark, not a test).

Every row has ``case``, ``renderer``, ``threads``, ``metric``, ``value`` and ``unit``, plus
``repeats`` and ``machine``. Times are the best of several runs in one process, interleaved by
renderer, so that ratios taken within one run hold even when the shared machine's absolute
speed drifts. Renderers: ``rtlab``, ``povray`` (its own Trace Time of one pass, start-up
excluded), ``mitsuba-llvm`` (a warm render, JIT compile excluded), ``mitsuba-scalar``, and in
the convergence suite ``mitsuba-llvm-stratified`` (Mitsuba's stratified sampler, the strata
rtlab draws: reference/convergence.py MITSUBA).
"""

from __future__ import annotations

import json
import os
import platform
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from tracer.image import atomic_path
from tracer.render import render_with_stats
from tracer.scene import load_scene
from tracer.scenes import demo_scene_path


def machine() -> str:
    model = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{model}, {os.cpu_count()} cores, {platform.system()} {platform.release()}"


def _best(fn: Callable[[], float], repeats: int) -> float:
    return min(fn() for _ in range(repeats))


def suite_classic(
    repeats: int = 3, threads: tuple[int, ...] = (1, 2), width: int = 1920, height: int = 1024
) -> list[dict[str, Any]]:
    """The demo scene (Ex 25) at 1920x1024, 1 spp: seconds per frame."""
    from reference.mitsuba import run_mitsuba
    from reference.povray import run_povray

    scene = load_scene(demo_scene_path()).with_overrides(width=width, height=height, spp=1)
    case = f"ex25-{width}x{height}"
    rows = []
    for n in threads:
        times = {
            # rtlab's frame is short, so the shared machine's hiccups weigh more: more repeats.
            "rtlab": _best(
                lambda n=n: render_with_stats(scene, threads=n, progress=False).seconds,
                2 * repeats + 1,
            ),
            "povray": _best(
                lambda n=n: run_povray(scene, threads=n, exr_pass=False).trace_seconds,
                max(1, repeats - 1),
            ),
            "mitsuba-llvm": _best(
                lambda n=n: run_mitsuba(scene, variant="llvm_ad_rgb", threads=n).render_seconds,
                max(1, repeats - 1),
            ),
        }
        for renderer, value in times.items():
            rows.append({"case": case, "renderer": renderer, "threads": n, "metric": "seconds",
                         "value": value, "unit": "s", "repeats": repeats})  # fmt: skip
    return rows


def _camera_rays(scene: Any) -> tuple[np.ndarray, np.ndarray]:
    """The primary rays through the pixel centres (03_camera.h's formula), as float32 arrays."""
    cam = scene.camera
    eye = np.asarray(cam.eye, dtype=np.float64)
    forward = np.asarray(cam.look_at) - eye
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, cam.up)
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    h = 2 * np.tan(np.radians(cam.fov_y) / 2)
    w = h * cam.width / cam.height
    x = (np.arange(cam.width) + 0.5) / cam.width - 0.5
    y = 0.5 - (np.arange(cam.height) + 0.5) / cam.height
    xx, yy = np.meshgrid(x * w, y * h)
    d = forward + xx[..., None] * right + yy[..., None] * up
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    d = np.ascontiguousarray(d.reshape(-1, 3), dtype=np.float32)
    o = np.ascontiguousarray(np.broadcast_to(eye, d.shape), dtype=np.float32)
    return o, d


def suite_geometry(
    repeats: int = 3, threads: tuple[int, ...] = (1, 2), width: int = 1920, height: int = 1024
) -> list[dict[str, Any]]:
    """Primary rays per second on the Stanford bunny (99,785 triangles), closest hit only:
    rtlab's aov integrator (its hierarchy, double precision, watertight) against Embree's
    single-ray kernel (embreex, robust=False, float), plus each one's hierarchy build time."""
    import dataclasses
    import threading
    import time

    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh

    from tracer.render import to_core
    from tracer.scene import Mesh

    root = Path(__file__).resolve().parent
    scene = load_scene(root / "scenes" / "bunny.toml").with_overrides(
        width=width, height=height, integrator="aov"
    )
    # The bunny alone: what Embree is given too.
    meshes = tuple(o for o in scene.objects if isinstance(o, Mesh))
    bunny_only = dataclasses.replace(scene, objects=meshes)
    mesh = meshes[0]
    case, n_rays = "bunny-primary", width * height
    rows: list[dict[str, Any]] = []

    def build_rtlab() -> float:
        start = time.perf_counter()
        to_core(bunny_only)
        return time.perf_counter() - start

    triangles_f32 = np.ascontiguousarray(mesh.vertices[mesh.faces], dtype=np.float32)

    def build_embree() -> tuple[Any, float]:
        start = time.perf_counter()
        embree = rtcore_scene.EmbreeScene(robust=False)
        TriangleMesh(embree, triangles_f32)
        embree.run(np.zeros((1, 3), np.float32), np.array([[0, 0, 1]], np.float32))  # commit
        return embree, time.perf_counter() - start

    origins, directions = _camera_rays(bunny_only)
    embree, _ = build_embree()

    def embree_seconds(n: int) -> float:
        parts = np.array_split(np.arange(n_rays), n)
        work = [threading.Thread(target=lambda p=p: embree.run(
            origins[p[0]:p[-1] + 1], directions[p[0]:p[-1] + 1], query="INTERSECT", output=1))
            for p in parts]  # fmt: skip
        start = time.perf_counter()
        for t in work:
            t.start()
        for t in work:
            t.join()
        return time.perf_counter() - start

    for n in threads:
        ours = _best(lambda n=n: render_with_stats(bunny_only, threads=n, progress=False).seconds,
                     2 * repeats + 1)  # fmt: skip
        theirs = _best(lambda n=n: embree_seconds(n), 2 * repeats + 1)
        for renderer, seconds in (("rtlab", ours), ("embree", theirs)):
            rows.append({"case": case, "renderer": renderer, "threads": n,
                         "metric": "mrays_per_s", "value": n_rays / seconds / 1e6,
                         "unit": "Mrays/s", "repeats": 2 * repeats + 1})  # fmt: skip
    for renderer, fn in (("rtlab", build_rtlab), ("embree", lambda: build_embree()[1])):
        rows.append({"case": "bunny-bvh-build", "renderer": renderer, "threads": 1,
                     "metric": "seconds", "value": _best(fn, repeats), "unit": "s",
                     "repeats": repeats, "triangles": len(mesh.faces)})  # fmt: skip
    return rows


def suite_convergence(out_dir: str | os.PathLike[str] = "out") -> list[dict[str, Any]]:
    """Error against run time (reference/convergence.py): the Cornell box path traced by rtlab
    and Mitsuba, and the demo scene antialiased by rtlab, POV-Ray and Mitsuba; writes a log-log
    plot per case beside the JSON and prints the time each renderer needs to reach an error."""
    from reference.convergence import convergence, convergence_classic, plot, summary

    rows = []
    cases = (("cornell", convergence()),
             ("cornell-128", convergence(width=128, height=128,
                                         renderers=("rtlab", "mitsuba-llvm",
                                                    "mitsuba-llvm-stratified"))),
             ("ex25", convergence_classic()))  # fmt: skip
    for name, made in cases:
        path = Path(out_dir) / f"convergence-{name}.png"
        plot(made, path)
        print(summary(made))
        print(f"plot: {path}")
        rows += made
    return rows


SUITES: dict[str, Callable[..., list[dict[str, Any]]]] = {
    "classic": suite_classic,
    "geometry": suite_geometry,
    "convergence": suite_convergence,
    "grading": lambda: __import__("lessons.bench").bench.suite_grading(),  # lessons/bench.py
    "report": lambda: __import__("reports.bench").bench.suite_report(),  # reports/bench.py
}


class UnknownSuiteError(ValueError):
    """A benchmark suite that does not exist: a usage error, not a fault of any scene."""


def run_suites(names: list[str], json_path: str | os.PathLike[str] | None) -> list[dict]:
    unknown = [n for n in names if n not in SUITES]
    if unknown:
        raise UnknownSuiteError(f"unknown suite {unknown[0]!r}; expected {', '.join(SUITES)}")
    rows: list[dict[str, Any]] = []
    where = machine()
    for name in names:
        suite = SUITES[name]
        made = (
            suite(out_dir=Path(json_path).parent)
            if name == "convergence" and json_path
            else suite()
        )
        for row in made:
            row["suite"] = name
            row["machine"] = where
            rows.append(row)
    if json_path is not None:
        with atomic_path(json_path) as tmp:
            tmp.write_text(json.dumps(rows, indent=2) + "\n")
    return rows


def format_ratios(rows: list[dict[str, Any]]) -> str:
    """Each case and thread count: every renderer's value and its ratio to rtlab's."""
    lines = []
    rows = [r for r in rows if r["metric"] != "rmse"]  # convergence rows print their own summary
    keys = sorted({(r["case"], r["threads"], r["metric"]) for r in rows})
    for case, threads, metric in keys:
        group = {r["renderer"]: r for r in rows if (r["case"], r["threads"], r["metric"]) ==
                 (case, threads, metric)}  # fmt: skip
        ours = group.get("rtlab")
        lines.append(f"{case}, {threads} thread{'s' if threads > 1 else ''} ({metric}):")
        for name, r in group.items():
            ratio = ""
            if ours is not None and name != "rtlab":
                # seconds: how many times slower the other is; throughput: how many times faster
                x = r["value"] / ours["value"] if r["unit"] == "s" else ours["value"] / r["value"]
                ratio = (
                    f"   rtlab is {x:.2f}x faster" if x >= 1 else f"   rtlab is {1 / x:.2f}x slower"
                )
            lines.append(f"  {name:<16}{r['value']:>10.4f} {r['unit']}{ratio}")
    if rows:
        lines.append(f"machine: {rows[0]['machine']}")
    return "\n".join(lines)
