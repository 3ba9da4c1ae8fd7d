"""The grader on lessons L01 (the camera), L05 (shadow rays), L07 (the chain) and L11
(stereoscopy): tests/lessons/test_grader.py's checks (the solution scores full marks, every
known-wrong version is caught and named by its concept, the stub tree scores zero), for the
lessons with checks that its GRADED tuple does not list yet; and the independent arithmetic
of their checks.py against closed forms."""

from __future__ import annotations

import math
from fractions import Fraction
from pathlib import Path

import pytest

from lessons import grade
from lessons.catalog import get_lesson
from lessons.grader import lesson_probes, lessons_with_checks
from lessons.markers import find_regions
from lessons.mistakes import Mistake, mistakes
from lessons.student import CORE, write_student_tree
from tests.lessons import test_grader

MINE = ("L01", "L05", "L07", "L11")
# Once test_grader.py grades every lesson with checks, these parametrisations run nothing.
LESSONS = [lesson for lesson in MINE if lesson not in test_grader.GRADED]
MISTAKES = [m for lesson in LESSONS for m in mistakes(lesson)]


def test_the_lessons_have_checks() -> None:
    assert set(MINE) <= set(lessons_with_checks())


@pytest.mark.parametrize("lesson", LESSONS)
def test_the_solution_scores_full_marks(tmp_path: Path, lesson: str) -> None:
    test_grader.test_the_solution_scores_full_marks(tmp_path, lesson)


@pytest.mark.parametrize("lesson", MINE)
def test_public_and_hidden_probes_of_every_concept(lesson: str) -> None:
    probes = lesson_probes(lesson)
    assert {p.concept for p in probes} == set(get_lesson(lesson).concepts)
    for concept in get_lesson(lesson).concepts:
        mine = {p.visibility for p in probes if p.concept == concept}
        assert mine == {"visible", "after_published"}, concept
    assert len({p.name for p in probes}) == len(probes)


@pytest.mark.parametrize("lesson", MINE)
def test_at_least_four_known_wrong_versions(lesson: str) -> None:
    assert len(mistakes(lesson)) >= 4


@pytest.mark.parametrize("mistake", MISTAKES, ids=[f"{m.lesson}-{m.name}" for m in MISTAKES])
def test_a_known_wrong_version_is_caught_and_named(tmp_path: Path, mistake: Mistake) -> None:
    test_grader.test_a_known_wrong_version_is_caught_and_named(tmp_path, mistake)


@pytest.mark.parametrize("lesson", MINE)
def test_the_student_tree_scores_zero_not_implemented(tmp_path: Path, lesson: str) -> None:
    write_student_tree(lesson, tmp_path / "hw")
    result = grade(tmp_path / "hw", lesson=lesson)
    assert result.score == 0 and result.max_score > 0
    assert result.diagnosis.startswith(f"{lesson}: not implemented: ")
    functions = {r.function for r in find_regions(CORE) if r.lesson == lesson and not r.is_copy}
    for name in functions:
        assert f"{name}()" in result.diagnosis.split("\n")[0]
    assert all("not implemented" in t.output for t in result.tests)


# --- the checks' own arithmetic against closed forms ---------------------------------------


def test_l01_tangents_match_the_library() -> None:
    from lessons.L01_camera.checks import tan_half

    for fov in (30, 45, 60, 90, 120):
        assert float(tan_half(fov)) == pytest.approx(math.tan(math.radians(fov) / 2), rel=4e-16)
    with pytest.raises(ValueError, match="no closed form"):
        tan_half(50)


def test_l01_the_frame_is_right_handed_and_orthonormal() -> None:
    from lessons.L01_camera.checks import probes

    for p in probes():
        if p.function != "initialize":
            continue
        f, r, u = (p.expected[i : i + 3] for i in (0, 3, 6))
        for v in (f, r, u):
            assert math.hypot(*v) == pytest.approx(1, abs=1e-15)  # type: ignore[arg-type]
        # true_up = right x forward (the frame right, true_up, -forward is right-handed).
        fr = [Fraction(x) for x in f]
        rr = [Fraction(x) for x in r]
        ur = [Fraction(x) for x in u]
        cross = (rr[1] * fr[2] - rr[2] * fr[1], rr[2] * fr[0] - rr[0] * fr[2],
                 rr[0] * fr[1] - rr[1] * fr[0])  # fmt: skip
        assert [float(c) for c in cross] == pytest.approx([float(x) for x in ur], abs=1e-15)
