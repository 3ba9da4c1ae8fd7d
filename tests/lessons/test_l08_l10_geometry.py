"""The geometry lessons L08 (box and triangle), L09 (mesh and hierarchy), L10 (smooth
normals): their student trees score zero and name every function they stub; the probes' scenes
are what their names say (a hierarchy whose boxes overlap); the expected values
of the exact computations agree with closed forms worked by hand."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from lessons import grade
from lessons.L08_box_triangle.checks import exact_slabs, exact_triangle
from lessons.L09_mesh_bvh.checks import OVERLAP, STACK, TWO_Z, closest
from lessons.student import write_student_tree
from tracer import _core

STUBBED = {
    "L08": ("slab_interval()", "box_crossing()", "intersect_triangle()", "triangle_hit()"),
    "L09": ("slab_test()", "traverse()"),
    "L10": ("smooth_normal()",),
}


@pytest.mark.parametrize("lesson", sorted(STUBBED))
def test_the_student_tree_scores_zero_not_implemented(tmp_path: Path, lesson: str) -> None:
    write_student_tree(lesson, tmp_path / "hw")
    result = grade(tmp_path / "hw", lesson=lesson)
    assert result.score == 0 and result.max_score > 0
    first = result.diagnosis.split("\n")[0]
    assert first.startswith(f"{lesson}: not implemented: ")
    for name in STUBBED[lesson]:
        assert name in first
    assert all("not implemented" in t.output for t in result.tests)


def test_the_exact_slab_test_by_hand() -> None:
    # Box [-1, 1]^3, o = (0, 0, 5), d = (0, 0, -1): enters z = 1 at t = 4, leaves z = -1 at 6.
    box = ((-1.0, -1.0, -1.0), (1.0, 1.0, 1.0))
    assert exact_slabs(*box, (0, 0, 5), (0, 0, -1)) == (4, 6, [2], [2])
    # In the plane x = 1 with d.x = 0: the closed slab puts no bound (where 0 * inf is NaN).
    assert exact_slabs(*box, (1, 0, 5), (0, 0, -1))[:2] == (4, 6)
    # Outside a slab with d's component 0: empty.
    enter, leave, _, _ = exact_slabs(*box, (2, 0, 5), (0, 0, -1))
    assert enter > leave


def test_the_exact_triangle_by_hand() -> None:
    # The triangle (0,0,0), (2,0,0), (0,2,0) met at (0.5, 0.25) from z = 3 straight down:
    # t = 3, b1 = 0.5 / 2, b2 = 0.25 / 2, b0 = 1 - b1 - b2.
    t, b0, b1, b2 = exact_triangle((0, 0, 0), (2, 0, 0), (0, 2, 0), (0.5, 0.25, 3), (0, 0, -1))
    assert (t, b0, b1, b2) == (3, Fraction(5, 8), Fraction(1, 4), Fraction(1, 8))
    assert exact_triangle((0, 0, 0), (2, 0, 0), (0, 2, 0), (0, 0, 1), (1, 0, 0)) is None


def test_the_brute_force_closest_hit_is_the_nearest_of_the_stack() -> None:
    # The stack is at z = 2.5, 2, 2.75, 2.25: from z = -5 upwards the closest is z = 2 (t = 7,
    # triangle 1), from z = 8 downwards z = 2.75 (t = 5.25, triangle 2).
    assert closest(STACK, (0, 0, -5), (0, 0, 1), 0, float("inf"))[:2] == (7, 1)
    assert closest(STACK, (0, 0, 8), (0, 0, -1), 0, float("inf"))[:2] == (Fraction(21, 4), 2)
    # Within (0, 6) nothing; the far cluster's closest from above is z = 10.75.
    assert closest(TWO_Z, (0, 0, -5), (0, 0, 1), 0, 6) is None
    assert closest(TWO_Z, (0, 0, 20), (0, 0, -1), 0, float("inf"))[:2] == (Fraction(37, 4), 6)


def test_the_overlap_scene_is_a_hierarchy_whose_first_box_holds_the_farther_hit() -> None:
    """The scene that catches "the first leaf with a hit is final" must have the ray enter the
    box of the farther hit first; the hierarchy is the solution's build(), so check it here."""
    scene = _core.Scene()
    vertices = [p for tri in OVERLAP for p in tri]
    faces = [[3 * i, 3 * i + 1, 3 * i + 2] for i in range(len(OVERLAP))]
    nodes = scene.add_mesh(
        np.array(vertices, dtype=float), np.array(faces, dtype=np.int32), None, "bvh", 0, 0
    )
    assert nodes >= 3  # a hierarchy (a root and its children), not one leaf of 8
    # The tilted triangle's box (z from 0 to 12) is entered at t = 5 by o = (0, 0, -5) along
    # +z, before the stack's (z from 2, t = 7), yet its hit (z = 11.2) is the farther.
    tilted = closest(OVERLAP[:1], (0, 0, -5), (0, 0, 1), 0, float("inf"))
    assert tilted is not None and tilted[0] == Fraction(81, 5)
    assert closest(OVERLAP, (0, 0, -5), (0, 0, 1), 0, float("inf"))[:2] == (7, 5)
