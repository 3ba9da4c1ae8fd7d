"""Speed, side by side: ``rtlab bench SUITE --json FILE`` (a benchmark, not a test).

Every row has ``case``, ``renderer``, ``threads``, ``metric``, ``value`` and ``unit``, plus
``repeats`` and ``machine`` (and ``run``, its run's number, from ``--runs N``; several runs
are summarised by ``--runs`` or ``rtlab bench --summarize FILE...``: summarize_runs()).
Times are the best of several runs in one process, interleaved by renderer, so that ratios
taken within one run hold even when the shared machine's absolute speed drifts. Renderers:
``rtlab``, ``povray`` (its own Trace Time of one pass, start-up excluded), ``mitsuba-llvm``
(a warm render, JIT compile excluded), ``mitsuba-scalar``, and in the convergence suite
``mitsuba-llvm-stratified`` (Mitsuba's stratified sampler, the strata rtlab draws:
reference/convergence.py MITSUBA).
"""

from __future__ import annotations

import json
import os
import platform
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from tracer import interrupt
from tracer.image import atomic_path
from tracer.render import default_threads, render_with_stats
from tracer.scene import load_scene
from tracer.scenes import demo_scene_path


def _cpuinfo() -> dict[str, str]:
    """The first processor's fields of /proc/cpuinfo ({} where there is none)."""
    fields: dict[str, str] = {}
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return fields
    for line in text.splitlines():
        if not line.strip():
            break  # the end of the first processor's block
        key, _, value = line.partition(":")
        fields.setdefault(key.strip(), value.strip())
    return fields


# The flags that say which vector units the kernels can use (the core is built with
# -march=native): SSE, AVX, AVX2, AVX-512, FMA and their kin. The whole flag list, a hundred
# words, says no more about these benchmarks.
_VECTOR_FLAG = ("sse", "ssse", "avx", "fma", "f16c", "amx")


# Intel's family 6 models with AVX-512 and no AMX, by model number, as LLVM names their cores.
_INTEL_AVX512 = {85: "skylake-avx512", 106: "icelake-server", 108: "icelake-server",
                 125: "icelake-client", 126: "icelake-client", 140: "tigerlake",
                 141: "tigerlake", 167: "rocketlake"}  # fmt: skip


def cpu_core(info: dict[str, str]) -> str:
    """The processor's core as LLVM names it (its -march / llvm-mca -mcpu value), from the
    fields of /proc/cpuinfo; "" where they do not say. The flags come first: a hypervisor may
    report another model's numbers. This machine class's Xeon reports family 6 model 167
    (Rocket Lake) but has AMX and AVX512-FP16, which no Rocket Lake has, and 48 KiB of L1 data
    cache and 2 MiB of L2 a core: a Sapphire Rapids or later Xeon (Golden Cove or Redwood Cove
    cores; LLVM's scheduling model is one for all of them), whose 512-bit adds and multiplies
    issue on two ports where Rocket Lake's issue on one."""
    flags = set(info.get("flags", "").split())
    try:
        family, model = int(info["cpu family"]), int(info["model"])
    except (KeyError, ValueError):
        return ""
    vendor = info.get("vendor_id", "")
    if vendor == "GenuineIntel" and family == 6:
        if "amx_tile" in flags:
            return "sapphirerapids"
        return _INTEL_AVX512.get(model, "") if "avx512f" in flags else ""
    if vendor == "AuthenticAMD":
        if family == 26:
            return "znver5"
        if family == 25:  # Zen 4: Genoa, Bergamo, Raphael, Phoenix; the rest Zen 3
            zen4 = 0x10 <= model <= 0x1F or 0x60 <= model <= 0x7F or 0xA0 <= model <= 0xAF
            return "znver4" if zen4 else "znver3"
        if family == 23:
            return "znver2" if model >= 0x30 else "znver1"
    return ""


def cpu() -> dict[str, Any]:
    """The CPU the figures were measured on: its model, its vector-unit flags, its cores, and
    its core as LLVM names it (cpu_core())."""
    info = _cpuinfo()
    flags = sorted(f for f in info.get("flags", "").split() if f.startswith(_VECTOR_FLAG))
    model = info.get("model name") or platform.processor() or platform.machine()
    # A virtual machine may name only the brand ("AMD EPYC"); the vendor's family and model
    # numbers still tell the generation (AMD family 25 is Zen 3 and 4, 26 is Zen 5).
    numbers = [f"{k} {info[k]}" for k in ("cpu family", "model", "stepping") if k in info]
    if numbers:
        model += f" ({info.get('vendor_id', '')} {', '.join(numbers)})".replace("( ", "(")
    return {
        "cpu_model": model,
        "cpu_flags": flags,
        "cpu_count": os.cpu_count(),
        "cpu_core": cpu_core(info),
    }


