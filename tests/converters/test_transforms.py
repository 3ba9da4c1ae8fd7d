"""Object transforms (scale, then rotate, then translate) checked against something that does not
share them. The converters receive each object already placed in world space by the scene code
(tracer.scene.to_world), so rtlab, POV-Ray and Mitsuba agree with each other even when that
placement is wrong: a rotation turned the wrong way changes 531 of 19,200 pixels of
boxes_triangles and no comparison notices. Two independent checks:

- closed forms: the aov integrator's depth and normal along one ray, worked out by hand below;
- POV-Ray's own ``scale``, ``rotate`` and ``translate`` statements, written by hand on the
  untransformed objects, rendered by POV-Ray and compared with rtlab's render of the scene
  with the transform.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import tracer
from converters.povray import to_povray
from reference.metrics import FLOAT32_SLACK, agrees
from reference.povray import run_povray
from tests.helpers import material, scene_dict

# Depth is a double-precision distance returned as float32 (one rounding, 2^-24 relative);
# normals are unit vectors in float32. 1e-6 holds both; the smallest difference any wrong
# transform below makes is 0.03 in depth or 0.07 in a normal component.
REL = ABS = 1e-6
COS30, SIN30 = math.cos(math.radians(30)), 0.5


def cube(transform, lo=(-0.5, -0.5, -0.5), hi=(0.5, 0.5, 0.5), mat="m"):
    return dict(type="box", min=list(lo), max=list(hi), material=mat, transform=transform)


def cylinder(top, radius, transform, mat="m"):
    base = [0.0, 0.0, 0.0]
    return dict(type="cylinder", base=base, top=top, radius=radius, capped=True, material=mat,
                transform=transform)  # fmt: skip


def torus(major, minor, transform, mat="m"):
    return dict(type="torus", center=[0.0, 0.0, 0.0], axis=[0.0, 1.0, 0.0], major_radius=major,
                minor_radius=minor, material=mat, transform=transform)  # fmt: skip


def aov_at(obj, eye, look_at):
    """depth, object id and normal of the one pixel of a 1x1 aov image, looking along -z."""
    data = scene_dict(
        camera={"eye": eye, "look_at": look_at},
        render={"integrator": "aov"},
        objects=[obj],
    )
    px = tracer.render(tracer.load_scene(data), threads=1)[0, 0]
    return float(px[0]), int(px[1]), [float(v) for v in px[2:5]]


def y_rotation(degrees):
    return {"axis": [0, 1, 0], "degrees": degrees}


# Each case: the object, the eye (the ray runs along -z from it), the depth and the normal by
# hand, or None for a miss. What a wrong transform would give is noted beside each.
CASES = {
    # The unit cube turned 30 degrees about +y, right-handed (counter-clockwise seen from +y):
    # its +z face turns towards +x, normal (sin 30, 0, cos 30) (turned the wrong way: -sin 30).
    # The face's plane n.p = 0.5 meets the ray x = y = 0 at z = 0.5 / cos 30.
    "rotate y": (
        cube({"rotate": y_rotation(30.0)}),
        [0.0, 0.0, 5.0],
        (5.0 - 0.5 / COS30, [SIN30, 0.0, COS30]),
    ),
    # +90 degrees about +z takes the cylinder's axis +y to -x: it lies along x in [-1, 0] and
    # the ray at x = -0.5 meets its side at z = r = 0.5 (turned the wrong way, it lies along
    # [0, 1] and the ray misses).
    "rotate z, cylinder": (
        cylinder([0, 1, 0], 0.5, {"rotate": {"axis": [0, 0, 1], "degrees": 90.0}}),
        [-0.5, 0.0, 5.0],
        (4.5, [0.0, 0.0, 1.0]),
    ),
    # 120 degrees about (1, 1, 1) permutes the axes x -> y -> z -> x: a bar along +x becomes a
    # bar along +y, its +y face (z was y) the front, at z = 0.1 (the wrong way, x -> z: the bar
    # runs along +z, away from the ray at y = 1).
    "rotate about (1, 1, 1)": (
        cube({"rotate": {"axis": [1, 1, 1], "degrees": 120.0}}, (0, -0.1, -0.1), (2, 0.1, 0.1)),
        [0.0, 1.0, 5.0],
        (4.9, [0.0, 0.0, 1.0]),
    ),
    # Translation alone: the cube's front face moves to z = 0.5 + 0.4.
    "translate": (
        cube({"translate": [0.3, -0.2, 0.4]}),
        [0.3, -0.2, 5.0],
        (5.0 - 0.9, [0.0, 0.0, 1.0]),
    ),
    # Scale alone, about the origin: the front face at z = 0.5 * 3; the ray at x = 0.6 is
    # inside the face only if x was scaled by 1.5 (to 0.75), not left at 0.5.
    "scale": (
        cube({"scale": [1.5, 1.0, 3.0]}),
        [0.6, 0.0, 5.0],
        (5.0 - 1.5, [0.0, 0.0, 1.0]),
    ),
    # All three, in their order T R S: the cube stretched to z in [-1, 1], turned 30 degrees
    # about +y, moved by t = (-0.5, 0, 0). Its +z face: normal n = (sin 30, 0, cos 30), plane
    # n.(p - t) = 1, so on the ray x = y = 0: z = (1 + sin 30 * tx) / cos 30 = cos 30 (the face's
    # centre, so well inside it). Other orders give other answers: translate before rotate
    # (R T S) z = 1 / cos 30 = 1.155, depth 3.845; scale after rotate (T S R) tilts the normal
    # to (0.756, 0, 0.655).
    "scale, rotate, translate in that order": (
        cube({"scale": [1, 1, 2], "rotate": y_rotation(30.0), "translate": [-0.5, 0, 0]}),
        [0.0, 0.0, 5.0],
        (5.0 - COS30, [SIN30, 0.0, COS30]),
    ),
}


@pytest.mark.parametrize("case", CASES, ids=list(CASES))
def test_transform_in_closed_form(case):
    obj, eye, (depth, normal) = CASES[case]
    got_depth, got_object, got_normal = aov_at(obj, eye, [eye[0], eye[1], 0.0])
    assert got_object == 0, f"{case}: the ray missed"
    assert got_depth == pytest.approx(depth, rel=REL), case
    assert got_normal == pytest.approx(normal, abs=ABS), case


# --------------------------------------------------------------------------- POV-Ray by hand
#
# POV-Ray is left-handed and rotates by the left-hand rule; tracer.scene is right-handed and
# rotates by the right-hand rule (Rodrigues' formula). Both describe the same matrix on the same
# numbers: POV-Ray's ``rotate y*a`` takes (x, y, z) to (x cos a + z sin a, y, -x sin a + z cos a)
# (its source, Compute_Rotation_Transform, with row vectors), and so does Rodrigues' rotation by
# a about +y: the handedness of the rule matches the handedness of the axes. The converter hands
# POV-Ray our coordinates unchanged (only the camera's ``right -x`` mirrors the picture), so the
# scene's rotate {axis = y, degrees = a} is POV-Ray's ``rotate y*a``, with the same sign; an
# arbitrary axis is transforms.inc's Axis_Rotate_Trans(axis, a), built on vaxis_rotate, the
# same rule. POV-Ray applies the statements in the order written: scale, rotate, translate.

BLOCK = {"scale": [0.3, 0.61, 0.3], "rotate": y_rotation(18.25), "translate": [-0.33, -0.4, -0.28]}
TILTED = {"scale": [1.0, 0.7, 1.3], "rotate": {"axis": [1.0, 0.0, 1.0], "degrees": 40.0},
          "translate": [0.45, -0.35, 0.1]}  # fmt: skip
RING = {"scale": [1.2, 1.0, 0.8], "rotate": {"axis": [0.0, 0.0, 1.0], "degrees": -60.0},
        "translate": [-0.55, 0.3, -0.4]}  # fmt: skip
SLAB = {"rotate": {"axis": [1.0, 0.0, 0.0], "degrees": -35.0}, "translate": [0.6, 0.35, -0.5]}


def transformed_scene(width=96, height=72):
    white = material(color=[0.8, 0.8, 0.75], ambient=0.1, diffuse=0.7, specular=0.2,
                     shininess=20.0)  # fmt: skip
    red = material(color=[0.8, 0.15, 0.1], ambient=0.1, diffuse=0.7)
    return scene_dict(
        camera={"eye": [0.0, 0.6, 3.2], "look_at": [0.0, -0.1, 0.0], "fov_y": 45.0}
        | {"width": width, "height": height},
        render={"background": [0.1, 0.1, 0.15], "ambient_light": [1.0, 1.0, 1.0]},
        materials={"white": white, "red": red},
        lights=[{"type": "point", "position": [1.0, 2.0, 2.0], "color": [0.9, 0.9, 0.9]}],
        objects=[
            cube(BLOCK, mat="white"),
            cylinder([0, 0.5, 0], 0.15, TILTED, "red"),
            torus(0.25, 0.07, RING, "red"),
            cube(SLAB, (-0.3, -0.05, -0.2), (0.3, 0.05, 0.2), "white"),
            {"type": "plane", "point": [0, -0.7, 0], "normal": [0, 1, 0], "material": "white"},
        ],
    )


def _v(v):
    return "<" + ", ".join(repr(float(x)) for x in v) + ">"


def povray_statements(t):
    """The scene's transform as POV-Ray's own statements, in the scene's order."""
    out = []
    if "scale" in t:
        out.append(f"scale {_v(t['scale'])}")
    if "rotate" in t:
        axis, degrees = t["rotate"]["axis"], float(t["rotate"]["degrees"])
        if axis == [0, 1, 0]:
            out.append(f"rotate y*{degrees!r}")  # the same sign: see the comment above
        else:
            out.append(f"transform {{ Axis_Rotate_Trans({_v(axis)}, {degrees!r}) }}")
    if "translate" in t:
        out.append(f"translate {_v(t['translate'])}")
    return " ".join(out)


