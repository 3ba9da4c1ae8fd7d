"""L08's scene checks (lessons/scene_checks.py): an axis-aligned box seen from a corner (both
signs of the direction's components) and with rays in the planes of two of its faces (the
slab test's NaN), two boxes and one behind the eye, a room seen from inside (the nearest hit in
range), two triangles of opposite windings (both sides), a long thin triangle with a second
behind the eye (the generic triangle), and a large tilted triangle (its unit normal).

The analytic values are computed here in double precision from the scene's numbers (the slab
test and the plane of a triangle, written out below), never from the tracer."""

import math

from lessons.probe import HIDDEN, Vec
from lessons.scene_checks import Analytic, SceneCheck, cross, sub, unit


def box_entry(o: Vec, d: Vec, lo: Vec, hi: Vec) -> tuple[float, Vec]:
    """The slab test for a ray from outside (d without zero components): the entry t and the
    outward normal of the face it enters."""
    enter, axis, sign = -math.inf, -1, 0.0
    for k in range(3):
        t0, t1 = (lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]
        near = min(t0, t1)
        if near > enter:
            enter, axis, sign = near, k, (-1.0 if d[k] > 0 else 1.0)
    n = [0.0, 0.0, 0.0]
    n[axis] = sign
    return enter, (n[0], n[1], n[2])


# box_corner: the centre ray, eye to look_at, enters the red box through its front face.
CORNER_EYE: Vec = (-2.2, 2.0, 3.0)
CORNER_D = unit(sub((0.0, 0.2, 0.0), CORNER_EYE))
CORNER_T, CORNER_N = box_entry(CORNER_EYE, CORNER_D, (-0.6, 0.0, -0.5), (0.7, 0.9, 0.6))

# triangle_normal: the centre ray (0, 0, 4) - t z meets the triangle's plane n.(p - p0) = 0.
P0: Vec = (-3.0, -2.0, -1.0)
TRI_NG = cross(sub((3.0, -2.0, 0.5), P0), sub((0.0, 3.0, -0.5), P0))  # (-7.5, 1.5, 30)
TRI_N = unit(TRI_NG)
TRI_T = 4.0 - P0[2] - (TRI_NG[0] * P0[0] + TRI_NG[1] * P0[1]) / TRI_NG[2]

# float32 output: half an ulp of a value below 8 is 4.8e-7, of a unit normal's components
# 6e-8; the double arithmetic's roundings ~1e-15. 2e-6 holds both with room; the normal left
# 31 long (the mistake this catches) is off by 30.
FLOAT32 = 2e-6

SCENES = [
    SceneCheck(
        "L08",
        "box_corner",
        "the axis-aligned box (slab test)",
        "a box on a floor seen from above, the left and the front",
        analytic=(
            Analytic(
                40,
                30,
                "depth",
                (CORNER_T,),
                FLOAT32,
                "the centre ray's entry: the largest of the three slabs' near t",
            ),
            Analytic(
                40,
                30,
                "normal",
                CORNER_N,
                FLOAT32,
                "the outward normal of that slab's face (the front face, +z)",
            ),
        ),
        hint="each slab's two t, (min - o) / d and (max - o) / d, swapped where d's component "
        "is negative; the entry is the largest near t, the exit the smallest far t",
    ),
    SceneCheck(
        "L08",
        "box_edge_on",
        "the axis-aligned box (slab test)",
        "a box seen with the eye in the planes of its top and left faces",
        visibility=HIDDEN,
        # POV-Ray only: its box is the slab test (analytic), which counts a ray in the plane of
        # a face as meeting the face's edge, as the lecture's does; Mitsuba's box is twelve
        # float32 triangles, whose watertight test misses the middle row and column (64 of
        # 4941 pixels, measured with rtlab lesson grade tracer/cpp --lesson L08): a tie that
        # rounding decides. The aov and the ray counts are Mitsuba's hits: not compared here.
        references=("povray",),
        aov=False,
        rays=False,
        hint="a ray in the plane of a face makes 0 x infinity = NaN in that slab: compare so "
        "that a NaN never replaces the entry or the exit",
    ),
    SceneCheck(
        "L08",
        "two_boxes",
        "the box's nearest hit in range",
        "a red box in front of a blue one, and a third box behind the eye",
        hint="the hit is the entry t_enter if it is in range; a box behind the eye (both t "
        "negative) is not hit",
    ),
    SceneCheck(
        "L08",
        "inside_box",
        "the box's nearest hit in range",
        "a room (a box) seen and lit from inside, a block on its floor",
        visibility=HIDDEN,
        hint="from inside a box t_enter < 0 < t_leave: the hit is where the ray leaves",
    ),
    SceneCheck(
        "L08",
        "triangle_back",
        "the triangle seen from both sides",
        "two triangles of opposite windings, both lit from the eye's side",
        hint="a triangle has no outside: accept the hit when the three edge functions have the "
        "same sign, whichever it is",
    ),
    SceneCheck(
        "L08",
        "triangle_edges",
        "the generic triangle",
        "a long thin triangle across the view, and a second triangle behind the eye",
        visibility=HIDDEN,
        hint="inside means b0, b1, b2 >= 0 (b0 = 1 - b1 - b2: the third edge), and the t of "
        "the hit must lie in the ray's range",
    ),
    SceneCheck(
        "L08",
        "triangle_normal",
        "the triangle's point and normal",
        "a large tilted triangle filling the view (the aov's normal)",
        visibility=HIDDEN,
        analytic=(
            Analytic(
                40,
                30,
                "depth",
                (TRI_T,),
                FLOAT32,
                "the centre ray meets the plane n.(p - p0) = 0, n = (-7.5, 1.5, 30)",
            ),
            Analytic(40, 30, "normal", TRI_N, FLOAT32, "(p1 - p0) x (p2 - p0) made unit length"),
        ),
        hint="the normal is the unit cross product of two edges; the point is o + t d",
    ),
]
