"""The reflection-coefficient chain (slide "Specular Reflected Light") in closed form.

Scene: two parallel mirror planes, z = -1 (material A) and z = +1 (material B), and a camera
between them looking along -z through the pixel centre. The ray bounces A, B, A, B, ... The
materials have only an ambient term (no lights), so each level's local colour C_k is exactly
color * ambient, and the slides' sum  C1 + a1 C2 + a1 a2 C3 + ...  can be written down:
level k (1-based) adds  prod_{i<k} a_i * C_k  while k <= max_depth and the running product is
not below min_coefficient.
"""

from __future__ import annotations

import pytest

import tracer
from tests.helpers import material, plane, scene_dict, sphere

A = {"color": [1.0, 0.5, 0.25], "ambient": 0.4, "reflectivity": 0.5}
B = {"color": [0.2, 1.0, 0.6], "ambient": 0.3, "reflectivity": 0.8}


def closed_form(max_depth: int, min_coefficient: float) -> list[float]:
    color = [0.0, 0.0, 0.0]
    coef = 1.0
    for level in range(1, max_depth + 1):
        if coef < min_coefficient:
            break
        m = A if level % 2 == 1 else B
        color = [c + coef * m["ambient"] * mc for c, mc in zip(color, m["color"], strict=True)]
        coef *= m["reflectivity"]
    return color


def render_mirrors(max_depth: int, min_coefficient: float):
    data = scene_dict(
        camera={"eye": [0, 0, 0], "look_at": [0, 0, -1]},
        render={"max_depth": max_depth, "min_coefficient": min_coefficient},
        materials={"A": material(**A), "B": material(**B)},
        objects=[plane([0, 0, -1], [0, 0, 1], "A"), plane([0, 0, 1], [0, 0, -1], "B")],
    )
    return tracer.render_with_stats(tracer.load_scene(data), threads=1)


@pytest.mark.parametrize("max_depth", [1, 2, 3, 5, 8, 20])
def test_chain_matches_closed_form_up_to_max_depth(max_depth):
    result = render_mirrors(max_depth, 0.0)
    # rel 1e-6: float32 output of a double sum of at most 20 positive terms (see test_shading).
    assert [float(v) for v in result.image[0, 0]] == pytest.approx(
        closed_form(max_depth, 0.0), rel=1e-6
    )
    assert result.rays["secondary"] == max_depth - 1  # the primary ray is level 1


@pytest.mark.parametrize("min_coefficient", [0.5, 0.4, 0.2, 0.16, 0.1, 0.01])
def test_min_coefficient_cuts_the_chain(min_coefficient):
    """Coefficients run 1, 0.5, 0.4, 0.2, 0.16, 0.08, ...: 0.4 and 0.16 sit exactly on a level's
    coefficient, which counts (only a coefficient *below* the bound is cut)."""
    result = render_mirrors(30, min_coefficient)
    want = closed_form(30, min_coefficient)
    assert [float(v) for v in result.image[0, 0]] == pytest.approx(want, rel=1e-6)


def test_cut_chain_differs_from_uncut():
    """The closed form is not trivially met: cutting at 0.2 must change the pixel."""
    assert closed_form(30, 0.2) != pytest.approx(closed_form(30, 0.0), rel=1e-3)
    cut = render_mirrors(30, 0.2).image[0, 0]
    full = render_mirrors(30, 0.0).image[0, 0]
    assert abs(float(cut[0]) - float(full[0])) > 1e-3


def test_reflection_reaching_the_background():
    """A mirror sphere seen head-on reflects the ray straight back past the camera into the
    background: pixel = C1 + a * background."""
    data = scene_dict(
        render={"background": [0.2, 0.4, 0.8]},
        materials={"m": material(color=[1.0, 0.0, 0.0], ambient=0.5, reflectivity=0.25)},
        objects=[sphere([0, 0, 0], 1.0)],
    )
    got = tracer.render(tracer.load_scene(data), threads=1)[0, 0]
    assert [float(v) for v in got] == pytest.approx(
        [0.5 + 0.25 * 0.2, 0.25 * 0.4, 0.25 * 0.8], rel=1e-6
    )


def test_past_max_depth_is_black_not_background():
    """With max_depth 1 the reflected ray is never traced: no background through the mirror."""
    data = scene_dict(
        render={"background": [0.2, 0.4, 0.8], "max_depth": 1},
        materials={"m": material(color=[1.0, 0.0, 0.0], ambient=0.5, reflectivity=0.25)},
        objects=[sphere([0, 0, 0], 1.0)],
    )
    got = tracer.render(tracer.load_scene(data), threads=1)[0, 0]
    assert [float(v) for v in got] == pytest.approx([0.5, 0.0, 0.0], abs=1e-7)
