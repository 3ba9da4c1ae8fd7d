"""A lesson page's contents, every number of it computed here, by the run that makes the page.

For each scene of the lesson (lessons/Lnn_name/scenes/): the solution rendered by rtlab (the
one-ray tracer, ``packets=False``, as the grader renders a student's code) and judged by the
grader's own comparisons (lessons/scene_checks.py judge, judge_path) against the grader's
cached references; each reference's metric row against rtlab by reference/metrics.py (RMSE,
max abs, PSNR, SSIM, FLIP, the share over tolerance) under the grader's rule (the tolerance
per reference, the share scaled to the image's width); POV-Ray and Mitsuba rendered again now
to be timed (reference/compare.py's runners).

For the known-wrong versions (lessons/Lnn_name/mistakes/*.json): each built as an extension
(lessons/sandbox.py, a child process; the build cached), the lesson's scenes rendered with it
in a child process (lessons/scene_checks.render_student, as the grader does), and the scene it
changes most shown beside the correct image.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from lessons.catalog import Lesson, get_lesson
from lessons.mistakes import Mistake, mistakes, write_mistake
from lessons.probe import HIDDEN
from lessons.scene_checks import SceneCheck, lesson_scenes, share_bound
from reports.plots import Plot, lesson_plots
from tracer import interrupt

ROOT = Path(__file__).resolve().parent.parent
# Built extensions of the known-wrong versions, keyed by the digest of what goes into the
# build (the core's sources with the edit, the support header, the compiler flags): a build
# takes 3.5 s (lessons/sandbox.py), a render of a lesson's scenes a few tenths of one.
MISTAKE_CACHE = ROOT / "build" / "report-mistakes"
# How many known-wrong versions a page builds and shows (`--mistakes N`; by default every one,
# as "what the mistake looks like" asks): each costs a build when not cached (two at a time,
# one per core); those over a cap are listed with their description and concept.
DEFAULT_MISTAKES: int | None = None
# A known-wrong version "changes the picture" where a pixel of a scene differs from the
# correct image by more than the tolerance the references are held to against rtlab
# (MITSUBA_TOLERANCE, 1e-4): a smaller change is not one the scene checks could see.
VISIBLE_CHANGE = 1e-4

Image = npt.NDArray[np.float32]

TOLERANCE_ARGUMENT = {
    "povray": (
        "POV-Ray's per-pixel output precision (its 16-bit PNG's half step, read back per "
        "pixel and channel) + 2.4e-7 for our float32 rounding (reference/metrics.py "
        "FLOAT32_SLACK)"
    ),
    "mitsuba": (
        "1e-4 absolute (reference/metrics.py MITSUBA_TOLERANCE): Mitsuba intersects in "
        "float32, moving hit points by ~1e-6, which a Phong lobe of exponent up to 200 turns "
        "into ~2e-4 relative of a highlight of at most 0.5"
    ),
    # A path scene's row (path_scene_page): Monte Carlo estimates agree in the statistical sense.
    "mitsuba-path": (
        "statistical, as the grader's (lessons/scene_checks.py PathSceneCheck): each pixel's "
        "z-test of rtlab's mean over its independent renders against Mitsuba's path tracer "
        "at {ref_spp} spp, Šidák-corrected at alpha = {alpha:g} (the per-pixel tolerance is that "
        "test's threshold: {z:.3g} standard errors), and the t-tests of the whole image's and "
        "each block's mean; the image agrees when all of them pass"
    ),
}
SHARE_ARGUMENT = (
    "at most {share:.3g}% of the pixels: grazing silhouettes may differ by a whole colour "
    "(float32 against double hit-or-miss decisions); the reference suite allows 0.05% at 160 "
    "pixels wide, and at {width} pixels the same silhouettes are 160 / {width} times the share "
    "(lessons/scene_checks.py share_bound)"
)
NAMES = {"rtlab": "rtlab", "povray": "POV-Ray", "mitsuba": "Mitsuba 3"}


@dataclass
class RendererRun:
    renderer: str  # rtlab, povray, mitsuba
    image: Image
    trace_seconds: float
    whole_seconds: float
    rays: dict[str, int] = field(default_factory=dict)
    note: str = ""


@dataclass
class ComparisonRow:
    """One reference against rtlab: the fields of reference.compare's rows, with the rule."""

    scene: str
    renderer: str
    rmse: float
    max_abs: float
    psnr: float
    ssim: float
    flip: float
    over_tolerance: float
    pixels_over: int
    pixels: int
    tolerance: str  # the number, or "per pixel"
    tolerance_argument: str
    max_share: float
    agrees: bool
    verdict: str

    def as_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


