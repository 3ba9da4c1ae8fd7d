"""The solution markers of tracer/cpp/ (lessons/markers.py): balanced, each a whole function
body of a known lesson, the regions the lessons name; and the parser refuses every malformed
marker with file:line."""

from __future__ import annotations

import pytest

from lessons.catalog import LESSON_IDS
from lessons.markers import MarkerError, find_regions, parse, parse_signature
from tests.helpers import ROOT

CPP = ROOT / "tracer" / "cpp"

# The functions a student writes, per lesson (the table; the lessons after L07 later).
EXPECTED = {
    "L01": {("02_ray.h", "at"), ("03_camera.h", "initialize"), ("03_camera.h", "primary_ray")},
    "L02": {("05_sphere.h", f) for f in ("sphere_roots", "sphere_case", "sphere_t")},
    "L03": {("06_plane.h", "plane_t"), ("06_plane.h", "intersect_plane")},
    "L04": {
        ("10_classic.h", "ambient_term"),
        ("10_classic.h", "lambert_term"),
        ("10_classic.h", "to_light"),
        ("04_hit.h", "face_the_ray"),
    },
    "L05": {
        ("10_classic.h", "shadow_ray"),
        ("10_classic.h", "in_shadow"),
        ("04_hit.h", "shadow_ray_to"),
        ("04_hit.h", "shadow_ray_towards"),
    },
    "L06": {("10_classic.h", "reflect"), ("10_classic.h", "phong_term")},
    "L07": {("10_classic.h", "local_color"), ("10_classic.h", "trace")},
}


def test_the_core_markers_parse_and_hold_the_lessons_regions():
    regions = find_regions(CPP)  # raises MarkerError on any unbalanced or unknown marker
    found: dict[str, set[tuple[str, str]]] = {}
    for r in regions:
        found.setdefault(r.lesson, set()).add((r.file, r.function))
        assert r.body, f"{r.file}:{r.begin}: an empty solution region"
    for lesson, functions in EXPECTED.items():
        missing = functions - found.get(lesson, set())
        assert not missing, f"{lesson}: no region in {missing}"


def test_every_region_has_a_prompt():
    for r in find_regions(CPP):
        assert len(r.prompt) > 20, f"{r.file}:{r.begin} {r.function}(): no prompt"


def test_signatures_give_names_and_parameters():
    assert parse_signature("inline double lambert_term(const Vec3 &N, const Vec3 &L) {") == (
        "lambert_term",
        ("N", "L"),
    )
    assert parse_signature(
        "inline Color local_color(const Scene &scene, const Material &m, "
        "std::pair<int, int> p = {1, 2}) {"
    ) == ("local_color", ("scene", "m", "p"))
    assert parse_signature("inline Color trace() {") == ("trace", ())


GOOD = """inline double f(double x) {
    // BEGIN SOLUTION L04
    // PROMPT: twice x
    return 2 * x;
    // END SOLUTION
}
"""


def test_a_good_region_parses():
    (r,) = parse(GOOD, "a.h", set(LESSON_IDS))
    assert (r.lesson, r.function, r.parameters, r.prompt) == ("L04", "f", ("x",), "twice x")
    assert r.body == ("    return 2 * x;",) and (r.begin, r.end) == (2, 5)


def test_given_code_parses_after_the_prompt():
    text = GOOD.replace(
        "    return 2 * x;\n", "    // GIVEN: return x + x; // plain\n    return 2 * x;\n"
    )
    (r,) = parse(text, "a.h", set(LESSON_IDS))
    assert r.given == ("    return x + x; // plain",) and r.body == ("    return 2 * x;",)
    assert r.prompt == "twice x"


BAD = {
    "unclosed": (GOOD.replace("    // END SOLUTION\n", ""), "a.h:2", "never closed"),
    "end without begin": (
        GOOD.replace("    // BEGIN SOLUTION L04\n", ""),
        "a.h:4",
        "without a BEGIN",
    ),
    "nested": (
        GOOD.replace("    return 2 * x;\n", "    // BEGIN SOLUTION L05\n    return 2 * x;\n"),
        "a.h:4",
        "do not nest",
    ),
    "unknown lesson": (GOOD.replace("L04", "L4"), "a.h:2", "did you mean L04"),
    "lesson out of range": (GOOD.replace("L04", "L99"), "a.h:2", "unknown lesson 'L99'"),
    "misspelt": (GOOD.replace("BEGIN SOLUTION", "BEGIN SOLUTON"), "a.h:2", "malformed"),
    "lower case": (GOOD.replace("END SOLUTION", "end solution"), "a.h:5", "malformed"),
    "not a body": (
        GOOD.replace("{\n    // BEGIN", "\n    // BEGIN"),
        "a.h:2",
        "first line of a function body",
    ),
    "given inside the solution": (
        GOOD.replace("    return 2 * x;\n", "    return 2 * x;\n    // GIVEN: return x + x;\n"),
        "a.h:5",
        "inside the solution",
    ),
    "given outside a region": (
        "// GIVEN: return 0;\n" + GOOD,
        "a.h:1",
        "outside a solution region",
    ),
    "code after end": (
        GOOD.replace("    // END SOLUTION\n", "    // END SOLUTION\n    x = 0;\n"),
        "a.h:5",
        "last line of a function body",
    ),
}


@pytest.mark.parametrize("case", BAD, ids=list(BAD))
def test_malformed_markers_are_refused_with_file_and_line(case):
    text, where, words = BAD[case]
    assert text != GOOD, "the injection changed nothing"
    with pytest.raises(MarkerError) as error:
        parse(text, "a.h", set(LESSON_IDS))
    assert str(error.value).startswith(where + ":"), str(error.value)
    assert words in str(error.value)
