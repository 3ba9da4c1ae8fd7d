"""Lessons L12 (the path tracer's estimator) and L13 (precision): the stub tree scores zero and
every concept has public and hidden probes (tests/lessons/test_grader.py grades them like
the others), and L13's stiff probes really are stiff: the
textbook formulas, run in double here, fail them while the robust ones pass, and an L02
solution written with the textbook formula still passes L02."""

from __future__ import annotations

import math
import re
import shutil
from pathlib import Path

import pytest

from lessons import grade
from lessons.catalog import get_lesson
from lessons.grader import lesson_probes
from lessons.mistakes import mistakes
from lessons.student import CORE, write_student_tree

LESSONS = ("L12", "L13")
# tests/lessons/test_grader.py grades them as every other lesson (the solution full, every
# known-wrong version caught and named); what is particular to them is here.


@pytest.mark.parametrize("lesson", LESSONS)
def test_public_and_hidden_probes_of_every_concept_and_four_mistakes(lesson: str) -> None:
    probes = lesson_probes(lesson)
    concepts = get_lesson(lesson).concepts
    assert {p.concept for p in probes} == set(concepts)
    for concept in concepts:
        assert {p.visibility for p in probes if p.concept == concept} == {
            "visible",
            "after_published",
        }, concept
    assert len({p.name for p in probes}) == len(probes)
    assert len(mistakes(lesson)) >= 4


@pytest.mark.parametrize("lesson", LESSONS)
def test_the_student_tree_scores_zero_not_implemented(tmp_path: Path, lesson: str) -> None:
    write_student_tree(lesson, tmp_path / "hw")
    result = grade(tmp_path / "hw", lesson=lesson)
    assert result.score == 0 and result.max_score > 0
    assert result.diagnosis.startswith(f"{lesson}: not implemented: ")
    assert all("not implemented" in t.output for t in result.tests)


# --- L13's probes are stiff: the textbook formulas in double fail them -------------------
# The core's formulas and the textbook ones, operation for operation as 05_sphere.h and
# 01_vec3.h evaluate them (the probes build with -ffp-contract=off: no fused multiply-add, so
# Python's doubles round exactly as the C++ does).


def _dot(a: tuple[float, ...], b: tuple[float, ...]) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _discriminant(inputs: tuple[float, ...], textbook: bool) -> float:
    c, r, o, d = inputs[:3], inputs[3], inputs[4:7], inputs[7:10]
    f = tuple(o[i] - c[i] for i in range(3))
    a, b, r2 = _dot(d, d), _dot(f, d), r * r
    if textbook:
        return b * b - a * (_dot(f, f) - r2)
    bi = b * (1 / a)
    ell = tuple(f[i] - bi * d[i] for i in range(3))
    return a * (r2 - _dot(ell, ell))


def _roots(b: float, c0: float, D: float, inv_a: float, textbook: bool) -> tuple[float, float]:
    if textbook:
        s = math.sqrt(D)
        t0, t1 = (-b - s) * inv_a, (-b + s) * inv_a
    else:
        q = -(b + math.copysign(math.sqrt(D), b))
        t0, t1 = (c0 / q, q * inv_a) if q != 0 else (0.0, 0.0)
    return min(t0, t1), max(t0, t1)


def _sphere_t(inputs: tuple[float, ...], textbook: bool) -> float:
    c, r, o, d = inputs[:3], inputs[3], inputs[4:7], inputs[7:10]
    f = tuple(o[i] - c[i] for i in range(3))
    b, c0 = _dot(f, d), _dot(f, f) - r * r
    if c0 > 0 and b > 0:
        return math.inf
    D = _discriminant(inputs, textbook)
    if D < 0:
        return math.inf
    return next((t for t in _roots(b, c0, D, 1 / _dot(d, d), False) if t > 0), math.inf)


def _stiff(name: str) -> bool:
    """Every L13 probe of the quadratic is stiff but the first of each kind (well conditioned:
    any formula passes it, so that a failure elsewhere is the formula's, not the setup's)."""
    return not re.search(r"distance 3$|well separated|from inside|a double root", name)


L13_QUADRATIC = [
    p
    for p in lesson_probes("L13")
    if p.function in ("sphere_discriminant", "quadratic_roots", "sphere_t")
]


