"""Error against run time (``rtlab bench convergence``): each renderer renders the same
path-traced scene over a sweep of samples per pixel; each point records the wall time of the
render and its error against a high-spp Mitsuba reference (RMSE, relative MSE, FLIP).

A Monte Carlo estimate's RMSE falls as 1/sqrt(samples), so with time proportional to samples
the points of one renderer lie on a line of slope -1/2 in log-log; its height is the
renderer's efficiency. Fitting that line (slope fixed) gives the time each renderer needs to
reach a given error: their ratio is the speed comparison that matters for Monte Carlo.
"""

from __future__ import annotations

import math
import os
import time
from pathlib import Path
from typing import Any

import numpy as np

from reference.stats import mitsuba_reference
from tracer.render import render_with_stats
from tracer.scene import Scene, load_scene

SCENES = Path(__file__).resolve().parent / "scenes"
SWEEP = (4, 8, 16, 32, 64, 128)


def errors(image: np.ndarray, ref: np.ndarray) -> dict[str, float]:
    from reference.metrics import flip

    diff = np.asarray(image, np.float64) - ref
    return {
        "rmse": float(np.sqrt(np.mean(diff**2))),
        "relmse": float(np.mean(diff**2 / (ref**2 + 1e-2))),
        "flip": flip(ref, image)[0],
    }


#: Mitsuba's renderers of the sweep: (variant, sampler). "mitsuba-llvm" and "mitsuba-scalar"
#: draw independent samples (the converter's sampler, Mitsuba's default); "mitsuba-llvm-
#: stratified" draws jittered strata as rtlab-stratified does (tracer/cpp/11_render.h
#: for_each_sample()), Mitsuba's stratified sampler (it rounds spp up to a square: 8 -> 9,
#: 32 -> 36, 128 -> 144; the fit uses each render's time and error, not its spp). On the
#: Cornell box the RMSE is decided by the pixels on the light's edges, where the samples'
#: pattern in the pixel, not speed, decides: with independent samples Mitsuba's RMSE at 128
#: spp was twice rtlab-stratified's, with strata the two within a few per cent, and without
#: the 1% worst pixels they were equal with either sampler; rtlab's Sobol net (the scene's
#: sampler) halves rtlab-stratified's squared error there. The stratified rows compare the
#: renderers' speed at the same sampling design.
MITSUBA: dict[str, tuple[str, str | None]] = {
    "mitsuba-llvm": ("llvm_ad_rgb", None),
    "mitsuba-llvm-stratified": ("llvm_ad_rgb", "stratified"),
    "mitsuba-scalar": ("scalar_rgb", None),
}


#: rtlab's renderers of the sweep: the scene as it is (the Cornell box asks for the "sobol"
#: sampler), and "rtlab-stratified", the same with the jittered grid of strata, which tells
#: how much of rtlab's lead is its sampler and how much its speed.
RTLAB: dict[str, dict[str, str]] = {"rtlab": {}, "rtlab-stratified": {"sampler": "stratified"}}


def _rtlab_timer(scene: Scene) -> Any:
    """A function (spp, seed) -> (image, seconds, samples drawn), as _mitsuba_timer's."""

    def run(spp: int, seed: int) -> tuple[np.ndarray, float, int]:
        res = render_with_stats(scene.with_overrides(spp=spp, seed=seed), progress=False)
        return res.image, res.seconds, spp

    return run


def _mitsuba_timer(scene: Scene, variant: str, sampler: str | None = None) -> Any:
    """A function (spp, seed) -> (image, seconds, samples drawn) rendering a loaded scene warm:
    each sample count is rendered and read once untimed before its timed render, so no timing
    includes the JIT's compilation (the stratified sampler's kernels depend on the count;
    rtlab compiles nothing at render time)."""
    import mitsuba as mi

    import converters.mitsuba as cm

    cm.use_variant(variant)
    d = cm.to_mitsuba_dict(scene)
    if sampler is not None:
        d["sensor"]["sampler"] = {"type": sampler, "sample_count": 4, "jitter": True}
    mi_scene = mi.load_dict(d)
    warm: set[int] = set()

    def run(spp: int, seed: int) -> tuple[np.ndarray, float, int]:
        cm.use_variant(variant)
        if sampler == "stratified":  # the smallest square grid of strata, as Mitsuba rounds
            spp = (math.isqrt(spp - 1) + 1) ** 2
        if spp not in warm:  # compile the kernels; not part of any timing
            # np.array() as below: the image's last kernel (the film's development) runs only
            # when the image is read, and must be compiled here too.
            np.array(mi.render(mi_scene, spp=spp, seed=seed + 1))
            warm.add(spp)
        start = time.perf_counter()
        image = np.array(mi.render(mi_scene, spp=spp, seed=seed), dtype=np.float32)[..., :3]
        seconds = time.perf_counter() - start
        drawn = int(mi_scene.sensors()[0].sampler().sample_count())
        assert drawn == spp, f"Mitsuba drew {drawn} samples per pixel, asked {spp}"
        return image, seconds, drawn

    return run