@dataclass
class ScenePage:
    """One scene: the images shown and compared are rtlab's, rendered now, and the grader's
    references (lessons/scene_checks.py references(): POV-Ray's and Mitsuba's, cached in
    build/lesson-references), so the page's verdict is the grader's; the times are of the
    references rendered again now, at the scene's own settings (``runs``)."""

    check: SceneCheck
    width: int
    height: int
    runs: dict[str, RendererRun]  # the times; rtlab's image
    rows: list[ComparisonRow]
    share_argument: str
    images: dict[str, Image] = field(default_factory=dict)  # renderer -> the image compared
    verdict: list[str] = field(default_factory=list)  # the grader's lines, Markdown
    agrees: bool = True  # the grader's verdict on the solution
    refs: dict[str, Any] = field(default_factory=dict)  # the grader's cached references


@dataclass
class MistakeShown:
    mistake: Mistake
    outcome: str  # "ok" (rendered), or the build's or render's outcome kind
    message: str = ""
    scene: str = ""  # the scene it changes most
    image: Image | None = None  # the known-wrong version's image of that scene
    correct: Image | None = None
    pixels_changed: int = 0
    pixels: int = 0
    max_abs: float = 0.0
    caught: str = ""  # what the grader's check of that scene says of it (its first failure)
    build_seconds: float = 0.0
    cached: bool = False
    render_seconds: float = 0.0

    @property
    def changes_picture(self) -> bool:
        return self.outcome == "ok" and self.pixels_changed > 0


@dataclass
class ProbeConcept:
    concept: str
    visible: int
    hidden: int


@dataclass
class LessonPage:
    lesson: Lesson
    title: str
    text_markdown: str  # lesson.md without its first heading ("" when it has no text)
    scenes: list[ScenePage]
    mistakes_shown: list[MistakeShown]
    mistakes_listed: list[Mistake]  # not built (over the cap)
    probe_concepts: list[ProbeConcept]
    scene_seconds: float
    mistake_seconds: float
    command: str
    made: str  # when, UTC
    plots: list[Plot] = field(default_factory=list)  # reports/plots.py, measured by this run

    @property
    def rows(self) -> list[ComparisonRow]:
        return [row for s in self.scenes for row in s.rows]


# --- the scenes -----------------------------------------------------------------------------


def run_rtlab(scene: Any) -> RendererRun:
    """The solution, one ray at a time (the path the grader renders a student's code by)."""
    from tracer.render import render_with_stats

    start = time.perf_counter()
    result = render_with_stats(scene, threads=2, progress=False, packets=False)
    return RendererRun("rtlab", result.image, result.seconds, time.perf_counter() - start,
                       dict(result.rays))  # fmt: skip


def run_reference(name: str, scene: Any) -> RendererRun:
    """A reference renderer on the scene, timed now (reference/compare.py's runners): a stereo
    pair one eye at a time (the converters take one eye), the eyes' times and rays added."""
    from lessons.scene_checks import _stereo_layout
    from reference.compare import run_reference as run
    from tracer.render import eye_scene

    if _stereo_layout(scene) is not None:
        eyes = [run_reference(name, eye_scene(scene, eye)) for eye in ("left", "right")]
        rays = {k: eyes[0].rays.get(k, 0) + eyes[1].rays.get(k, 0)
                for k in {*eyes[0].rays, *eyes[1].rays}}  # fmt: skip
        return RendererRun(name, eyes[0].image, sum(e.trace_seconds for e in eyes),
                           sum(e.whole_seconds for e in eyes), rays,
                           "both eyes, one at a time")  # fmt: skip
    r = run(name, scene, threads=2)
    rays = {k: int(v) for k, v in r.notes.get("rays", {}).items()}
    return RendererRun(name, r.image, r.trace_seconds, r.whole_seconds, rays,
                       r.notes.get("variant", ""))  # fmt: skip


