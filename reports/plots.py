"""The lesson pages' plots, every figure of them measured by the run that makes the page.

One function per plot kind, each returning a ``Plot``: the figures it is drawn from (rows, as
the page's table gives them), the PNG (matplotlib's Agg), the alt text (the finding, with this
run's numbers, for a reader who cannot see the image) and a caption that says what is plotted
and how (the same from every run). Nothing here is cached: each plot renders its references
too, so that every number on a page comes from the command that made it.

- ``antialiasing`` (L01's page): RMSE against render time for rtlab (stratified, n x n strata
  of one jittered sample each), POV-Ray (its jittered n x n supersampling) and Mitsuba 3
  (independent samples) on the course's Ex 25, with the Monte Carlo slope -1/2.
- ``global_illumination`` (L12's page): the same for rtlab's path tracer and Mitsuba's on the
  Cornell box, with the fitted efficiency ratio.
- ``precision`` (L13's page): the relative error of the hit distance t on a unit sphere at
  distance D = 10 .. 10^10, the textbook quadratic (numpy) against rtlab's (the built core),
  both against exact arithmetic on the ray and the sphere.
- ``bounding_volumes`` (L09's page): box and triangle tests per primary ray, and the trace
  time, for each of rtlab's acceleration modes on the Stanford bunny.
"""

from __future__ import annotations

import io
import math
import struct
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from decimal import Decimal, localcontext
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "reference" / "scenes"
THREADS = 2  # as the lesson pages render their scenes
NAMES = {"rtlab": "rtlab", "povray": "POV-Ray", "mitsuba": "Mitsuba 3"}
COLOURS = {"rtlab": "C0", "povray": "C1", "mitsuba": "C2", "textbook": "C3"}


@dataclass
class Plot:
    name: str  # the image's file stem and the block's id
    title: str
    caption: str  # what is plotted and how: the same from every run
    alt: str  # the finding, with this run's numbers
    findings: list[str]  # sentences with this run's numbers (fitted slopes, ratios, noise)
    columns: list[tuple[str, str]]  # (row key, heading) of the table of figures
    rows: list[dict[str, Any]]  # the figures the plot is drawn from
    png: bytes
    seconds: float  # what computing it took: renders, references, drawing
    fit: dict[str, float] = field(default_factory=dict)  # fitted numbers, by name

    @property
    def size(self) -> tuple[int, int]:
        """The PNG's (width, height) in pixels, from its IHDR chunk."""
        width, height = struct.unpack(">II", self.png[16:24])
        return width, height


def _figure(width: float = 6.0, height: float = 4.0) -> tuple[Any, Any]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt.subplots(figsize=(width, height), dpi=100)


def _png(fig: Any) -> bytes:
    import matplotlib.pyplot as plt

    buffer = io.BytesIO()
    # No timestamp or version in the file: the same figures draw the same bytes.
    fig.savefig(buffer, format="png", bbox_inches="tight", metadata={"Software": None})
    plt.close(fig)
    return buffer.getvalue()


# The relative error's floor: a pixel's squared error over (reference^2 + 0.01), the relative
# MSE of the denoising literature (Rousselle, Knaus and Zwicker 2011), so that a few pixels of
# the light (radiance ~17, whose edge pixels have a per-sample spread ~8) do not outweigh the
# whole room, while a dark pixel (reference < 0.1) counts in absolute terms.
RELATIVE_FLOOR = 1e-2


def _relative_weight(reference: np.ndarray) -> np.ndarray:
    return 1.0 / (reference**2 + RELATIVE_FLOOR)


def _relative_rmse(image: np.ndarray, reference: np.ndarray) -> float:
    diff = np.asarray(image, np.float64)[..., :3] - reference
    return float(np.sqrt(np.mean(diff**2 * _relative_weight(reference))))


def slope(rows: list[dict[str, Any]], x: str, y: str = "rmse") -> float:
    """The least-squares slope of log y against log x."""
    xs = np.log([r[x] for r in rows])
    ys = np.log([r[y] for r in rows])
    return float(np.polyfit(xs, ys, 1)[0])


def efficiency(rows: list[dict[str, Any]]) -> float:
    """c in RMSE = c / sqrt(seconds) (the slope -1/2 line through the points): the geometric
    mean of rmse sqrt(seconds). Two renderers reach the same error in times in the ratio of
    their c squared."""
    return float(np.exp(np.mean([np.log(r["rmse"] * math.sqrt(r["seconds"])) for r in rows])))