def convergence(
    name: str = "cornell_box", width: int = 64, height: int = 64, sweep: tuple[int, ...] = SWEEP,
    reference_spp: int = 4096, renderers: tuple[str, ...] = ("rtlab", "rtlab-stratified",
                                                              "mitsuba-llvm",
                                                              "mitsuba-llvm-stratified",
                                                              "mitsuba-scalar"),
    repeats: int = 3,
) -> list[dict[str, Any]]:  # fmt: skip
    """Rows of (time, error) per renderer and spp. A row's seconds are the fastest of `repeats`
    renders of the same seed, interleaved by renderer, as reference/bench.py times: other work
    on the shared machine only ever slows a render, so the fastest is the least disturbed, for
    every renderer alike; the error is the first render's (the same seed, the same image)."""
    scene = load_scene(SCENES / f"{name}.toml").with_overrides(width=width, height=height)
    # The reference's own error is in every renderer's: drawn with Mitsuba's strata, a pixel
    # on the light's edge has a small fraction of an independent reference's noise (at 128 spp
    # rtlab's edge pixels' squared error was below an independent 4096-spp reference's own).
    ref = mitsuba_reference(scene, reference_spp, sampler="stratified").mean
    case = f"{name}-{width}x{height}"
    timers: dict[str, Any] = {}
    for r in renderers:
        if r in RTLAB:
            timers[r] = _rtlab_timer(scene.with_overrides(**RTLAB[r]))
        else:
            timers[r] = _mitsuba_timer(scene, *MITSUBA[r])
    rows = []
    threads = os.cpu_count() or 1
    for spp in sweep:
        made: dict[str, tuple[np.ndarray, float, int]] = {}
        for _ in range(repeats):
            for r, run in timers.items():
                image, seconds, rendered = run(spp, 17 + spp)
                first = made.get(r, (image, seconds, rendered))
                made[r] = (first[0], min(first[1], seconds), rendered)
        for r, (image, seconds, rendered) in made.items():
            e = errors(image, ref)
            rows.append({"case": case, "renderer": r, "threads": threads, "metric": "rmse",
                         "value": e["rmse"], "unit": "", "spp": spp, "seconds": seconds,
                         "relmse": e["relmse"], "flip": e["flip"],
                         "reference_spp": reference_spp, "repeats": repeats,
                         "spp_rendered": rendered})  # fmt: skip
    return rows


def efficiency(rows: list[dict[str, Any]]) -> dict[str, float]:
    """Per renderer, c in RMSE = c / sqrt(seconds): the geometric mean of rmse sqrt(seconds)."""
    out: dict[str, list[float]] = {}
    for r in rows:
        out.setdefault(r["renderer"], []).append(np.log(r["value"] * np.sqrt(r["seconds"])))
    return {k: float(np.exp(np.mean(v))) for k, v in out.items()}


def time_to_error(rows: list[dict[str, Any]], target: float) -> dict[str, float]:
    return {k: (c / target) ** 2 for k, c in efficiency(rows).items()}


