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
from lessons.mistakes import mistakes
from lessons.student import CORE, write_student_tree

MINE = ("L01", "L05", "L07", "L11")


def test_the_lessons_have_checks() -> None:
    assert set(MINE) <= set(lessons_with_checks())


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


def test_l11_marks_the_stereo_eye_and_keeps_the_core() -> None:
    regions = [r for r in find_regions(CORE) if r.lesson == "L11"]
    assert [(r.file, r.function) for r in regions] == [("03_camera.h", "stereo_eye")]
    assert regions[0].parameters == ("centre", "eye_separation", "convergence", "side")


def test_l07_the_chain_is_the_slides_geometric_series() -> None:
    from lessons.L07_chain.checks import BOTTOM, TOP, WARM, chain

    # Two parallel mirrors, the same one (C, alpha) for ever: sum_{k < D} alpha^k C.
    for depth in (1, 2, 5, 9):
        colour, secondary = chain([WARM] * 50, depth, 0.0, (0.0, 0.0, 0.0))
        alpha = Fraction(WARM.alpha)
        series = (1 - alpha**depth) / (1 - alpha)
        assert colour == tuple(k * series for k in WARM.local())
        assert secondary == depth - 1
    # Alternating mirrors: C_T (1 + aT aB + ...) + aT C_B (1 + aT aB + ...) over 2n levels.
    colour, _ = chain([TOP, BOTTOM] * 10, 8, 0.0, (0.0, 0.0, 0.0))
    q = Fraction(TOP.alpha) * Fraction(BOTTOM.alpha)
    s = (1 - q**4) / (1 - q)
    assert colour == tuple(
        t * s + Fraction(TOP.alpha) * b * s
        for t, b in zip(TOP.local(), BOTTOM.local(), strict=True)
    )
    # A miss after one mirror adds alpha times the background; min_coefficient = alpha^2 still
    # traces the level of coef alpha^2 and stops before alpha^3.
    sky = (0.25, 0.5, 1.0)
    colour, secondary = chain([WARM], 5, 0.0, sky)
    assert colour == tuple(
        k + Fraction(WARM.alpha) * Fraction(b) for k, b in zip(WARM.local(), sky, strict=True)
    )
    assert secondary == 1
    _, secondary = chain([WARM] * 50, 40, WARM.alpha**2, (0.0, 0.0, 0.0))
    assert secondary == 2


def test_l11_toe_in_would_give_vertical_parallax() -> None:
    # The check's closed form: with the frame unchanged the row of a point is the same in both
    # eyes; a toed-in eye (forward turned by atan(h / convergence)) sees it in another row.
    from lessons.L11_stereo.checks import probes

    rows = [p for p in probes() if p.function == "stereo_eye" and p.inputs[0] == 3]
    assert rows and all(p.expected[1] == p.expected[3] for p in rows)
    h, conv, point = 0.125, 4.0, (0.5, 0.75, -2.0)  # the first parallax probe's geometry
    angle = math.atan2(h, conv)
    for side in (-1, 1):
        eye_x = side * h
        # The toed-in eye's forward and right (rotated about y), true_up stays y.
        fx, fz = -side * math.sin(angle), -math.cos(angle)
        v = (point[0] - eye_x, point[1], point[2])
        z = v[0] * fx + v[2] * fz
        row = (0.5 - (v[1] / z) / 2) * 64
        assert abs(row - rows[0].expected[1]) > 0.05  # a visible vertical disparity