def compiler() -> str:
    """The compiler that built the core, as it names itself (GCC: its version alone, "12.2.0";
    Clang: "Debian Clang 19.1.7 ..."): the same source runs at different speeds under each."""
    from tracer import _core

    version = str(_core.compiler)
    return f"GCC {version}" if _core.compiler_family == "gcc" else version


def machine() -> str:
    model = cpu()["cpu_model"]
    return f"{model}, {os.cpu_count()} cores, {platform.system()} {platform.release()}"


def _best(fn: Callable[[], float], repeats: int) -> float:
    return min(fn() for _ in range(repeats))


def _best_alternating(runs: dict[str, tuple[Callable[[], float], int]]) -> dict[str, float]:
    """Each renderer's fastest of its repeats, the renderers taking turns (one run each per
    round, until each has made its repeats) rather than one after another: a shared machine's
    speed drifts over seconds (by 20% on these machines), and renderers timed in different
    seconds would carry that drift into their ratio."""
    times: dict[str, list[float]] = {name: [] for name in runs}
    for round_ in range(max(repeats for _, repeats in runs.values())):
        for name, (fn, repeats) in runs.items():
            if round_ < repeats:
                # A Ctrl-C lost in a finaliser (a POV-Ray run's temporary directory's:
                # tracer/interrupt.py) stops the bench here, not minutes later at its end.
                interrupt.raise_if_interrupted()
                times[name].append(fn())
    return {name: min(t) for name, t in times.items()}


def ex25_scene(width: int = 1920, height: int = 1024) -> Any:
    """The demo scene (Ex 25) at width x height, 1 spp: the classic suite's frame."""
    return load_scene(demo_scene_path()).with_overrides(width=width, height=height, spp=1)


def cornell_scene(size: int, spp: int = 64) -> Any:
    """The Cornell box at size x size, spp samples a pixel: the convergence suite's scaling."""
    scene = load_scene(Path(__file__).resolve().parent / "scenes" / "cornell_box.toml")
    return scene.with_overrides(width=size, height=size, spp=spp)


def suite_classic(
    repeats: int = 3, threads: tuple[int, ...] = (1, 2), width: int = 1920, height: int = 1024
) -> list[dict[str, Any]]:
    """The demo scene (Ex 25) at 1920x1024, 1 spp: seconds per frame."""
    from reference.mitsuba import run_mitsuba
    from reference.povray import run_povray

    scene = ex25_scene(width, height)
    case = f"ex25-{width}x{height}"
    rows = []
    for n in threads:
        times = _best_alternating(
            {
                # rtlab's frame is short, so the shared machine's hiccups weigh more: more repeats.
                "rtlab": (
                    lambda n=n: render_with_stats(scene, threads=n, progress=False).seconds,
                    2 * repeats + 1,
                ),
                "povray": (
                    lambda n=n: run_povray(scene, threads=n, exr_pass=False).trace_seconds,
                    max(1, repeats - 1),
                ),
                "mitsuba-llvm": (
                    lambda n=n: run_mitsuba(scene, variant="llvm_ad_rgb", threads=n).render_seconds,
                    max(1, repeats - 1),
                ),
            }
        )
        for renderer, value in times.items():
            rows.append({"case": case, "renderer": renderer, "threads": n, "metric": "seconds",
                         "value": value, "unit": "s", "repeats": repeats})  # fmt: skip
    return rows


def camera_frame(cam: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float, float]:
    """03_camera.h Camera::initialize() for a scene's camera: the eye, the unit vectors forward,
    right and true_up, and the image plane's width and height at distance 1."""
    eye = np.asarray(cam.eye, dtype=np.float64)
    forward = np.asarray(cam.look_at) - eye
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, cam.up)
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    h = 2 * np.tan(np.radians(cam.fov_y) / 2)
    return eye, forward, right, up, h * cam.width / cam.height, h


def _camera_rays(scene: Any) -> tuple[np.ndarray, np.ndarray]:
    """The primary rays through the pixel centres (03_camera.h's formula), as float32 arrays."""
    cam = scene.camera
    eye, forward, right, up, w, h = camera_frame(cam)
    x = (np.arange(cam.width) + 0.5) / cam.width - 0.5
    y = 0.5 - (np.arange(cam.height) + 0.5) / cam.height
    xx, yy = np.meshgrid(x * w, y * h)
    d = forward + xx[..., None] * right + yy[..., None] * up
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    d = np.ascontiguousarray(d.reshape(-1, 3), dtype=np.float32)
    o = np.ascontiguousarray(np.broadcast_to(eye, d.shape), dtype=np.float32)
    return o, d