@pytest.mark.parametrize("probe", L13_QUADRATIC, ids=[p.name for p in L13_QUADRATIC])
def test_the_robust_formula_passes_and_the_textbook_one_fails_each_stiff_probe(probe) -> None:
    def run(textbook: bool) -> tuple[float, ...]:
        if probe.function == "sphere_discriminant":
            return (_discriminant(probe.inputs, textbook),)
        if probe.function == "quadratic_roots":
            return (1.0, *_roots(*probe.inputs, textbook=textbook))
        return (_sphere_t(probe.inputs, textbook),)

    assert probe.compare(run(textbook=False)) == []
    textbook = probe.compare(run(textbook=True))
    assert bool(textbook) == _stiff(probe.name), textbook
    if textbook and probe.function != "sphere_t":  # by far more than the tolerance
        misses = [
            abs(got - want) / probe.tolerance(want)
            for got, want in zip(run(textbook=True), probe.expected, strict=True)
            if isinstance(want, float)
        ]
        assert max(misses) > 10, misses


NAIVE_ROOTS = """    Vec3 f = ray.o - s.center;
    double a = dot(ray.d, ray.d);
    double b = dot(f, ray.d);
    double r2 = s.radius * s.radius;
    double D = b * b - a * (dot(f, f) - r2);
    if (D < 0) return {};
    double sq = std::sqrt(D);
    return {true, (-b - sq) / a, (-b + sq) / a};
"""
NAIVE_T = """    SphereRoots r = sphere_roots(s, ray);
    if (!r.real) return infinity;
    if (range.surrounds(r.t0)) return r.t0;
    if (range.surrounds(r.t1)) return r.t1;
    return infinity;
"""


def _replace_body(text: str, signature: str, body: str) -> str:
    """The region of the function whose signature line is `signature`, its code replaced."""
    start = text.index(signature)
    begin = text.index("// END SOLUTION", start)
    first = text.rindex("// PROMPT:", start, begin)
    first = text.index("\n", first) + 1
    return text[:first] + body + text[begin - 4 :]


def test_a_textbook_l02_passes_l02_and_its_textbook_l13_fails_l13(tmp_path: Path) -> None:
    text = (CORE / "05_sphere.h").read_text()
    naive = _replace_body(text, "inline SphereRoots sphere_roots(", NAIVE_ROOTS)
    naive = _replace_body(naive, "inline double sphere_t(", NAIVE_T)
    for m in mistakes("L13"):  # the textbook discriminant and roots in L13's regions
        if m.name in ("textbook_discriminant", "textbook_roots"):
            assert naive.count(m.old) == 1
            naive = naive.replace(m.old, m.new)
    assert "b * b - a * (dot(f, f) - r2)" in naive and "(-b - sq) / a" in naive  # injected
    sub = tmp_path / "sub"
    sub.mkdir()
    (sub / "05_sphere.h").write_text(naive)
    shutil.copyfile(CORE / "02_ray.h", sub / "02_ray.h")  # L13's offset, the solution's
    l02 = grade(sub, lesson="L02")
    assert l02.score == l02.max_score, l02.diagnosis
    l13 = grade(sub, lesson="L13")
    failed = {t.concept for t in l13.tests if t.status == "failed"}
    concepts = get_lesson("L13").concepts
    assert failed == set(concepts[:3])  # the quadratic's three; the offsets are still right
    assert l13.diagnosis.startswith("L13: wrong: the robust quadratic")


def test_the_l12_regions_are_the_estimators_parts() -> None:
    from lessons.markers import find_regions

    regions = {(r.file, r.function) for r in find_regions(CORE) if r.lesson == "L12"}
    assert regions == {
        ("20_path.h", f)
        for f in (
            "sample_cosine",
            "cosine_pdf",
            "russian_roulette",
            "connect_to_light",
            "light_estimate",
            "power_heuristic",
            "mis_weights",
        )
    }
    l13 = {(r.file, r.function) for r in find_regions(CORE) if r.lesson == "L13" and not r.is_copy}
    assert l13 == {
        ("05_sphere.h", "sphere_discriminant"),
        ("05_sphere.h", "quadratic_roots"),
        ("02_ray.h", "offset_ray_origin"),
    }