def compare_row(
    check: SceneCheck, name: str, reference: Image, ours: Image, tolerance: Any, share: float
) -> ComparisonRow:
    from reference.metrics import agrees, compare

    c = compare(reference, ours, tolerance)
    ok, text = agrees(reference, ours, tolerance, share)
    per_pixel = not np.isscalar(tolerance)
    return ComparisonRow(
        scene=check.name,
        renderer=name,
        rmse=c.rmse,
        max_abs=c.max_abs,
        psnr=c.psnr,
        ssim=c.ssim,
        flip=c.flip,
        over_tolerance=c.over_tolerance,
        pixels_over=c.pixels_over,
        pixels=int(reference.shape[0] * reference.shape[1]),
        tolerance=f"per pixel, at most {c.tolerance:.3g}" if per_pixel else f"{c.tolerance:g}",
        tolerance_argument=TOLERANCE_ARGUMENT[name],
        max_share=share,
        agrees=ok,
        verdict=text,
    )


def scene_page(check: SceneCheck) -> ScenePage:
    """A classic scene: rtlab's image and aov rendered now, judged by the grader's own
    comparisons (lessons/scene_checks.py judge) against its cached references; each
    reference's metric row by the same rule; each reference timed again now."""
    from lessons.scene_checks import PathSceneCheck, Rendered, judge, references
    from reference.metrics import FLOAT32_SLACK, MITSUBA_TOLERANCE
    from tracer.render import render_with_stats

    # Each scene renders rtlab and times its references: seconds. A Ctrl-C lost in a finaliser
    # (a reference run's temporary directory: tracer/interrupt.py) stops the report here.
    interrupt.raise_if_interrupted()
    if isinstance(check, PathSceneCheck):
        return path_scene_page(check)
    scene = check.load()
    share = share_bound(scene.camera.width)
    refs = references(check)
    ours = run_rtlab(scene)
    aov = render_with_stats(scene.with_overrides(integrator="aov"), threads=2, progress=False)
    verdict = judge(check, Rendered("ok", image=ours.image, aov=aov.image, rays=ours.rays), refs)
    runs, rows, images = {"rtlab": ours}, [], {"rtlab": ours.image}
    for name in check.references:
        runs[name] = run_reference(name, scene)
        images[name] = refs[name]
        tolerance = refs["povray_bound"] + FLOAT32_SLACK if name == "povray" else MITSUBA_TOLERANCE
        rows.append(compare_row(check, name, refs[name], ours.image, tolerance, share))
    width, height = scene.camera.width, scene.camera.height
    argument = SHARE_ARGUMENT.format(share=100 * share, width=width)
    return ScenePage(check, width, height, runs, rows, argument, images, verdict.lines,
                     verdict.ok, refs)  # fmt: skip