def _surface_samples(
    vertices: np.ndarray, faces: np.ndarray, n: int, seed: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """n points on a mesh's surface and a direction leaving each: a triangle chosen uniformly by
    index, a point p uniform on it (barycentrics by the square-root map), and a direction
    cosine-distributed about its unit face normal Ng. Returns (p, sum |b_i v_i| per axis, Ng,
    direction), all float64; the second is what p's rounding error is bounded by."""
    rng = np.random.default_rng(seed)
    v = np.asarray(vertices, dtype=np.float64)[np.asarray(faces)[rng.integers(0, len(faces), n)]]
    r1, r2 = rng.random(n), rng.random(n)
    s = np.sqrt(r1)
    b = np.stack([1 - s, s * (1 - r2), s * r2], axis=1)[..., None]  # (n, 3, 1)
    p = np.sum(b * v, axis=1)
    magnitude = np.sum(np.abs(b * v), axis=1)
    ng = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    ng /= np.linalg.norm(ng, axis=1, keepdims=True)
    # Cosine-distributed about ng: a uniform point on the unit disc lifted to the hemisphere.
    a = np.where(np.abs(ng[:, :1]) > 0.9, [[0.0, 1.0, 0.0]], [[1.0, 0.0, 0.0]])
    t1 = np.cross(ng, a)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(ng, t1)
    phi, r = 2 * np.pi * rng.random(n), np.sqrt(rng.random(n))
    z = np.sqrt(np.maximum(0.0, 1 - r * r))
    d = (r * np.cos(phi))[:, None] * t1 + (r * np.sin(phi))[:, None] * t2 + z[:, None] * ng
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return p, magnitude, ng, d


def _offset_origins(
    p: np.ndarray, magnitude: np.ndarray, ng: np.ndarray, dtype: type[np.floating[Any]]
) -> np.ndarray:
    """02_ray.h offset_ray_origin() for points p of the surface whose error is bounded by
    gamma(7) ``magnitude`` in ``dtype``'s arithmetic (its unit roundoff u: 2^-53 for float64,
    2^-24 for float32): p moved along Ng (the directions leave on Ng's side) by the distance the
    error box reaches along Ng, computed in float64, then rounded to ``dtype`` away from the
    surface (one step further where rounding to nearest came back towards it)."""
    u = float(np.finfo(dtype).eps) / 2
    gamma7 = 7 * u / (1 - 7 * u)
    p_error = gamma7 * magnitude
    offset = np.sum(np.abs(ng) * p_error, axis=1, keepdims=True) * ng
    po = p + offset
    rounded = po.astype(dtype)
    away = np.copysign(np.inf, offset).astype(dtype)
    if dtype == np.float64:  # rounded is po: one ulp further, as next_away() does
        return np.where(offset != 0, np.nextafter(rounded, away), rounded)
    back = (rounded.astype(np.float64) - po) * offset < 0
    return np.where(back, np.nextafter(rounded, away), rounded)


# The seed of `rtlab bench geometry`'s diffuse rays (both renderers' copies of them), and
# how many it traces.
DIFFUSE_SEED = 12
DIFFUSE_RAYS = 2_000_000


def _rays_leaving(
    samples: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray], dtype: type[np.floating[Any]]
) -> tuple[np.ndarray, np.ndarray]:
    """The rays of _surface_samples()' points and directions in ``dtype``, their origins
    offset for ``dtype``'s arithmetic (_offset_origins())."""
    p, magnitude, ng, d = samples
    o = _offset_origins(p, magnitude, ng, dtype)
    return np.ascontiguousarray(o), np.ascontiguousarray(d, dtype=dtype)


def diffuse_rays(
    vertices: np.ndarray, faces: np.ndarray, n: int, seed: int = DIFFUSE_SEED
) -> tuple[np.ndarray, np.ndarray]:
    """n incoherent rays leaving a mesh's surface (float64 origins and unit directions): a
    triangle chosen uniformly by index, a point uniform on it (barycentrics by the square-root
    map), a cosine-distributed direction about its face normal, and the origin moved off the
    surface as the core spawns rays (02_ray.h offset_ray_origin(): p's error bound gamma(7)
    (|b0 p0| + |b1 p1| + |b2 p2|) along Ng, then one ulp further away)."""
    return _rays_leaving(_surface_samples(vertices, faces, n, seed), np.float64)


def diffuse_rays_float32(
    vertices: np.ndarray, faces: np.ndarray, n: int, seed: int = DIFFUSE_SEED
) -> tuple[np.ndarray, np.ndarray]:
    """diffuse_rays()'s rays for a renderer that takes float32 rays (Embree): the same points
    and directions, each origin moved off the surface by float32's error bound instead
    (gamma(7) with u = 2^-24, about 2e-5 on the bunny) and rounded to float32 away from it.
    diffuse_rays()' origins, 1e-14 off the surface, merely rounded to float32 fall back onto
    it or below: Embree then hit the triangle the ray leaves at t ~ 0 on 50% of the bunny's
    rays (where 9.4% hit anything; same triangle as rtlab's on 49.9%). These agree with rtlab's
    answers on 99.997% of them (suite_geometry() records the agreement)."""
    return _rays_leaving(_surface_samples(vertices, faces, n, seed), np.float32)


