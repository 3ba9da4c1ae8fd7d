"""The grader (lessons/grader.py): the solution scores full marks, a stub tree scores zero and
says "not implemented", every known-wrong version (lessons/Lnn_*/mistakes/) is caught and named
by its concept, and hostile submissions (compile error, crash, hang, flood, nothing to grade)
each give a results.json that says what happened.

Cost: a grade() with scenes builds the probe program and the extension at once (about 3 s and
4.7 s of CPU at -O1) and renders the lesson's scenes; probes only (scenes=False) is one probe
build. Every mistake is graded on its probes; the mistakes of SCENE_MISTAKES, one per lesson
whose mistake changes the picture, are graded with the scenes too and must fail a scene of
their concept: the scene checks' power is shown once per lesson, and the suite stays within its
budget (22 mistakes x 8 s of builds on 2 cores would add three minutes for no new kind of
evidence)."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from lessons import grade
from lessons.catalog import get_lesson
from lessons.grader import INTEGRATION, lesson_probes, lessons_with_checks
from lessons.markers import parse
from lessons.mistakes import Mistake, mistakes, mutated_text, write_mistake
from lessons.scene_checks import lesson_scenes
from lessons.student import CORE, write_student_tree

GRADED = tuple(lessons_with_checks())  # probes (checks.py) or scenes (scenes/__init__.py)
PROBED = tuple(i for i in GRADED if (get_lesson(i).folder / "checks.py").exists())
MISTAKES = [m for lesson in GRADED for m in mistakes(lesson)]
# Graded with their lesson's scenes too (see the docstring): each changes the picture.
SCENE_MISTAKES = {
    ("L01", "left_handed_frame"),
    ("L02", "t1_before_t0"),
    ("L03", "sign_of_a_minus_o"),
    ("L04", "normal_not_turned"),
    ("L06", "phong_unclamped"),
    ("L08", "triangle_one_sided"),
    ("L09", "first_leaf_is_final"),
    ("L10", "not_renormalised"),
    ("L11", "no_shift"),
    ("L12", "roulette_without_reweighting"),  # the furnace's closed form and Mitsuba's
    ("L13", "textbook_discriminant"),  # the far spheres against Mitsuba
}


def _solution(tmp_path: Path) -> Path:
    out = tmp_path / "solution"
    shutil.copytree(CORE, out)
    return out


@pytest.mark.parametrize("lesson", GRADED)
def test_the_solution_scores_full_marks(tmp_path: Path, lesson: str) -> None:
    result = grade(_solution(tmp_path), lesson=lesson, artifacts=tmp_path)
    failed = [(t.name, t.output) for t in result.tests if t.status == "failed"]
    assert failed == []
    assert result.score == result.max_score > 0
    assert result.diagnosis.startswith(f"{lesson} (")
    assert "all" in result.diagnosis.split("\n")[0]
    # The scenes ran, against both references, and the integration check closed the grade.
    scenes = [t for t in result.tests if t.kind == "scene" and t.lesson == lesson]
    assert len(scenes) == len(lesson_scenes(lesson))
    # Each scene against the references it names: a path-traced scene (L12) Mitsuba's path
    # tracer, in the statistical sense; a stiff one of L13 only those right there; L08's
    # box_edge_on POV-Ray's analytic box alone (Mitsuba's triangles miss that tie).
    pairs = list(zip(scenes, lesson_scenes(lesson), strict=True))
    assert all("against POV-Ray: agrees" in t.output for t, c in pairs if "povray" in c.references)
    assert all("against Mitsuba" in t.output and "agrees" in t.output
               for t, c in pairs if "mitsuba" in c.references)  # fmt: skip
    assert result.tests[-1].lesson == INTEGRATION and result.tests[-1].status == "passed"
    assert not list(tmp_path.glob("*.png"))  # no heat map for a scene that agrees


def test_every_lesson_with_scenes_has_public_and_hidden_ones() -> None:
    scened = [lesson for lesson in GRADED if lesson_scenes(lesson)]
    assert {"L01", "L02", "L03", "L04", "L05", "L06", "L07"} <= set(scened)
    assert {"L08", "L09", "L10", "L11"} <= set(scened)
    for lesson in scened:
        checks = lesson_scenes(lesson)
        assert {c.visibility for c in checks} == {"visible", "after_published"}
        assert {c.concept for c in checks} <= set(get_lesson(lesson).concepts)


def test_every_lesson_has_public_and_hidden_probes_of_every_concept() -> None:
    for lesson in PROBED:
        probes = lesson_probes(lesson)
        assert {p.concept for p in probes} == set(get_lesson(lesson).concepts)
        assert {p.visibility for p in probes} == {"visible", "after_published"}
        assert len({p.name for p in probes}) == len(probes)  # names unique in the lesson


def test_the_l04_student_tree_scores_zero_not_implemented(tmp_path: Path) -> None:
    write_student_tree("L04", tmp_path / "hw04")
    result = grade(tmp_path / "hw04", lesson="L04")
    assert result.score == 0 and result.max_score > 0
    assert result.diagnosis.startswith("L04: not implemented: ")
    for name in ("ambient_term()", "lambert_term()", "to_light()", "face_the_ray()"):
        assert name in result.diagnosis.split("\n")[0]
    mine = [t for t in result.tests if t.lesson == "L04"]
    assert all("not implemented" in t.output for t in mine)
    assert {t.kind for t in mine} == {"not_implemented"}
    assert any(t.kind == "not_implemented" for t in mine if t.name.startswith("scene "))
    # Without --lesson: the stubbed lesson the tree starts with.
    assert grade(tmp_path / "hw04").lessons == ["L04"]


@pytest.mark.parametrize("mistake", MISTAKES, ids=[f"{m.lesson}-{m.name}" for m in MISTAKES])
def test_a_known_wrong_version_is_caught_and_named(tmp_path: Path, mistake: Mistake) -> None:
    # The mutation changed the region it edits, and only it.
    solution = (CORE / mistake.file).read_text()
    text = mutated_text(mistake)
    before = {r.key: r.body for r in parse(solution, mistake.file)}
    after = {r.key: r.body for r in parse(text, mistake.file)}
    changed = [k for k in before if before[k] != after[k]]
    assert changed == [(mistake.file, mistake.lesson, mistake.function)]

    write_mistake(mistake, tmp_path / "sub")
    with_scenes = (mistake.lesson, mistake.name) in SCENE_MISTAKES
    result = grade(
        tmp_path / "sub", lesson=mistake.lesson, scenes=with_scenes, integration=False,
        artifacts=tmp_path,
    )  # fmt: skip
    failed = [t for t in result.tests if t.status == "failed"]
    mine = [t for t in failed if t.concept == mistake.concept]
    assert mine, f"no check of {mistake.concept!r} caught {mistake.name}"
    assert all(t.kind in ("probe", "scene") for t in failed)  # wrong values, not crashes
    if with_scenes:
        # A scene of its concept fails, says where, and left a heat map beside the results.
        scene = next(t for t in mine if t.kind == "scene")
        assert "**differs**" in scene.output and "failing pixels in x " in scene.output
        maps = list(tmp_path.glob(f"{mistake.lesson}-*.png"))
        assert maps and all(f"`{m.name}`" in "".join(t.output for t in failed) for m in maps)
    assert result.diagnosis.split("\n")[0].startswith(
        f"{mistake.lesson}: wrong: {mistake.concept} ("
    )
    # Few others: concepts that do not run the broken one's code fail at most 2 checks.
    from lessons.grader import _checks

    depends = _checks(mistake.lesson).DEPENDS
    elsewhere = [
        t
        for t in failed
        if t.concept != mistake.concept and mistake.concept not in depends.get(t.concept, ())
    ]
    assert len(elsewhere) <= 2, [t.name for t in elsewhere]
    # A failing probe says inputs, expected and got.
    assert "**Inputs**:" in mine[0].output and "expected" in mine[0].output
    assert "got" in mine[0].output
    assert 0 < result.score < result.max_score
    # Without --lesson the grader finds the lesson the edit touches (once per lesson: each
    # grade() is a build).
    if mistake == mistakes(mistake.lesson)[0]:
        assert grade(tmp_path / "sub", scenes=False).lessons == [mistake.lesson]


def _sphere_with(tmp_path: Path, old: str, new: str) -> Path:
    text = (CORE / "05_sphere.h").read_text()
    assert text.count(old) == 1
    out = tmp_path / "hostile"
    out.mkdir()
    (out / "05_sphere.h").write_text(text.replace(old, new))
    assert (out / "05_sphere.h").read_text() != text  # injected
    return out


# The start of sphere_roots()'s body (the same lines begin sphere_t() without `double a`).
ROOTS_START = (
    "    Vec3 f = ray.o - s.center;\n    double a = dot(ray.d, ray.d);\n"
    "    double b = dot(f, ray.d);\n    double r2"
)


def _cli_grade(submission: Path, out: Path, lesson: str = "L02") -> dict:
    done = subprocess.run(
        [sys.executable, "-m", "tracer.cli", "lesson", "grade", str(submission),
         "--lesson", lesson, "--json", str(out)],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    return json.loads(out.read_text())


@pytest.mark.parametrize(
    ("name", "inject", "expect", "first_line"),
    [
        ("compile_error", "    Vec3 f = ray.o - s.centre;\n", "has no member named 'centre'",
         "L02: your code does not compile"),
        ("crash", "    if (ray.o.z > -2) { volatile int *p = nullptr; *p = 1; }\n", "SIGSEGV",
         "L02: the roots of the quadratic: the program crashed"),
        ("hang", "    while (ray.o.z > -2) {\n    }\n", "did not finish within 2 s of CPU",
         "L02: the roots of the quadratic: this check did not finish"),
        ("flood", '    for (int i = 0; i < 100000000; ++i) std::printf("debug %d\\n", i);\n',
         "more than 64 KiB", "L02: the roots of the quadratic: this check wrote too much"),
    ],
)  # fmt: skip
def test_a_hostile_submission_gives_a_clear_results_file(
    tmp_path: Path, name: str, inject: str, expect: str, first_line: str
) -> None:
    old = ROOTS_START
    new = inject + old if name != "compile_error" else old.replace("s.center", "s.centre")
    submission = _sphere_with(tmp_path, old, new)
    data = _cli_grade(submission, tmp_path / "results.json")
    assert data["output"].startswith(first_line), data["output"][:300]
    roots = [t for t in data["tests"] if t["tags"] == ["L02", "the roots of the quadratic"]]
    caught = [t for t in roots if expect in t["output"]]
    assert caught and all(t["status"] == "failed" and t["score"] == 0 for t in caught)
    if name in ("compile_error", "flood"):  # every probe meets it
        assert all(t["status"] == "failed" and t["score"] == 0 for t in roots)
    if name in ("crash", "hang"):
        # Charged to the probe that ran (o.z > -2), not to those before it: a probe from
        # o.z = -3 passes.
        assert data["tests"][0]["status"] == "passed"
        probes = [t for t in data["tests"] if not t["name"].startswith("scene ")]
        first = probes.index(caught[0])
        later = probes[first + 1 :]
        if name == "crash":  # the program went on after it: a later probe ran and passed
            assert any(t["status"] == "passed" for t in later)
        else:  # two hangs cost their limits; the rest are not run (MAX_HANGS)
            assert "not run: 2 checks before it hung" in later[-1]["output"]


@pytest.mark.parametrize("what", ["empty", "not_cpp", "missing"])
def test_nothing_to_grade_still_writes_results(tmp_path: Path, what: str) -> None:
    submission = tmp_path / "sub"
    if what != "missing":
        submission.mkdir()
    if what == "not_cpp":
        (submission / "answer.py").write_text("print('hello')\n")
        (submission / "notes.txt").write_text("my sphere\n")
    data = _cli_grade(submission, tmp_path / "out" / "results.json", lesson="L03")
    assert data["score"] == 0
    assert data["output"].startswith("L03: nothing to grade: ")
    assert data["tests"] and all(t["status"] == "failed" for t in data["tests"])
    assert not [p for p in (tmp_path / "out").iterdir() if p.name != "results.json"]  # no temp left


def test_results_json_follows_gradescope(tmp_path: Path) -> None:
    mistake = next(m for m in mistakes("L04") if m.name == "two_sided_lambert")
    write_mistake(mistake, tmp_path / "sub")
    data = _cli_grade(tmp_path / "sub", tmp_path / "results.json", lesson="L04")
    assert set(data) >= {"score", "execution_time", "output", "tests"}
    assert data["output"].startswith("L04: wrong: diffuse (Lambertian) reflection N.L")
    assert data["score"] == pytest.approx(sum(t["score"] for t in data["tests"]))
    # The last test is the integration check: worth nothing (a mistake is charged once).
    last = data["tests"].pop()
    assert last["tags"] == [INTEGRATION, last["tags"][1]] and last["max_score"] == 0
    for test in data["tests"]:
        assert set(test) >= {"name", "number", "score", "max_score", "status", "tags", "output",
                             "visibility"}  # fmt: skip
        assert test["status"] in ("passed", "failed")
        assert test["visibility"] in ("visible", "after_published")
        assert test["tags"][0] == "L04" and test["tags"][1] in get_lesson("L04").concepts
    # Partial credit per concept: each concept is worth the same, shared among its probes.
    per: dict[str, float] = {}
    for test in data["tests"]:
        per[test["tags"][1]] = per.get(test["tags"][1], 0) + test["max_score"]
    assert set(per) == set(get_lesson("L04").concepts)
    # Each check's share is whole ten-thousandths (results.json's 4 decimals) and a concept's
    # shares sum to its 10 points exactly: summed in ten-thousandths (integers), no float
    # round-off can hide a unit; and the lesson's maximum is a whole 10 per concept.
    assert all(round(v * 10_000) == 100_000 for v in per.values())
    for test in data["tests"]:
        assert test["max_score"] == round(test["max_score"], 4)
    assert 0 < data["score"] < sum(per.values())


def test_a_submission_without_its_markers_is_graded_not_implemented(tmp_path: Path) -> None:
    text = (CORE / "06_plane.h").read_text()
    broken = text.replace(
        "    // END SOLUTION\n}\n\n// The hit record", "}\n\n// The hit record", 1
    )
    assert broken != text
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "06_plane.h").write_text(broken)
    result = grade(tmp_path / "sub", lesson="L03")
    assert result.score == 0
    assert any("markers are broken" in note for note in result.notes)


def test_grading_one_lesson_takes_only_its_regions(tmp_path: Path) -> None:
    # One mistake is charged once: a sphere that does not even compile (L02) and a wrong plane
    # (L03) leave the grade of L04 untouched, and L03's grade names only the plane.
    sub = tmp_path / "sub"
    write_mistake(next(m for m in mistakes("L03") if m.name == "sign_of_a_minus_o"), sub)
    shutil.copyfile(CORE / "10_classic.h", sub / "10_classic.h")
    shutil.copyfile(CORE / "04_hit.h", sub / "04_hit.h")
    sphere = (CORE / "05_sphere.h").read_text()
    broken = sphere.replace(
        "    double a = dot(ray.d, ray.d);\n", "    double a = dot(ray.d);\n", 1
    )
    assert broken != sphere
    (sub / "05_sphere.h").write_text(broken)
    l04 = grade(sub, lesson="L04", integration=False)
    assert l04.score == l04.max_score
    l03 = grade(sub, lesson="L03", scenes=False)
    assert l03.diagnosis.startswith("L03: wrong: the plane (p - a).n = 0")
    assert grade(sub, scenes=False).lessons == ["L02", "L03"]