def path_scene_page(check: Any) -> ScenePage:
    """A path-traced scene: rtlab renders the grader's independent replicates now (one ray at a
    time, each its own seed); the grader's statistical comparison (judge_path) against
    Mitsuba's path tracer at high spp (cached); the metric row of their mean against
    Mitsuba's mean; Mitsuba timed now at the scene's own spp (one render, as rtlab's one)."""
    from scipy import stats

    from lessons.scene_checks import Rendered, judge_path, path_seeds, references
    from reference.metrics import compare

    scene = check.load()
    refs = references(check)
    seeds = path_seeds(check) or []
    replicates = [run_rtlab(scene.with_overrides(seed=seed)) for seed in seeds]
    images = [r.image for r in replicates]
    verdict = judge_path(check, Rendered("ok", image=images), refs)
    first = replicates[0]
    note = f"one of {len(seeds)} renders, {scene.render.spp} spp"
    ours = RendererRun("rtlab", first.image, first.trace_seconds, first.whole_seconds,
                       first.rays, note)  # fmt: skip
    runs = {"rtlab": ours}
    mean = np.mean(np.stack(images).astype(np.float64), axis=0).astype(np.float32)
    shown = {"rtlab": mean}
    spp_total = scene.render.spp * len(images)
    ref_spp = int(refs["path_spp"])
    variance = np.maximum(refs["path_variance"], np.var(images, axis=0, ddof=1) * scene.render.spp)
    pixels = scene.camera.width * scene.camera.height
    alpha_sidak = 1 - (1 - check.alpha) ** (1 / (3 * pixels))
    z = float(stats.norm.isf(alpha_sidak / 2))
    tolerance = z * np.sqrt(np.maximum(variance, 1e-4) / spp_total)
    rows = []
    if "mitsuba" in check.references:
        runs["mitsuba"] = run_reference("mitsuba", scene)
        runs["mitsuba"].note = f"{scene.render.spp} spp, timed now; the reference: {ref_spp} spp"
        reference = refs["path_mean"].astype(np.float32)
        shown["mitsuba"] = reference
        c = compare(reference, mean, tolerance)
        rows.append(ComparisonRow(
            scene=check.name, renderer="mitsuba", rmse=c.rmse, max_abs=c.max_abs, psnr=c.psnr,
            ssim=c.ssim, flip=c.flip, over_tolerance=c.over_tolerance, pixels_over=c.pixels_over,
            pixels=pixels, tolerance=f"z-test per pixel, at most {c.tolerance:.3g}",
            tolerance_argument=TOLERANCE_ARGUMENT["mitsuba-path"].format(
                ref_spp=ref_spp, alpha=check.alpha, z=z),
            max_share=0.0025, agrees=verdict.ok, verdict="; ".join(verdict.lines),
        ))  # fmt: skip
    width, height = scene.camera.width, scene.camera.height
    argument = (
        "the z-test passes in at least 99.75% of the pixels' channels (reference/stats.py "
        "pixel_test), and the t-tests of the image's and every block's mean pass"
    )
    return ScenePage(check, width, height, runs, rows, argument, shown, verdict.lines,
                     verdict.ok, refs)  # fmt: skip


# --- the known-wrong versions ---------------------------------------------------------------


def _build_key(submission: Path) -> str:
    from lessons.sandbox import BUILD_FLAGS
    from lessons.student import CORE

    h = hashlib.sha256(" ".join(BUILD_FLAGS).encode())
    names = {p.name for p in submission.iterdir()}
    for path in sorted(CORE.iterdir()):
        source = submission / path.name if path.name in names else path
        h.update(path.name.encode() + b"\0" + source.read_bytes())
    return h.hexdigest()[:24]


def build_mistake(mistake: Mistake, work: Path, cache: Path = MISTAKE_CACHE) -> tuple[Any, bool]:
    """The known-wrong version's extension: from the cache, or built (a child process under
    the sandbox's limits) and cached (copied to a temporary name and renamed)."""
    from lessons.sandbox import Build, Outcome, build_extension

    submission = work / "submission"
    write_mistake(mistake, submission)
    key = _build_key(submission)
    cached = sorted((cache / key).glob("_core*.so")) if (cache / key).is_dir() else []
    if cached:
        return Build(Outcome("ok", 0, "", 0.0, "cached"), cached[0], []), True
    build = build_extension(submission, work / "ext")
    if build.binary is not None:
        (cache / key).mkdir(parents=True, exist_ok=True)
        partial = cache / key / f".{build.binary.name}.{os.getpid()}.{threading.get_ident()}"
        shutil.copyfile(build.binary, partial)
        os.replace(partial, cache / key / build.binary.name)
    return build, False