def agreement(triangles: np.ndarray, others: np.ndarray) -> float:
    """The fraction of rays for which two renderers found the same closest triangle (index in
    the mesh), or both none (-1 or any negative index)."""
    a, b = np.asarray(triangles), np.asarray(others)
    same = (a == b) | ((a < 0) & (b < 0))
    return float(np.mean(same)) if len(same) else 1.0


def bunny_alone(width: int = 1920, height: int = 1024) -> Any:
    """The Stanford bunny's scene with the bunny alone (what Embree is given too), rendered by
    the aov integrator: the geometry suite's primary rays."""
    import dataclasses

    from tracer.scene import Mesh

    scene = load_scene(Path(__file__).resolve().parent / "scenes" / "bunny.toml")
    scene = scene.with_overrides(width=width, height=height, integrator="aov")
    meshes = tuple(o for o in scene.objects if isinstance(o, Mesh))
    return dataclasses.replace(scene, objects=meshes)


def suite_geometry(
    repeats: int = 3,
    threads: tuple[int, ...] = (1, 2),
    width: int = 1920,
    height: int = 1024,
    diffuse: int = DIFFUSE_RAYS,
) -> list[dict[str, Any]]:
    """Rays per second on the Stanford bunny (99,785 triangles), closest hit only, rtlab
    (its hierarchy, double precision, watertight) against Embree's single-ray kernel (embreex,
    robust=False, float): ``bunny-primary``, the camera's primary rays (rtlab's aov
    integrator); ``bunny-diffuse``, ``diffuse`` incoherent rays leaving the bunny's surface
    (diffuse_rays(); rtlab's batch call closest_mesh_hits, Embree the same rays in float32,
    their origins offset for float32: diffuse_rays_float32()); Embree's rows of both carry
    ``agreement``, the fraction of its rays on which Embree found the closest triangle rtlab
    finds for them, or none where rtlab finds none;
    plus each one's hierarchy build time."""
    import threading
    import time

    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh

    from tracer import _core
    from tracer.render import to_core
    from tracer.scene import Mesh

    bunny_only = bunny_alone(width, height)
    mesh = bunny_only.objects[0]
    assert isinstance(mesh, Mesh)
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

    embree, _ = build_embree()
    core = to_core(bunny_only)

    def embree_seconds(origins: np.ndarray, directions: np.ndarray, n: int) -> float:
        parts = np.array_split(np.arange(len(origins)), n)
        work = [threading.Thread(target=lambda p=p: embree.run(
            origins[p[0]:p[-1] + 1], directions[p[0]:p[-1] + 1], query="INTERSECT", output=1))
            for p in parts]  # fmt: skip
        start = time.perf_counter()
        for t in work:
            t.start()
        for t in work:
            t.join()
        return time.perf_counter() - start

    def batch_seconds(origins: np.ndarray, directions: np.ndarray, n: int) -> float:
        start = time.perf_counter()
        _core.closest_mesh_hits(core, origins, directions, n)
        return time.perf_counter() - start

    primary_o, primary_d = _camera_rays(bunny_only)
    # diffuse_rays() and diffuse_rays_float32() from one draw of the points (2M: about 1 s).
    samples = _surface_samples(mesh.vertices, mesh.faces, diffuse, DIFFUSE_SEED)
    diffuse_o, diffuse_d = _rays_leaving(samples, np.float64)
    diffuse_f32 = _rays_leaving(samples, np.float32)

    def embree_agreement(
        ours: tuple[np.ndarray, np.ndarray], theirs: tuple[np.ndarray, ...]
    ) -> float:
        """Whether Embree answers its rays as rtlab answers the same rays (the same work,
        timed): each one's closest triangle, once, outside the timing."""
        triangles = _core.closest_mesh_hits(core, *ours, default_threads())[2]
        return agreement(triangles, embree.run(*theirs, query="INTERSECT", output=1)["primID"])

    agreements = {
        # The camera's rays as Embree gets them, widened back to float64 (exactly) for rtlab.
        "bunny-primary": embree_agreement(
            (primary_o.astype(np.float64), primary_d.astype(np.float64)), (primary_o, primary_d)
        ),
        "bunny-diffuse": embree_agreement((diffuse_o, diffuse_d), diffuse_f32),
    }
    cases = (
        ("bunny-primary", width * height,
         lambda n: render_with_stats(bunny_only, threads=n, progress=False).seconds,
         lambda n: embree_seconds(primary_o, primary_d, n)),
        ("bunny-diffuse", diffuse, lambda n: batch_seconds(diffuse_o, diffuse_d, n),
         lambda n: embree_seconds(*diffuse_f32, n)),
    )  # fmt: skip
    for case, n_rays, ours_fn, theirs_fn in cases:
        for n in threads:
            best = _best_alternating(
                {
                    "rtlab": (lambda n=n, f=ours_fn: f(n), 2 * repeats + 1),
                    "embree": (lambda n=n, f=theirs_fn: f(n), 2 * repeats + 1),
                }
            )
            ours, theirs = best["rtlab"], best["embree"]
            for renderer, seconds in (("rtlab", ours), ("embree", theirs)):
                rows.append({"case": case, "renderer": renderer, "threads": n,
                             "metric": "mrays_per_s", "value": n_rays / seconds / 1e6,
                             "unit": "Mrays/s", "repeats": 2 * repeats + 1})  # fmt: skip
                if renderer == "embree":
                    rows[-1]["agreement"] = agreements[case]
    # Both builds use every core the process may use (16_mesh.h builds the root's halves side
    # by side; Embree's builder runs on its own thread pool), so the rows say so.
    cores = default_threads()
    for renderer, fn in (("rtlab", build_rtlab), ("embree", lambda: build_embree()[1])):
        rows.append({"case": "bunny-bvh-build", "renderer": renderer, "threads": cores,
                     "metric": "seconds", "value": _best(fn, repeats), "unit": "s",
                     "repeats": repeats, "triangles": len(mesh.faces)})  # fmt: skip
    return rows