# --- Mitsuba, loaded once and rendered warm -------------------------------------------------


def _mitsuba_scene(scene: Any, sampler: dict[str, Any] | None = None) -> Any:
    import gc

    import mitsuba as mi

    # Scenes loaded before (rtlab's classic integrator and BSDFs are Python plugins, kept in
    # reference cycles) are freed now, not by the cycle collector in the middle of a render,
    # where Dr.Jit then finds a plugin instance gone ("callable 0 returned an
    # empty/uninitialized Dr.Jit array", seen after other tests in the same process).
    gc.collect()

    import converters.mitsuba as cm

    cm.use_variant("llvm_ad_rgb")
    d = cm.to_mitsuba_dict(scene)
    if sampler is not None:
        d["sensor"]["sampler"] = sampler
    return mi.load_dict(d)


def _mitsuba_render(mi_scene: Any, spp: int, seed: int) -> tuple[np.ndarray, float]:
    import gc

    import mitsuba as mi

    # And no collection during the render either (see _mitsuba_scene).
    enabled = gc.isenabled()
    gc.disable()
    try:
        start = time.perf_counter()
        image = np.array(mi.render(mi_scene, spp=spp, seed=seed), dtype=np.float64)[..., :3]
        return image, time.perf_counter() - start
    finally:
        if enabled:
            gc.enable()


@dataclass
class Reference:
    """Mitsuba's image at ``chunks`` x ``spp`` samples per pixel (the mean of ``chunks``
    independent renders, seeds 1000 on) and the variance of that mean per pixel and channel,
    estimated from the spread of the chunks (var(chunk) / chunks)."""

    mean: np.ndarray
    variance: np.ndarray
    spp: int
    chunks: int
    seconds: float

    def noise(self, weight: np.ndarray | None = None) -> float:
        """The RMSE (weighted: the relative RMSE) that the reference's own noise adds to an
        error measured against it: the square root of its mean (weighted) variance."""
        w = 1.0 if weight is None else weight
        return math.sqrt(float(np.mean(self.variance * w)))


def _reference(mi_scene: Any, spp: int, chunks: int) -> Reference:
    start = time.perf_counter()
    images = np.stack([_mitsuba_render(mi_scene, spp, 1000 + c)[0] for c in range(chunks)])
    variance = images.var(axis=0, ddof=1) / chunks
    return Reference(
        images.mean(axis=0), variance, spp * chunks, chunks, time.perf_counter() - start
    )


# Renders of a few milliseconds vary by more than their own length on a shared machine: each
# time plotted is the shortest of REPEATS renders of the same image (the same seed).
REPEATS = 3


def _warm_render(mi_scene: Any, spp: int, seed: int) -> tuple[np.ndarray, float]:
    """Rendered once untimed (Dr.Jit compiles a kernel for each new sample count, and the
    compile is not the render), then REPEATS - 1 times: the image and the shortest time."""
    _mitsuba_render(mi_scene, spp, seed)
    runs = [_mitsuba_render(mi_scene, spp, seed) for _ in range(REPEATS - 1)]
    return runs[0][0], min(seconds for _, seconds in runs)


def _rtlab_render(scene: Any, packets: bool = True) -> tuple[np.ndarray, float]:
    """rtlab's image and the shortest trace time of REPEATS renders."""
    from tracer.render import render_with_stats

    runs = [
        render_with_stats(scene, threads=THREADS, progress=False, packets=packets)
        for _ in range(REPEATS)
    ]
    return runs[0].image, min(r.seconds for r in runs)


def _noise_said(ref: Reference, noise: float, smallest: float, metric: str = "RMSE") -> str:
    extra = 100 * (math.hypot(1, noise / smallest) - 1)
    return (
        f"The reference's own noise (Mitsuba, {ref.spp} samples per pixel in {ref.chunks} "
        f"renders of {ref.spp // ref.chunks}; estimated from their spread) adds "
        f"{'an' if metric[0] == 'R' else 'a'} {metric} of {noise:.2g}, "
        f"{smallest / noise:.1f} times below the smallest error plotted "
        f"({smallest:.2g}): at most {extra:.1f}% more on any error here (independent errors "
        f"add in quadrature)."
    )


# --- error against time ---------------------------------------------------------------------