def handwritten_povray(scene):
    """The converter's camera, lights, materials and floor, with the four transformed objects
    replaced by POV-Ray's own untransformed primitives and transform statements."""
    sdl = to_povray(scene)
    tex = dict(re.findall(r"#declare (M\d+_(\w+)) = texture", sdl))
    tex = {name: ident for ident, name in tex.items()}
    lines = [ln for ln in sdl.splitlines() if not re.search(r"// objects\[[0-3]\]$", ln)]
    assert len(lines) == len(sdl.splitlines()) - 4, "the transformed objects were not removed"
    t = {k: f"texture {{ {v} }}" for k, v in tex.items()}
    lines += [
        '#include "transforms.inc"',
        f"box {{ <-0.5, -0.5, -0.5>, <0.5, 0.5, 0.5> {t['white']} {povray_statements(BLOCK)} }}",
        f"cylinder {{ <0, 0, 0>, <0, 0.5, 0>, 0.15 {t['red']} {povray_statements(TILTED)} }}",
        # POV-Ray's torus lies around its y axis, centred at the origin: ours, axis y.
        f"torus {{ 0.25, 0.07 sturm {t['red']} {povray_statements(RING)} }}",
        f"box {{ <-0.3, -0.05, -0.2>, <0.3, 0.05, 0.2> {t['white']} {povray_statements(SLAB)} }}",
    ]
    return "\n".join(lines) + "\n"


def test_transforms_match_povrays_own():
    scene = tracer.load_scene(transformed_scene())
    ours = tracer.render(scene, threads=2)
    sdl = handwritten_povray(scene)
    assert "matrix" not in sdl  # nothing placed by our code
    pov = run_povray(scene, threads=2, sdl=sdl)
    ok, text = agrees(pov.image, ours, pov.error_bound + FLOAT32_SLACK)
    assert ok, f"rtlab's transforms vs POV-Ray's scale/rotate/translate: {text}"
    # Not vacuous: each transformed object covers pixels of its own.
    ids = tracer.render(scene.with_overrides(integrator="aov"), threads=2)[..., 1]
    assert all(np.sum(ids == k) > 50 for k in range(4)), [np.sum(ids == k) for k in range(4)]