def suite_convergence(
    out_dir: str | os.PathLike[str] = "out", engine: Any = None
) -> list[dict[str, Any]]:
    """Error against run time (reference/convergence.py): the Cornell box path traced by rtlab
    and Mitsuba, and the demo scene antialiased by rtlab, POV-Ray and Mitsuba; writes a log-log
    plot per case beside the JSON and prints the time each renderer needs to reach an error."""
    from reference.convergence import CASES, convergence, convergence_classic, plot, summary

    rows = []
    cases: tuple[tuple[str, list[dict[str, Any]]], ...] = ()
    if engine is None:  # the cases one after the other, here
        run = {"path": convergence, "classic": convergence_classic}
        cases = tuple((name, run[kind](**kwargs)) for name, kind, kwargs in CASES)
    else:  # --workers/--scheduler: a case per task (reference/convergence.py)
        from reference.convergence import batched

        cases = tuple(batched(engine))
    for name, made in cases:
        path = Path(out_dir) / f"convergence-{name}.png"
        plot(made, path)
        print(summary(made))
        print(f"plot: {path}")
        rows += made
    return rows + cornell_scaling()


def cornell_scaling(
    sizes: tuple[int, ...] = (64, 128), spp: int = 64, repeats: int = 5
) -> list[dict[str, Any]]:
    """The convergence rows are timed on every core; these time rtlab's Cornell box path
    tracer on 1 and 2 threads (one spp, the best of `repeats` interleaved renders), so that the
    suite's gain from the second thread can be read like the others'.

    Five repeats, not three: a 2-thread render needs both cores, and on the Zen 4 of
    2026-12-05 one of three runs of `rtlab bench convergence` gave 1.75x at 64x64 (its three
    2-thread renders 159 ms or more, the other runs' 139-140 ms, the 1-thread renders the
    same 278 ms in all three), where the scaling alone gave 1.89x to 2.00x in seven tries:
    something held a core for the second or so the three renders span. Five span about two
    seconds at 64x64 (and eight at 128x128) for some 4 s more a run."""
    rows = []
    for size in sizes:
        sized = cornell_scene(size, spp)
        best: dict[int, float] = {}
        for _ in range(repeats):
            for n in (1, 2):
                seconds = render_with_stats(sized, threads=n, progress=False).seconds
                best[n] = min(best.get(n, seconds), seconds)
        for n, value in best.items():
            rows.append({"case": f"cornell_box-{size}x{size}-{spp}spp", "renderer": "rtlab",
                         "threads": n, "metric": "seconds", "value": value, "unit": "s",
                         "repeats": repeats})  # fmt: skip
    return rows


SUITES: dict[str, Callable[..., list[dict[str, Any]]]] = {
    "classic": suite_classic,
    "geometry": suite_geometry,
    "convergence": suite_convergence,
    "grading": lambda: __import__("lessons.bench").bench.suite_grading(),  # lessons/bench.py
    "report": lambda: __import__("reports.bench").bench.suite_report(),  # reports/bench.py
    "batch": lambda: __import__("reference.bench_batch").bench_batch.suite_batch(),  # Dask
    # tracer/viewer/bench.py: rtlab view's frames through a WebSocket client at 1920x1024
    "viewer": lambda: __import__("tracer.viewer.bench").viewer.bench.suite_viewer(),
}


class UnknownSuiteError(ValueError):
    """A benchmark suite that does not exist: a usage error, not a fault of any scene."""