def plot(rows: list[dict[str, Any]], path: str | os.PathLike[str]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from tracer.image import atomic_path

    fig, ax = plt.subplots(figsize=(6, 4.5), dpi=100)
    for renderer in dict.fromkeys(r["renderer"] for r in rows):
        pts = sorted((r["seconds"], r["value"]) for r in rows if r["renderer"] == renderer)
        ax.loglog(*zip(*pts, strict=True), "o-", label=renderer)
    t = np.array([min(r["seconds"] for r in rows), max(r["seconds"] for r in rows)])
    c = max(efficiency(rows).values())
    ax.loglog(t, c / np.sqrt(t), "k--", lw=1, label="slope -1/2 (Monte Carlo)")
    ax.set_xlabel("render time (s)")
    ax.set_ylabel("RMSE against the reference")
    ax.set_title(rows[0]["case"])
    ax.legend()
    ax.grid(True, which="both", alpha=0.3)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", bbox_inches="tight")
    plt.close(fig)


def summary(rows: list[dict[str, Any]]) -> str:
    target = float(np.median([r["value"] for r in rows if r["renderer"] == "rtlab"]))
    times = time_to_error(rows, target)
    ours = times.get("rtlab")
    lines = [f"{rows[0]['case']}: time to reach RMSE {target:.3g} (fitted, slope -1/2):"]
    for k, t in times.items():
        ratio = (
            ""
            if k == "rtlab" or ours is None
            else (
                f"   rtlab is {t / ours:.2f}x faster"
                if t >= ours
                else f"   rtlab is {ours / t:.2f}x slower"
            )
        )
        lines.append(f"  {k:<16}{t:>9.3f} s{ratio}")
    return "\n".join(lines)


#: Classic scenes: POV-Ray's n x n jittered supersampling against rtlab's stratified spp = n^2.
CLASSIC_SWEEP = (1, 2, 3, 4, 6, 8)


def convergence_classic(
    name: str = "ex25", width: int = 96, height: int = 72,
    sweep: tuple[int, ...] = CLASSIC_SWEEP, reference_spp: int = 1024,
) -> list[dict[str, Any]]:  # fmt: skip
    """Error against time for antialiasing a classic scene: rtlab (stratified jittered spp =
    n^2), POV-Ray (jittered n x n supersampling) and Mitsuba llvm_ad_rgb (the classic
    integrator, independent samples), against Mitsuba's classic integrator at reference_spp."""
    from reference.mitsuba import run_mitsuba
    from reference.povray import run_povray

    scene = load_scene(SCENES / f"{name}.toml").with_overrides(width=width, height=height)
    ref = run_mitsuba(scene.with_overrides(spp=reference_spp), variant="llvm_ad_rgb").image
    case = f"{name}-{width}x{height}"
    threads = os.cpu_count() or 1
    rows = []
    for n in sweep:
        spp = n * n
        runs = {
            "rtlab": lambda spp=spp: (lambda r: (r.image, r.seconds))(render_with_stats(
                scene.with_overrides(spp=spp, seed=spp), progress=False)),
            "povray": lambda n=n: (lambda r: (r.image, r.trace_seconds))(
                run_povray(scene, threads=threads, antialias=n) if n > 1
                else run_povray(scene, threads=threads)),
            "mitsuba-llvm": lambda spp=spp: (lambda r: (r.image, r.render_seconds))(
                run_mitsuba(scene.with_overrides(spp=spp, seed=spp), variant="llvm_ad_rgb")),
        }  # fmt: skip
        for renderer, run in runs.items():
            image, seconds = run()
            e = errors(image, ref)
            rows.append({"case": case, "renderer": renderer, "threads": threads,
                         "metric": "rmse", "value": e["rmse"], "unit": "", "spp": spp,
                         "seconds": seconds, "relmse": e["relmse"], "flip": e["flip"],
                         "reference_spp": reference_spp})  # fmt: skip
    return rows


# --- on Dask (rtlab bench convergence --workers N | --scheduler ADDRESS: tracer/batch.py) ---

#: The cases of `rtlab bench convergence` (reference/bench.py suite_convergence): a name, the
#: kind ("path": convergence(), "classic": convergence_classic()) and its arguments.
CASES: tuple[tuple[str, str, dict[str, Any]], ...] = (
    ("cornell", "path", {}),
    ("cornell-128", "path", {"width": 128, "height": 128,
                             "renderers": ("rtlab", "rtlab-stratified", "mitsuba-llvm",
                                           "mitsuba-llvm-stratified")}),
    ("ex25", "classic", {}),
)  # fmt: skip


def _host_lock() -> Any:
    """On a Dask worker, the cluster-wide lock of this worker's machine (distributed.Lock,
    named by the host): two cases timed on one machine at once would share its cores and
    spoil each other's timings. Elsewhere (serially) nothing to lock."""
    import contextlib
    import socket

    try:
        from distributed import Lock, get_worker

        get_worker()
    except (ImportError, ValueError):  # not in a worker
        return contextlib.nullcontext()
    return Lock(f"rtlab-timing-{socket.gethostname()}")


def case_task(kind: str, kwargs: dict[str, Any]) -> dict[str, Any]:
    """One batch task: one case whole (its reference, every renderer's sweep interleaved, as
    serially), holding its machine's timing lock, so that its renderers are timed side by side
    on one machine and no other case's renders run beside them there. Each row names its host
    (the rows' threads are that machine's cores)."""
    import socket

    with _host_lock():
        made = convergence(**kwargs) if kind == "path" else convergence_classic(**kwargs)
    return {"rows": [r | {"host": socket.gethostname()} for r in made]}


def batched(engine: Any, cases: tuple[tuple[str, str, dict[str, Any]], ...] = CASES
            ) -> list[tuple[str, list[dict[str, Any]]]]:  # fmt: skip
    """The cases as tasks of the batch layer: on a cluster of several machines the cases run
    at once, one a machine; on one machine (a LocalCluster) one after the other, whatever the
    workers, since a timing must not share its cores. What a task is here, and why: a whole
    case, because its renderers must be timed on the same machine, interleaved, to be
    compared (a renderer per task could put two renderers of one case on two machines)."""
    from tracer.batch import BatchError, Task, run_batch, summary

    tasks = [Task(name, case_task, (kind, kwargs)) for name, kind, kwargs in cases]
    outcomes = run_batch(tasks, engine, retries=0, desc="convergence")
    if any(o.status != "ok" for o in outcomes):
        raise BatchError(summary(outcomes, "convergence cases"))
    return [(o.name, o.data["rows"]) for o in outcomes]