def show_mistake(mistake: Mistake, scenes: list[ScenePage]) -> MistakeShown:
    from lessons.scene_checks import judge, render_student

    checks = [s.check for s in scenes]
    with tempfile.TemporaryDirectory(prefix="rtlab-report-") as tmp:
        start = time.perf_counter()
        build, cached = build_mistake(mistake, Path(tmp))
        built = time.perf_counter() - start
        shown = MistakeShown(mistake, build.outcome.kind, build_seconds=built, cached=cached)
        if build.binary is None:
            shown.message = build.outcome.message
            return shown
        start = time.perf_counter()
        rendered = render_student(build, checks, Path(tmp) / "renders")
        shown.render_seconds = time.perf_counter() - start
    best = None
    for page, r in zip(scenes, rendered, strict=True):
        if r.image is None:
            shown.outcome, shown.message, shown.scene = r.kind, r.message, page.check.name
            return shown
        # A path scene's renders are the grader's replicates (the solution's seeds): their
        # mean is the image, against the solution's mean of the same seeds.
        image = r.image if r.image.ndim == 3 else np.mean(r.image, axis=0, dtype=np.float64)
        image = np.asarray(image, np.float32)
        correct = page.images["rtlab"]
        diff = np.abs(image.astype(np.float64) - correct.astype(np.float64)).max(axis=-1)
        changed = int(np.sum(~(diff <= VISIBLE_CHANGE)))  # NaN counts as changed
        # The scene of the mistake's own concept first, then the one it changes most.
        rank = (changed > 0, page.check.concept == mistake.concept, changed)
        if best is None or rank > best[0]:
            best = (rank, page, image, changed, float(np.nanmax(diff)), r)
    assert best is not None
    _, page, image, changed, worst, rendered_best = best
    shown.scene, shown.image, shown.correct = page.check.name, image, page.images["rtlab"]
    shown.pixels_changed, shown.max_abs = changed, worst
    shown.pixels = int(image.shape[0] * image.shape[1])
    verdict = judge(page.check, rendered_best, page.refs)
    failing = [line for line in verdict.lines if "**differs**" in line or "**" in line]
    if verdict.ok:
        shown.caught = "passes every comparison of the scene"
    else:
        # The grader's first failing line ("against X: **differs**: ..."), said as a sentence.
        line = (failing or verdict.lines)[0]
        line = line.replace(": **differs**:", ":", 1).replace("**", "")
        shown.caught = "fails " + line
    return shown


def choose_mistakes(
    lesson: str, cap: int | None, scenes: list[ScenePage]
) -> tuple[list[Mistake], list[Mistake]]:
    """At most ``cap`` (None: all) to build: those whose concept a scene of the lesson checks
    first (their picture most likely changes), in file order; the rest are listed."""
    found = mistakes(lesson)
    if not scenes:
        return [], found
    concepts = {s.check.concept for s in scenes}
    ordered = sorted(found, key=lambda m: m.concept not in concepts)
    return ordered[:cap], [m for m in found if m not in ordered[:cap]]


# --- the page -------------------------------------------------------------------------------


def lesson_text(lesson: Lesson) -> tuple[str, str]:
    """(title, the Markdown after the first heading) of lesson.md; the catalog's title and ""
    when the lesson has no text yet."""
    if not lesson.text_path.exists():
        return f"{lesson.id}: {lesson.title}", ""
    lines = lesson.text_path.read_text().split("\n")
    if lines and lines[0].startswith("# "):
        return lines[0][2:].strip(), "\n".join(lines[1:]).strip() + "\n"
    return f"{lesson.id}: {lesson.title}", "\n".join(lines)


def probe_concepts(lesson: Lesson) -> list[ProbeConcept]:
    from lessons.grader import lesson_probes

    probes = lesson_probes(lesson.id)
    return [
        ProbeConcept(
            concept,
            sum(p.concept == concept and p.visibility == "visible" for p in probes),
            sum(p.concept == concept and p.visibility == HIDDEN for p in probes),
        )
        for concept in lesson.concepts
    ]


def build_lesson_page(lesson_id: str, *, mistake_cap: int | None = DEFAULT_MISTAKES,
                      command: str = "") -> LessonPage:  # fmt: skip
    lesson = get_lesson(lesson_id)
    title, text = lesson_text(lesson)
    start = time.perf_counter()
    scenes = [scene_page(c) for c in lesson_scenes(lesson.id)]
    scene_seconds = time.perf_counter() - start
    chosen, listed = choose_mistakes(lesson.id, mistake_cap, scenes)
    start = time.perf_counter()
    # Each known-wrong version builds and renders in child processes: one per core at once.
    with ThreadPoolExecutor(max_workers=max(1, os.cpu_count() or 1)) as pool:
        shown = list(pool.map(lambda m: show_mistake(m, scenes), chosen))
    mistake_seconds = time.perf_counter() - start
    return LessonPage(
        lesson=lesson,
        title=title,
        text_markdown=text,
        scenes=scenes,
        mistakes_shown=shown,
        mistakes_listed=listed,
        probe_concepts=probe_concepts(lesson),
        scene_seconds=scene_seconds,
        mistake_seconds=mistake_seconds,
        command=command,
        made=time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        plots=lesson_plots(lesson.id),
    )