def run_suites(
    names: list[str],
    json_path: str | os.PathLike[str] | None,
    engine: Any = None,
    out_dir: str | os.PathLike[str] | None = None,
) -> list[dict]:
    """The suites' rows, each with its suite and the machine's CPU and compiler, written to
    json_path if given. The convergence suite's plots go to out_dir (default: beside the JSON,
    or out/)."""
    unknown = [n for n in names if n not in SUITES]
    if unknown:
        raise UnknownSuiteError(f"unknown suite {unknown[0]!r}; expected {', '.join(SUITES)}")
    rows: list[dict[str, Any]] = []
    where, on, built = machine(), cpu(), compiler()
    if out_dir is None and json_path:
        out_dir = Path(json_path).parent
    for name in names:
        suite = SUITES[name]
        made = (
            suite(out_dir=out_dir or "out", engine=engine)
            if name == "convergence" and (out_dir or engine is not None)
            else suite()
        )
        for row in made:
            row["suite"] = name
            row["machine"] = where
            row.update(on)
            row["compiler"] = built
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
                x = _ratio(ours, r)
                ratio = "   " + speed_words(x, x, x, 1)
            lines.append(f"  {name:<16}{r['value']:>10.4f} {r['unit']}{ratio}")
    lines += format_scaling(rows)
    if rows:
        lines.append(f"machine: {rows[0]['machine']}")
        if rows[0].get("cpu_flags"):
            lines.append(f"vector units: {' '.join(rows[0]['cpu_flags'])}")
        if rows[0].get("compiler"):
            lines.append(f"core built by: {rows[0]['compiler']}")
    return "\n".join(lines)


def _ratio(ours: dict[str, Any], theirs: dict[str, Any]) -> float:
    """How many times faster rtlab is: their time over ours, or our throughput over theirs."""
    if ours["unit"] == "s":
        return float(theirs["value"] / ours["value"])
    return float(ours["value"] / theirs["value"])