def _error_time_figure(
    rows: list[dict[str, Any]], renderers: list[str], title: str, line: float, metric: str = "RMSE"
) -> bytes:
    """RMSE against seconds, log-log, one line per renderer, and the slope -1/2 line of
    height ``line`` (RMSE = line / sqrt(seconds))."""
    fig, ax = _figure()
    for r in renderers:
        # In the order of samples per pixel; the pixel centre (n = 1, antialiasing) apart.
        mine = sorted((p for p in rows if p["renderer"] == r), key=lambda p: p["spp"])
        centre = [p for p in mine if p.get("n") == 1]
        pts = [(p["seconds"], p["rmse"]) for p in mine if p not in centre]
        ax.loglog(*zip(*pts, strict=True), "o-", color=COLOURS[r], label=NAMES[r])
        if centre:
            ax.loglog(
                [p["seconds"] for p in centre],
                [p["rmse"] for p in centre],
                "s",
                mfc="none",
                color=COLOURS[r],
                ms=8,
            )
    if any(p.get("n") == 1 for p in rows):
        ax.plot([], [], "s", mfc="none", color="0.4", ms=8, label="one ray per pixel centre")
    t = np.geomspace(min(p["seconds"] for p in rows), max(p["seconds"] for p in rows), 2)
    ax.loglog(t, line / np.sqrt(t), "k--", lw=1, label="slope -1/2 (Monte Carlo)")
    ax.set_xlabel("render time (s, two threads)")
    ax.set_ylabel(f"{metric} against the reference")
    from matplotlib.ticker import NullFormatter

    ax.xaxis.set_minor_formatter(NullFormatter())  # the decades only: minor labels collide
    ax.set_title(title)
    ax.legend(fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    return _png(fig)


def antialiasing(
    width: int = 64,
    height: int = 48,
    strata: tuple[int, ...] = (1, 2, 4, 8),
    reference_chunks: int = 4,
) -> Plot:
    """Ex 25 antialiased by n x n samples per pixel; n = 1 is the pixel centre (all three
    renderers trace the same ray). The reference: Mitsuba with stratified jittered samples,
    ``reference_chunks`` renders of 16 x 16 each (1024 per pixel at 4): stratified, each chunk's
    error is that of the best points plotted at four times their samples."""
    from reference.metrics import rmse
    from reference.povray import run_povray
    from tracer.scene import load_scene

    start = time.perf_counter()
    scene = load_scene(SCENES / "ex25.toml").with_overrides(width=width, height=height)
    jittered = _mitsuba_scene(scene.with_overrides(spp=4))  # independent samples
    centre = _mitsuba_scene(scene)  # spp = 1: the pixel centre, as rtlab and POV-Ray
    ref = _reference(
        _mitsuba_scene(scene, {"type": "stratified", "sample_count": 256, "jitter": True}),
        256,
        reference_chunks,
    )
    rows = []
    for n in strata:
        spp = n * n
        ours, ours_seconds = _rtlab_render(scene.with_overrides(spp=spp, seed=spp), packets=False)
        pov = (
            run_povray(scene, threads=THREADS, antialias=n)
            if n > 1
            else run_povray(scene, threads=THREADS)
        )
        mi_image, mi_seconds = _warm_render(jittered if n > 1 else centre, spp, spp)
        for name, image, seconds in (
            ("rtlab", ours, ours_seconds),
            ("povray", pov.image, pov.trace_seconds),
            ("mitsuba", mi_image, mi_seconds),
        ):
            rows.append(
                {
                    "renderer": name,
                    "n": n,
                    "spp": spp,
                    "seconds": seconds,
                    "rmse": rmse(ref.mean, np.asarray(image)[..., :3]),
                }
            )
    renderers = ["rtlab", "povray", "mitsuba"]
    sampled = [r for r in rows if r["n"] > 1]  # the pixel centre is aliasing, not noise
    fit = {name: slope([r for r in sampled if r["renderer"] == name], "spp") for name in renderers}
    smallest = min(r["rmse"] for r in rows)
    centre_error = next(r["rmse"] for r in rows if r["renderer"] == "rtlab" and r["n"] == 1)
    most = max(strata) ** 2
    at_most = {r["renderer"]: r for r in rows if r["spp"] == most}
    line = efficiency([r for r in sampled if r["renderer"] == "mitsuba"])
    png = _error_time_figure(rows, renderers, f"Ex 25, {width} x {height}: antialiasing", line)
    fitted = ", ".join(f"{NAMES[k]}'s {v:.2f}" for k, v in fit.items())
    alt = (
        f"Log-log plot of RMSE against render time for Ex 25 at {width} by {height} pixels. "
        f"One ray through each pixel centre leaves an error of {centre_error:.2g} for all "
        f"three renderers (aliasing); with n by n samples per pixel the error falls, against "
        f"samples per pixel with slope {fitted}: the stratified samples of rtlab and POV-Ray "
        f"fall faster than Mitsuba's independent ones, which follow the dashed slope -1/2 "
        f"line. At {most} samples rtlab's error is {at_most['rtlab']['rmse']:.2g} in "
        f"{at_most['rtlab']['seconds']:.2g} s, POV-Ray's {at_most['povray']['rmse']:.2g} in "
        f"{at_most['povray']['seconds']:.2g} s, Mitsuba's {at_most['mitsuba']['rmse']:.2g} in "
        f"{at_most['mitsuba']['seconds']:.2g} s."
    )
    findings = [
        f"Fitted slope of log RMSE against log samples per pixel (n >= 2): {fitted}. Independent "
        f"samples give -1/2; stratified jittered samples do better where a pixel holds an "
        f"edge (-3/4 for an edge in a pixel, Mitchell 1996) and on smooth shading (down to -1).",
        f"One ray per pixel centre (n = 1): RMSE {centre_error:.3g} for every renderer: the "
        f"same ray, the same aliasing, which no number of images averages away.",
        _noise_said(ref, ref.noise(), smallest).replace(
            "samples", "stratified jittered samples", 1
        ),
    ]
    return Plot(
        name="antialiasing",
        title="Antialiasing: error against run time",
        caption=(
            "Ex 25 (three reflective spheres) rendered with n x n samples per pixel, n = "
            + ", ".join(str(n) for n in strata)
            + ": rtlab's stratified jitter (one random sample in each of n x n strata), "
            "POV-Ray's jittered n x n supersampling (+AM1 +Rn +J, threshold 0), Mitsuba 3's "
            "independent samples (llvm_ad_rgb, rtlab's classic integrator); n = 1 is the pixel "
            "centre for all three. RMSE against Mitsuba with stratified jittered samples, "
            "rendered by the same run. Times: the render itself (POV-Ray's trace time; "
            "Mitsuba's render after loading and compiling). The dashed line has the Monte "
            "Carlo slope -1/2 through Mitsuba's jittered points."
        ),
        alt=alt,
        findings=findings,
        columns=[
            ("renderer", "renderer"),
            ("n", "n"),
            ("spp", "samples per pixel"),
            ("seconds", "render time (s)"),
            ("rmse", "RMSE"),
        ],
        rows=rows,
        png=png,
        seconds=time.perf_counter() - start,
        fit={
            **{f"slope_{k}": v for k, v in fit.items()},
            "reference_noise": ref.noise(),
            "smallest": smallest,
            "reference_seconds": ref.seconds,
        },
    )


def global_illumination(
    width: int = 32,
    height: int = 32,
    sweep: tuple[int, ...] = (4, 16, 64),
    reference_spp: int = 64,
    reference_chunks: int = 16,
) -> Plot:
    """The Cornell box (reference/scenes/cornell_box.toml) path traced by rtlab and by
    Mitsuba's path integrator over a sweep of samples per pixel, against Mitsuba at
    ``reference_chunks`` x ``reference_spp`` samples."""
    from tracer.scene import load_scene

    start = time.perf_counter()
    scene = load_scene(SCENES / "cornell_box.toml").with_overrides(width=width, height=height)
    mi_scene = _mitsuba_scene(scene)
    ref = _reference(mi_scene, reference_spp, reference_chunks)
    rows = []
    for spp in sweep:
        ours, ours_seconds = _rtlab_render(scene.with_overrides(spp=spp, seed=spp))
        mi_image, mi_seconds = _warm_render(mi_scene, spp, spp)
        for name, image, seconds in (
            ("rtlab", ours, ours_seconds),
            ("mitsuba", mi_image, mi_seconds),
        ):
            rows.append(
                {
                    "renderer": name,
                    "spp": spp,
                    "seconds": seconds,
                    "rmse": _relative_rmse(image, ref.mean),
                }
            )
    renderers = ["rtlab", "mitsuba"]
    fit = {k: slope([r for r in rows if r["renderer"] == k], "spp") for k in renderers}
    c = {k: efficiency([r for r in rows if r["renderer"] == k]) for k in renderers}
    # The same error in times in the ratio of c^2: above 1, rtlab needs longer.
    ratio = (c["rtlab"] / c["mitsuba"]) ** 2
    smallest = min(r["rmse"] for r in rows)
    noise = ref.noise(_relative_weight(ref.mean))
    png = _error_time_figure(
        rows,
        renderers,
        f"Cornell box, {width} x {height}: path tracing",
        min(c.values()),
        "relative RMSE",
    )
    faster = f"rtlab needs {ratio:.2g} times Mitsuba's time"
    alt = (
        f"Log-log plot of relative RMSE against render time for the path-traced Cornell box "
        f"at {width} by {height} pixels: rtlab's error falls with slope {fit['rtlab']:.2f} "
        f"against samples per pixel and Mitsuba's with {fit['mitsuba']:.2f}, both along the "
        f"Monte Carlo slope -1/2; to reach the same error {faster}."
    )
    findings = [
        f"Fitted slope of log relative RMSE against log samples per pixel: rtlab "
        f"{fit['rtlab']:.3f}, Mitsuba {fit['mitsuba']:.3f} (Monte Carlo: -1/2).",
        f"Efficiency (c in relative RMSE = c / sqrt(seconds), the slope -1/2 line through "
        f"each renderer's points): rtlab {c['rtlab']:.3g}, Mitsuba {c['mitsuba']:.3g}; the "
        f"time to reach a given error goes as c^2, so {faster} (rtlab's c^2 over Mitsuba's: "
        f"{ratio:.3g}; above 1 Mitsuba is the more efficient, below 1 rtlab).",
        _noise_said(ref, noise, smallest, "relative RMSE"),
    ]
    return Plot(
        name="global-illumination",
        title="Global illumination: error against run time",
        caption=(
            "The Cornell box (Mitsuba's, converted from rtlab's scene file; up to 8 bounces) "
            "path traced by rtlab and by Mitsuba 3's path integrator (llvm_ad_rgb) at "
            + ", ".join(str(s) for s in sweep)
            + " samples per pixel. Relative RMSE (each pixel's squared error over reference^2 + "
            "0.01, so that the light's few pixels do not outweigh the room) against Mitsuba at "
            "many more samples, rendered by the same run. Times: the render itself (Mitsuba's "
            "after loading and compiling). The dashed line has the Monte Carlo slope -1/2 "
            "through the more efficient renderer's points: a renderer's points lie lower the "
            "more efficient it is."
        ),
        alt=alt,
        findings=findings,
        columns=[
            ("renderer", "renderer"),
            ("spp", "samples per pixel"),
            ("seconds", "render time (s)"),
            ("rmse", "RMSE"),
        ],
        rows=rows,
        png=png,
        seconds=time.perf_counter() - start,
        fit={
            **{f"slope_{k}": v for k, v in fit.items()},
            "ratio": ratio,
            "reference_noise": noise,
            "smallest": smallest,
        },
    )


# --- precision ------------------------------------------------------------------------------


def exact_t(
    center: list[float], radius: float, origin: list[float], direction: list[float]
) -> Decimal:
    """The nearer root of |o + t d - c|^2 = r^2 for the given doubles, to 60 digits: the
    quadratic's coefficients exactly (rational arithmetic on the doubles' binary values), the
    square root in 60-digit decimal."""
    f = [Fraction(o) - Fraction(c) for o, c in zip(origin, center, strict=True)]
    d = [Fraction(x) for x in direction]
    a = sum(x * x for x in d)
    b = sum(x * y for x, y in zip(f, d, strict=True))
    c0 = sum(x * x for x in f) - Fraction(radius) ** 2
    disc = b * b - a * c0
    with localcontext() as ctx:
        ctx.prec = 60

        def dec(q: Fraction) -> Decimal:
            return Decimal(q.numerator) / Decimal(q.denominator)

        return (-dec(b) - dec(disc).sqrt()) / dec(a)


def textbook_t(
    center: list[float], radius: float, origin: list[float], direction: list[float]
) -> float | None:
    """The textbook: A t^2 + B t + C = 0 with B = 2 f.d, the discriminant B^2 - 4AC and the
    nearer root (-B - sqrt(B^2 - 4AC)) / 2A, in double precision (numpy); None for a miss."""
    o, c, d = (np.asarray(v, np.float64) for v in (origin, center, direction))
    f = o - c
    a, b, c0 = np.dot(d, d), 2 * np.dot(f, d), np.dot(f, f) - radius * radius
    disc = b * b - 4 * a * c0
    if disc < 0:
        return None
    return float((-b - np.sqrt(disc)) / (2 * a))


def _ray_at(rng: np.random.Generator, distance: float) -> tuple[list[float], ...]:
    """(origin, direction, centre): a random unit direction from a random origin near 0, and a
    unit sphere ``distance`` along it whose centre lies 0.2 to 0.8 to the side of the ray
    (far from grazing: the discriminant is well conditioned, only the formula can lose it)."""
    origin = rng.uniform(-1, 1, 3)
    direction = rng.normal(size=3)
    direction /= np.linalg.norm(direction)
    side = np.cross(direction, rng.normal(size=3))
    side /= np.linalg.norm(side)
    center = origin + distance * direction + rng.uniform(0.2, 0.8) * side
    return origin.tolist(), direction.tolist(), center.tolist()


def precision(exponents: tuple[int, ...] = tuple(range(1, 11)), rays: int = 16) -> Plot:
    """A unit sphere at distance D = 10^k, ``rays`` random rays at each distance (seeded); the
    hit distance t by the textbook formula and by rtlab's core (``_core.intersect_sphere``, the
    intersection every render calls), each against the exact t; the largest error of each."""
    from tracer import _core

    start = time.perf_counter()
    rng = np.random.default_rng(13)
    rows = []
    for k in exponents:
        distance = 10.0**k
        row: dict[str, Any] = {"distance": distance, "rays": rays}
        worst = {"rtlab": 0.0, "textbook": 0.0}
        ulps = {"rtlab": 0.0, "textbook": 0.0}
        misses = {"rtlab": 0, "textbook": 0}
        for _ in range(rays):
            origin, direction, center = _ray_at(rng, distance)
            truth = exact_t(center, 1.0, origin, direction)
            _, hit = _core.intersect_sphere(center, 1.0, origin, direction)
            found = {
                "rtlab": None if hit is None else float(hit["t"]),
                "textbook": textbook_t(center, 1.0, origin, direction),
            }
            for key, t in found.items():
                if t is None:
                    misses[key] += 1
                    continue
                err = abs(Decimal(t) - truth)
                worst[key] = max(worst[key], float(err / truth))
                ulps[key] = max(ulps[key], float(err) / math.ulp(float(truth)))
        for key in worst:
            row[key], row[f"{key}_ulps"], row[f"{key}_misses"] = worst[key], ulps[key], misses[key]
        rows.append(row)
    worst_ulps = max(r["rtlab_ulps"] for r in rows)
    rtlab_misses = sum(r["rtlab_misses"] for r in rows)
    textbook_misses = sum(r["textbook_misses"] for r in rows)
    # The textbook's growth, fitted where its discriminant keeps some digits (D <= 10^7: its
    # rounding error, about 2^-51 D^2, is below the true discriminant, about 2).
    growing = [r for r in rows if r["distance"] <= 1e7 and r["textbook"] > 0]
    naive_slope = slope(growing, "distance", "textbook") if len(growing) >= 2 else float("nan")
    top = max(rows, key=lambda r: r["textbook"])
    fig, ax = _figure()
    floor = 1e-18  # an exact result drawn on the axis (log scale has no zero)
    for key, label in (
        ("textbook", "textbook (-B - sqrt(B^2 - 4AC)) / 2A, numpy double"),
        ("rtlab", "rtlab's core (L13's robust quadratic)"),
    ):
        pts = [(r["distance"], max(r[key], floor)) for r in rows]
        ax.loglog(*zip(*pts, strict=True), "o-", color=COLOURS[key], label=label)
        gone = [r["distance"] for r in rows if r[f"{key}_misses"]]
        if gone:
            ax.loglog(
                gone,
                [1.0] * len(gone),
                "x",
                color=COLOURS[key],
                ms=9,
                label=f"{key}: some rays miss the sphere",
            )
    d = np.array([rows[0]["distance"], rows[-1]["distance"]])
    ax.loglog(d, 2.0**-53 * np.ones(2), "k:", lw=1, label="half an ulp ($2^{-53}$ relative)")
    ax.set_ylim(floor / 2, 3.0)
    ax.set_xlabel("distance D of the unit sphere")
    ax.set_ylabel(f"relative error of t (the largest of {rays} rays)")
    ax.set_title("Hit distance on a unit sphere at distance D")
    ax.legend(fontsize=8, loc="upper left")
    ax.grid(True, which="both", alpha=0.3)
    png = _png(fig)
    textbook_said = (
        f"relative error grows in proportion to D (fitted slope {naive_slope:.2f} in log-log "
        f"up to D = 10^7), to {top['textbook']:.2g} at D = 10^{round(math.log10(top['distance']))}"
    )
    if textbook_misses:
        textbook_said += f", and {textbook_misses} of its rays miss the sphere altogether"
    alt = (
        f"Log-log plot of the relative error of the hit distance on a unit sphere at distance "
        f"D from 10^{exponents[0]} to 10^{exponents[-1]}, the largest of {rays} rays at each: "
        f"the textbook formula's {textbook_said}; rtlab's stays within {worst_ulps:.2g} ulp of "
        f"the exact value at every distance"
        + (f" ({rtlab_misses} of its rays miss)" if rtlab_misses else "")
        + "."
    )
    findings = [
        f"rtlab: at most {worst_ulps:.3g} ulp from the exact t at every D"
        + (f"; {rtlab_misses} rays miss" if rtlab_misses else "; no ray misses")
        + ".",
        f"Textbook: the {textbook_said}. Its discriminant B^2 - 4AC subtracts two numbers of about "
        f"4D^2 that agree in all but their last digits: their rounding error, about 2^-51 D^2, "
        f"moves sqrt(B^2 - 4AC) (about 2) by about 2^-53 D^2, so t's relative error grows as D; "
        f"beyond D ~ 10^8 the discriminant is all rounding error.",
    ]
    return Plot(
        name="precision",
        title="Precision: error against stiffness",
        caption=(
            f"A unit sphere at distance D; at each D, {rays} rays in random directions (seeded) "
            "passing 0.2 to 0.8 from the centre. The hit distance t by the textbook quadratic "
            "(computed here in numpy double) and by rtlab's core "
            "(tracer._core.intersect_sphere, the intersection every render calls: L13's "
            "robust discriminant and stable roots), each against the exact t (rational "
            "arithmetic on the ray's and the sphere's doubles, the square root to 60 digits). "
            "A cross at 1 marks a D where some ray missed; the dotted line is half an ulp."
        ),
        alt=alt,
        findings=findings,
        columns=[
            ("distance", "D"),
            ("textbook", "textbook: relative error"),
            ("textbook_ulps", "textbook: ulps"),
            ("textbook_misses", "textbook: misses"),
            ("rtlab", "rtlab: relative error"),
            ("rtlab_ulps", "rtlab: ulps"),
            ("rtlab_misses", "rtlab: misses"),
        ],
        rows=rows,
        png=png,
        seconds=time.perf_counter() - start,
        fit={"worst_ulps": worst_ulps, "textbook_slope": naive_slope},
    )


# --- bounding volumes -----------------------------------------------------------------------


def _count(x: float) -> str:
    """A count for a sentence: 29,000 rather than 2.9e+04; three digits below 1000."""
    return f"{x:,.0f}" if x >= 1000 else f"{x:.3g}"


def bounding_volumes(width: int = 24, height: int = 18) -> Plot:
    """The Stanford bunny alone (reference/scenes/bunny.toml without its floor and lights: each
    ray the counters count is a primary ray) rendered once per acceleration mode."""
    import dataclasses

    from tracer.render import render_with_stats
    from tracer.scene import load_scene
    from tracer.scene.model import ACCELERATIONS
    from tracer.scene.objects import Mesh

    start = time.perf_counter()
    full = load_scene(SCENES / "bunny.toml")
    meshes = [o for o in full.objects if isinstance(o, Mesh)]
    bunny = dataclasses.replace(full, objects=meshes, lights=[])
    triangles = sum(len(m.faces) for m in meshes)
    rows = []
    for mode in ACCELERATIONS:
        scene = bunny.with_overrides(width=width, height=height, max_depth=1, acceleration=mode)
        r = render_with_stats(scene, threads=THREADS, progress=False, packets=False)
        rays = r.rays["primary"]
        rows.append(
            {
                "mode": mode,
                "rays": rays,
                "box_tests": r.rays["box_tests"],
                "primitive_tests": r.rays["primitive_tests"],
                "boxes_per_ray": r.rays["box_tests"] / rays,
                "triangles_per_ray": r.rays["primitive_tests"] / rays,
                "seconds": r.seconds,
            }
        )
    by = {r["mode"]: r for r in rows}
    fig, ax = _figure()
    x = np.arange(len(rows))
    ax.bar(x - 0.2, [r["boxes_per_ray"] for r in rows], 0.4, label="box tests", color="C0")
    ax.bar(x + 0.2, [r["triangles_per_ray"] for r in rows], 0.4, label="triangle tests", color="C1")
    for i, r in enumerate(rows):
        top = max(r["boxes_per_ray"], r["triangles_per_ray"])
        ax.text(
            i,
            top * 3,
            f"{r['seconds']:.3g} s",
            ha="center",
            fontsize=9,
            bbox={"fc": "white", "ec": "none", "pad": 1},
        )
    ax.axhline(triangles, color="k", ls=":", lw=1, label=f"the mesh's {triangles:,} triangles")
    ax.set_yscale("log")
    ax.set_ylim(0.5, triangles * 300)
    ax.set_xticks(x, [r["mode"] for r in rows])
    ax.set_xlabel("acceleration (render.acceleration); above each pair, the trace time")
    ax.set_ylabel("tests per primary ray")
    ax.set_title(f"Stanford bunny, {width} x {height} primary rays")
    ax.legend(loc="upper right", fontsize=8)
    png = _png(fig)
    saving = by["bounding_box"]["triangles_per_ray"] / max(by["bvh"]["triangles_per_ray"], 1e-300)
    alt = (
        f"Bar chart, log scale, of tests per primary ray on the Stanford bunny "
        f"({triangles:,} triangles): with the hierarchy (bvh) a ray makes "
        f"{by['bvh']['boxes_per_ray']:.3g} box tests and {by['bvh']['triangles_per_ray']:.3g} "
        f"triangle tests in {by['bvh']['seconds']:.2g} s for the image; with one bounding box "
        f"{by['bounding_box']['boxes_per_ray']:.3g} box test and "
        f"{_count(by['bounding_box']['triangles_per_ray'])} triangle tests in "
        f"{by['bounding_box']['seconds']:.2g} s; with none "
        f"{by['none']['boxes_per_ray']:.3g} and {_count(by['none']['triangles_per_ray'])} in "
        f"{by['none']['seconds']:.2g} s: the hierarchy tests {_count(saving)} times fewer "
        f"triangles than the one box."
    )
    findings = [
        f"The hierarchy tests {_count(saving)} times fewer triangles per ray than the one box "
        f"around the mesh, at the cost of {by['bvh']['boxes_per_ray']:.3g} box tests, and "
        f"traces the image {by['bounding_box']['seconds'] / by['bvh']['seconds']:.3g} times "
        f"faster.",
        f"One box around the mesh: a ray that misses it tests no triangle, one that enters it "
        f"tests all {triangles:,}; {by['bounding_box']['triangles_per_ray'] / triangles:.1%} of "
        f"the mesh per ray here, the share of the rays that enter the box.",
    ]
    if (by["none"]["box_tests"], by["none"]["primitive_tests"]) == (
        by["bounding_box"]["box_tests"],
        by["bounding_box"]["primitive_tests"],
    ):
        findings.append(
            "'none' counts exactly what 'bounding_box' counts: rtlab's mesh builds one box and "
            "one leaf of every triangle for both (tracer/cpp/16_mesh.h, Mesh::build), so "
            "'none' too skips the triangles of a ray that misses the box."
        )
    return Plot(
        name="bounding-volumes",
        title="Bounding volumes: tests per ray",
        caption=(
            "The Stanford bunny (reference/scenes/bunny.toml, its floor and lights left out, "
            "so every ray counted is a primary ray), rendered by rtlab once per acceleration "
            "mode: bvh (the hierarchy, surface-area heuristic), bounding_box (one box around "
            "the whole mesh), none. The bars: box tests and triangle tests per primary ray, "
            "from the render's own counters (render_with_stats: box_tests, primitive_tests); "
            "above them the trace time of the image (two threads)."
        ),
        alt=alt,
        findings=findings,
        columns=[
            ("mode", "acceleration"),
            ("rays", "primary rays"),
            ("boxes_per_ray", "box tests per ray"),
            ("triangles_per_ray", "triangle tests per ray"),
            ("seconds", "trace time (s)"),
        ],
        rows=rows,
        png=png,
        seconds=time.perf_counter() - start,
        fit={"triangles": triangles, "saving": saving},
    )


#: The plots of each lesson's page.
LESSON_PLOTS: dict[str, list[Callable[[], Plot]]] = {
    "L01": [antialiasing],
    "L09": [bounding_volumes],
    "L12": [global_illumination],
    "L13": [precision],
}


def lesson_plots(lesson_id: str) -> list[Plot]:
    return [make() for make in LESSON_PLOTS.get(lesson_id, [])]
