"""``rtlab lesson check [--lesson Lnn]``: the instructor's check of every lesson with checks.

For each lesson: its markers are balanced (every core file parses, the lesson has regions);
its stub tree (``rtlab lesson student Lnn``) compiles (the tree's own ``make``) and scores zero
on the lesson, every check saying "not implemented"; the solution scores full marks; every
known-wrong version (lessons/Lnn_name/mistakes/) is caught and named first by its concept. A
table, and exit status 1 on any failure.
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
import time
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

from lessons.catalog import get_lesson
from lessons.markers import MarkerError, parse
from lessons.mistakes import Mistake, MistakeError, mistakes, write_mistake
from lessons.student import CORE, write_student_tree


@dataclass
class LessonCheck:
    lesson: str
    markers: str = ""  # "ok" or what is wrong
    stub_tree: str = ""
    solution: str = ""
    caught: int = 0
    mistakes: int = 0
    failures: list[str] = field(default_factory=list)
    seconds: float = 0.0

    @property
    def ok(self) -> bool:
        return not self.failures


def _markers(lesson: str) -> str:
    count = 0
    for path in sorted([*CORE.glob("*.h"), *CORE.glob("*.cpp")]):
        try:
            regions = parse(path.read_text(), path.name)
            count += sum(r.lesson == lesson and not r.is_copy for r in regions)
        except MarkerError as error:
            return f"broken: {error}"
    return f"ok ({count} regions)" if count else "no regions of this lesson in tracer/cpp/"


def check_lesson(
    lesson: str, *, scenes: bool = True, known_wrong: Iterable[Mistake] | None = None
) -> LessonCheck:
    """Every check of one lesson; `scenes` False grades the known-wrong versions on their
    probes only (quicker; the solution and the stub tree always run the scenes too), and so
    does a mistake whose concept has no scene in the lesson;
    `known_wrong` replaces the lesson's mistakes (tests feed one that must not be caught)."""
    from lessons.grader import grade
    from lessons.scene_checks import lesson_scenes

    start = time.monotonic()
    report = LessonCheck(lesson)
    report.markers = _markers(lesson)
    if not report.markers.startswith("ok"):
        report.failures.append(f"markers: {report.markers}")
    with tempfile.TemporaryDirectory(prefix="rtlab-check-") as tmp:
        work = Path(tmp)
        tree = work / "tree"
        write_student_tree(lesson, tree)
        made = subprocess.run(["make", "-s", "-C", str(tree)], capture_output=True, text=True)
        if made.returncode != 0:
            report.stub_tree = "does not compile"
            report.failures.append(f"stub tree: make failed:\n{made.stderr[-1500:]}")
        else:
            result = grade(tree, lesson=lesson, integration=False)
            mine = [t for t in result.tests if t.lesson == lesson]
            if result.score == 0 and all(t.kind == "not_implemented" for t in mine):
                report.stub_tree = "compiles, scores 0"
            else:
                report.stub_tree = f"scores {result.score:g}"
                report.failures.append(
                    f"stub tree: expected 0 and 'not implemented' everywhere, got "
                    f"{result.score:g}: {result.diagnosis.splitlines()[0]}"
                )
        solution = work / "solution"
        shutil.copytree(CORE, solution)
        result = grade(solution, lesson=lesson, integration=False)
        if result.score == result.max_score > 0:
            report.solution = f"full ({result.max_score:.4g})"
        else:
            report.solution = f"{result.score:g} of {result.max_score:g}"
            failed = [t.name for t in result.tests if t.status == "failed"]
            report.failures.append(f"solution: fails {', '.join(failed)}")
        wrong = list(mistakes(lesson) if known_wrong is None else known_wrong)
        # A mistake whose concept has no scene is graded on its probes only: a scene of another
        # concept cannot be the check that must name it, and the extension's build (about 5 s
        # of CPU) and the renders are saved.
        with_scenes = {c.concept for c in lesson_scenes(lesson)} if scenes else set()
        report.mistakes = len(wrong)
        for k, mistake in enumerate(wrong):
            sub = work / f"mistake{k}"
            try:
                write_mistake(mistake, sub)
            except MistakeError as error:
                report.failures.append(f"mistake {mistake.name}: {error}")
                continue
            result = grade(
                sub, lesson=lesson, scenes=mistake.concept in with_scenes, integration=False
            )
            first = result.diagnosis.split("\n", 1)[0]
            if first.startswith(f"{lesson}: wrong: {mistake.concept} ("):
                report.caught += 1
            else:
                report.failures.append(
                    f"mistake {mistake.name} ({mistake.description}): expected the first "
                    f"line to name {mistake.concept!r}, got: {first}"
                )
    report.seconds = time.monotonic() - start
    return report


def format_table(reports: list[LessonCheck]) -> str:
    head = f"{'lesson':<7}{'markers':<18}{'stub tree':<22}{'solution':<16}{'mistakes':<12}{'s':>6}"
    lines = [head, "-" * len(head)]
    for r in reports:
        caught = f"{r.caught}/{r.mistakes}"
        lines.append(
            f"{r.lesson:<7}{r.markers[:17]:<18}{r.stub_tree[:21]:<22}{r.solution[:15]:<16}"
            f"{caught:<12}{r.seconds:>6.1f}"
        )
    for r in reports:
        for failure in r.failures:
            lines.append(f"FAIL {r.lesson}: {failure}")
    return "\n".join(lines)


def check_lessons(lessons: list[str], *, scenes: bool = True) -> list[LessonCheck]:
    for lesson in lessons:
        get_lesson(lesson)
    return [check_lesson(lesson, scenes=scenes) for lesson in lessons]
