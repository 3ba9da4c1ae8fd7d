"""A lesson page's contents, every number of it computed here, by the run that makes the page.

For each scene of the lesson (lessons/Lnn_name/scenes/): the solution rendered by rtlab (the
one-ray tracer, ``packets=False``, as the grader renders a student's code), POV-Ray and Mitsuba
rendered now and timed (reference/compare.py's runners), each reference against rtlab by
reference/metrics.py (RMSE, max abs, PSNR, SSIM, FLIP, the share over tolerance) under the
grader's rule (lessons/scene_checks.py: the tolerance per reference, the share scaled to the
image's width). For the known-wrong versions (lessons/Lnn_name/mistakes/*.json): each built as
an extension (lessons/sandbox.py, a child process; the build cached), the lesson's scenes
rendered with it in a child process (lessons/scene_checks.render_student, as the grader does),
and the scene it changes most shown beside the correct image.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import tempfile
import time
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

ROOT = Path(__file__).resolve().parent.parent
# Built extensions of the known-wrong versions, keyed by the digest of what goes into the
# build (the core's sources with the edit, the support header, the compiler flags): a build
# takes 3.5 s (lessons/sandbox.py), a render of a lesson's scenes a few tenths of one.
MISTAKE_CACHE = ROOT / "build" / "report-mistakes"
# How many known-wrong versions a page builds and shows by default (`--mistakes`): each costs
# a build when not cached; the others are listed with their description and concept.
DEFAULT_MISTAKES = 3
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
    check: SceneCheck
    width: int
    height: int
    runs: dict[str, RendererRun]
    rows: list[ComparisonRow]
    share_argument: str
    tolerances: dict[str, Any] = field(default_factory=dict)  # per reference, as compared


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
    caught: str = ""  # what the scene check against POV-Ray says of it
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


def run_reference(name: str, scene: Any) -> tuple[RendererRun, Any]:
    from reference.compare import run_reference as run

    r = run(name, scene, threads=2)
    rays = {k: int(v) for k, v in r.notes.get("rays", {}).items()}
    note = r.notes.get("variant", "")
    return RendererRun(name, r.image, r.trace_seconds, r.whole_seconds, rays, note), r.tolerance


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
    scene = check.load()
    share = share_bound(scene.camera.width)
    runs = {"rtlab": run_rtlab(scene)}
    rows, tolerances = [], {}
    for name in check.references:
        run, tolerance = run_reference(name, scene)
        runs[name], tolerances[name] = run, tolerance
        rows.append(compare_row(check, name, run.image, runs["rtlab"].image, tolerance, share))
    width, height = scene.camera.width, scene.camera.height
    argument = SHARE_ARGUMENT.format(share=100 * share, width=width)
    return ScenePage(check, width, height, runs, rows, argument, tolerances)


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
        partial = cache / key / f".{build.binary.name}.{os.getpid()}"
        shutil.copyfile(build.binary, partial)
        os.replace(partial, cache / key / build.binary.name)
    return build, False


def show_mistake(mistake: Mistake, scenes: list[ScenePage]) -> MistakeShown:
    from lessons.scene_checks import compare_image, render_student

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
        correct = page.runs["rtlab"].image
        diff = np.abs(r.image.astype(np.float64) - correct.astype(np.float64)).max(axis=-1)
        changed = int(np.sum(~(diff <= VISIBLE_CHANGE)))  # NaN counts as changed
        # The scene of the mistake's own concept first, then the one it changes most.
        rank = (changed > 0, page.check.concept == mistake.concept, changed)
        if best is None or rank > best[0]:
            best = (rank, page, r.image, changed, float(np.nanmax(diff)))
    assert best is not None
    _, page, image, changed, worst = best
    shown.scene, shown.image, shown.correct = page.check.name, image, page.runs["rtlab"].image
    shown.pixels_changed, shown.max_abs = changed, worst
    shown.pixels = int(image.shape[0] * image.shape[1])
    if "povray" in page.runs:
        pov, tol = page.runs["povray"], page.tolerances["povray"]
        ok, text = compare_image("POV-Ray", pov.image, image, tol, share_bound(page.width))
        # compare_image's line without its "against POV-Ray: " and Markdown emphasis.
        said = text.replace("**", "").split(": ", 1)[1].removeprefix("differs: ")
        shown.caught = ("passes: " if ok else "fails: ") + said
    return shown


def choose_mistakes(
    lesson: str, cap: int, scenes: list[ScenePage]
) -> tuple[list[Mistake], list[Mistake]]:
    """At most ``cap`` to build: those whose concept a scene of the lesson checks first (their
    picture most likely changes), in file order; the rest are listed."""
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


def build_lesson_page(lesson_id: str, *, mistake_cap: int = DEFAULT_MISTAKES,
                      command: str = "") -> LessonPage:  # fmt: skip
    lesson = get_lesson(lesson_id)
    title, text = lesson_text(lesson)
    start = time.perf_counter()
    scenes = [scene_page(c) for c in lesson_scenes(lesson.id)]
    scene_seconds = time.perf_counter() - start
    chosen, listed = choose_mistakes(lesson.id, mistake_cap, scenes)
    start = time.perf_counter()
    shown = [show_mistake(m, scenes) for m in chosen]
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