def _times_to_error(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The convergence rows as one row per case and renderer: the time to reach rtlab's median
    RMSE, fitted with the Monte Carlo slope (reference/convergence.py, as its summary prints)."""
    import numpy as np

    from reference.convergence import time_to_error

    made = []
    for case in dict.fromkeys(r["case"] for r in rows if r["metric"] == "rmse"):
        group = [r for r in rows if r["metric"] == "rmse" and r["case"] == case]
        ours = [r["value"] for r in group if r["renderer"] == "rtlab"]
        if not ours:
            continue
        target = float(np.median(ours))
        for renderer, seconds in time_to_error(group, target).items():
            made.append({**group[0], "case": f"{case}, time to RMSE {target:.3g}",
                         "renderer": renderer, "metric": "time_to_error", "value": seconds,
                         "unit": "s"})  # fmt: skip
    return made


def _label(rows: list[dict[str, Any]]) -> Callable[[dict[str, Any]], str]:
    """A row's case as tables and the scaling lines name it: with its metric where the case has
    more than one (the viewer's render, encode and transfer times, fps and frame size)."""
    metrics: dict[str, set[str]] = {}
    for r in rows:
        metrics.setdefault(r["case"], set()).add(r["metric"])
    return lambda r: r["case"] if len(metrics[r["case"]]) == 1 else f"{r['case']}, {r['metric']}"


def format_markdown(rows: list[dict[str, Any]], command: str = "rtlab bench all") -> str:
    """The rows of one run as a Markdown table for the README: rtlab's figure and every other
    renderer's (or engine's) with rtlab's speed-up over it (below 1: rtlab is slower), then each
    renderer's gain from the second thread, the CPU and the command."""
    return _markdown_table([rows], command, heading=None)


def thread_scaling(rows: list[dict[str, Any]]) -> dict[tuple[str, str, str], float]:
    """What each renderer gains from the second thread, per suite and case (with its metric
    where the case has several): the 1-thread time over the 2-thread time (or the 2-thread
    throughput over the 1-thread one), from the rows of one run."""
    label = _label(rows)
    gains = {}
    for r in rows:
        if r["threads"] != 2:
            continue
        one = [q for q in rows if q["threads"] == 1 and (q.get("suite"), q["case"],
               q["renderer"], q["metric"]) == (r.get("suite"), r["case"], r["renderer"],
               r["metric"])]  # fmt: skip
        if one and one[0]["value"] > 0 and r["value"] > 0 and r["unit"] != "bytes":
            v1, v2 = one[0]["value"], r["value"]
            gains[(str(r.get("suite", "")), label(r), r["renderer"])] = (
                v1 / v2 if r["unit"] in ("s", "ms") else v2 / v1  # a time, or a rate
            )
    return gains


def format_scaling(rows: list[dict[str, Any]]) -> list[str]:
    """A line per suite and case: each renderer's gain from the second thread."""
    return _scaling_lines(summarize_scaling([rows]))


# -- several runs -------------------------------------------------------------------------
# The README's figures are medians of five runs with the range of rtlab's ratio over them.
# Each ratio is taken within one run, where the renderers took turns, and only then across
# runs: between runs these shared machines drift by 20%, which a median of times would mix in.


class RunsError(ValueError):
    """Runs that cannot be summarised together: from different machines or compilers, or a
    file that holds no bench rows. The message names the file."""


def _machine_of(rows: list[dict[str, Any]]) -> tuple[Any, ...]:
    first = rows[0] if rows else {}
    return (first.get("cpu_model"), first.get("cpu_count"), first.get("compiler"))


def read_runs(paths: list[str | os.PathLike[str]]) -> list[list[dict[str, Any]]]:
    """The runs in `rtlab bench --json` files: one run a file, or several where the rows carry
    ``run`` (``rtlab bench --runs N``). Refuses a file that is not a list of bench rows, and
    runs whose CPU, core count or compiler differ from the first file's."""
    runs: list[list[dict[str, Any]]] = []
    first: tuple[Any, ...] | None = None
    for path in paths:
        try:
            rows = json.loads(Path(path).read_text(encoding="utf-8"))
        except OSError as exc:
            raise RunsError(f"{path}: cannot read it: {exc.strerror or exc}") from exc
        except json.JSONDecodeError as exc:
            raise RunsError(f"{path}: not JSON ({exc.msg}, line {exc.lineno})") from exc
        needed = {"case", "renderer", "threads", "metric", "value", "unit"}
        if (
            not isinstance(rows, list)
            or not rows
            or not all(isinstance(r, dict) and needed <= set(r) for r in rows)
        ):
            raise RunsError(
                f"{path}: expected the list of rows `rtlab bench --json` writes, each with "
                + ", ".join(sorted(needed))
            )
        where = _machine_of(rows)
        if first is None:
            first = where
        elif where != first:
            raise RunsError(
                f"{path}: a run on {where[0]} ({where[1]} cores, core built by {where[2]}), "
                f"the first on {first[0]} ({first[1]} cores, {first[2]}): ratios of "
                "different machines or builds do not mix"
            )
        numbers = sorted({r["run"] for r in rows if "run" in r})
        if numbers:
            runs += [[r for r in rows if r.get("run") == n] for n in numbers]
        else:
            runs.append(rows)
    return runs


def _spread(values: list[float]) -> dict[str, float]:
    return {"median": float(np.median(values)), "min": min(values), "max": max(values)}


def summarize_runs(runs: list[list[dict[str, Any]]]) -> list[dict[str, Any]]:
    """One row per suite, case, thread count, metric and renderer over several runs of the same
    suites: ``value``, the median of its values (``values``, in run order; ``runs``, how
    many), and beside rtlab for every other renderer ``ratio``, ``ratio_min`` and
    ``ratio_max``, the median and range of rtlab's speed-up over it (``ratios``), each taken
    within one run. Convergence rows become times to rtlab's error run by run first, as
    format_markdown() shows one run. The machine's fields are the first run's."""
    keyed: dict[tuple[Any, ...], list[tuple[int, dict[str, Any]]]] = {}
    labels: dict[tuple[Any, ...], set[str]] = {}
    for number, rows in enumerate(runs):
        rows = [r for r in rows if r["metric"] != "rmse"] + _times_to_error(rows)
        label = _label(rows)
        for r in rows:
            # A time to error names its run's target (rtlab's median RMSE): grouped without it.
            case = label(r).split(", time to RMSE")[0]
            key = (r.get("suite", ""), case, r["threads"], r["metric"], r["renderer"])
            keyed.setdefault(key, []).append((number, r))
            labels.setdefault(key, set()).add(label(r))
    made = []
    for key, seen in keyed.items():
        suite, case, renderer = key[0], key[1], key[4]
        if len(labels[key]) == 1:
            case = next(iter(labels[key]))
        else:  # the runs' targets differ
            case += ", time to rtlab's median RMSE of each run"
        first = seen[0][1]
        values = [r["value"] for _, r in seen]
        row = {**{k: v for k, v in first.items() if k not in ("value", "run", "repeats")},
               "suite": suite, "case": case, "value": float(np.median(values)),
               "values": values, "runs": len(values)}  # fmt: skip
        if renderer != "rtlab":
            ours = {n: r for n, r in keyed.get((*key[:4], "rtlab"), [])}
            ratios = [_ratio(ours[n], r) for n, r in seen if n in ours]
            if ratios:
                spread = _spread(ratios)
                row.update(ratio=spread["median"], ratio_min=spread["min"],
                           ratio_max=spread["max"], ratios=ratios)  # fmt: skip
        made.append(row)
    return made


def summarize_scaling(runs: list[list[dict[str, Any]]]) -> dict[tuple[str, str, str], list[float]]:
    """Each renderer's gain from the second thread (thread_scaling()), run by run."""
    gains: dict[tuple[str, str, str], list[float]] = {}
    for rows in runs:
        for key, gain in thread_scaling(rows).items():
            gains.setdefault(key, []).append(gain)
    return gains


def _runs_heading(n: int) -> str:
    if n == 1:
        return "1 run"
    return f"{n} runs: medians, and rtlab's ratio's range over the runs"


def _with_range(x: float, low: float, high: float, runs: int) -> str:
    return f"{x:.2f}x" if runs == 1 else f"{x:.2f}x [{low:.2f}-{high:.2f}]"


def speed_words(x: float, low: float, high: float, runs: int) -> str:
    """rtlab's speed-up x over a renderer (median, and its least and greatest over `runs`
    runs) in words, one run or several alike: "rtlab is 10.00x faster [8.00-12.00]", or where
    the median is below 1, "rtlab is 1.25x slower [1.11-1.43]" (the range as slow-downs too)."""
    word = "faster" if x >= 1 else "slower"
    if x < 1:
        x, low, high = 1 / x, 1 / high, 1 / low
    return f"rtlab is {x:.2f}x {word}" + (f" [{low:.2f}-{high:.2f}]" if runs > 1 else "")


def _scaling_lines(gains: dict[tuple[str, str, str], list[float]]) -> list[str]:
    lines = []
    for suite, case in sorted({(s, c) for s, c, _ in gains}):
        each = ", ".join(
            f"{name} " + _with_range(float(np.median(g)), min(g), max(g), len(g))
            for (s, c, name), g in gains.items() if (s, c) == (suite, case)
        )  # fmt: skip
        lines.append(f"{suite + ': ' if suite else ''}{case}, 1 -> 2 threads: {each}")
    return lines


def format_summary(runs: list[list[dict[str, Any]]]) -> str:
    """The runs as format_ratios() prints one: each renderer's median value and rtlab's median
    speed-up over it [least-greatest over the runs], then the gains from the second thread."""
    rows = summarize_runs(runs)
    lines = [_runs_heading(len(runs))]
    for case, threads, metric in sorted({(r["case"], r["threads"], r["metric"]) for r in rows}):
        lines.append(f"{case}, {threads} thread{'s' if threads > 1 else ''} ({metric}):")
        for r in rows:
            if (r["case"], r["threads"], r["metric"]) != (case, threads, metric):
                continue
            ratio = ""
            if "ratio" in r:
                ratio = "   " + speed_words(r["ratio"], r["ratio_min"], r["ratio_max"],
                                            len(r["ratios"]))  # fmt: skip
            lines.append(f"  {r['renderer']:<16}{r['value']:>10.4f} {r['unit']}{ratio}")
    lines += _scaling_lines(summarize_scaling(runs))
    if rows and rows[0].get("machine"):
        lines.append(f"machine: {rows[0]['machine']}")
        if rows[0].get("compiler"):
            lines.append(f"core built by: {rows[0]['compiler']}")
    return "\n".join(lines)


def format_summary_markdown(runs: list[list[dict[str, Any]]], command: str) -> str:
    """The runs as the README's table: each cell a renderer's median value, and beside rtlab
    the median of rtlab's speed-up over it [its range over the runs]; then the gains from the
    second thread, the CPU, the compiler and the command."""
    return _markdown_table(runs, command, heading=_runs_heading(len(runs)))


def _markdown_table(runs: list[list[dict[str, Any]]], command: str, heading: str | None) -> str:
    """format_markdown()'s table (one run, heading None) and format_summary_markdown()'s: a
    cell per renderer, its (median) value and beside rtlab rtlab's speed-up over it, with its
    range where there are several runs."""
    rows = summarize_runs(runs)
    ours_too = any(r["renderer"] == "rtlab" for r in rows)
    names = (["rtlab"] if ours_too else []) + sorted({r["renderer"] for r in rows} - {"rtlab"})
    lines = ["| " + " | ".join(["case", "threads", *names]) + " |", "|" + "---|" * (2 + len(names))]
    for case, threads in sorted({(r["case"], r["threads"]) for r in rows}):
        group = {r["renderer"]: r for r in rows if (r["case"], r["threads"]) == (case, threads)}
        cells = []
        for name in names:
            r = group.get(name)
            if r is None:
                cells.append("")
                continue
            cell = f"{r['value']:.4g} {r['unit']}"
            if "ratio" in r:
                cell += " (rtlab " + _with_range(r["ratio"], r["ratio_min"], r["ratio_max"],
                                                 len(r["ratios"])) + ")"  # fmt: skip
            cells.append(cell)
        lines.append(f"| {case} | {threads} | " + " | ".join(cells) + " |")
    scaling = _scaling_lines(summarize_scaling(runs))
    if scaling:
        lines += ["", "Gain from the second thread: " + "; ".join(scaling) + "."]
    if rows:
        built = f" Core built by {rows[0]['compiler']}." if rows[0].get("compiler") else ""
        runs_said = f"{heading}. " if heading else ""
        lines += ["", f"{runs_said}CPU: {rows[0].get('machine', '')}.{built} "
                  f"Command: `{command}`."]  # fmt: skip
    return "\n".join(lines) + "\n"
