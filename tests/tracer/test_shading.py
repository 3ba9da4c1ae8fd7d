"""Hand-computed pixel values for the classic model's terms on a single sphere.

Geometry: a unit sphere at the origin seen from (0, 0, 5) in a 1x1 image: the one primary ray
runs along -z through the pixel centre and hits (0, 0, 1) where N = (0, 0, 1); the mirror
direction of the incoming ray is R = (0, 0, 1). A point light at (3, 0, 5) is seen from the hit
in the direction L = (3, 0, 4)/5, so N.L = 0.8 and R.L = 0.8.

Tolerance: the core computes in double and returns float32, so each value carries at most one
float32 rounding, a relative error of 2^-24 ~ 6e-8; rel=1e-6 leaves room for a few double
roundings before it and could still catch any wrong term (the smallest term tested is 1e-3).
"""

from __future__ import annotations

import math

import pytest

import tracer
from tests.helpers import material, scene_dict, sphere

REL = 1e-6
LIGHT = {"type": "point", "position": [3.0, 0.0, 5.0], "color": [1.0, 0.5, 0.25]}


def pixel(**parts):
    image = tracer.render(tracer.load_scene(scene_dict(**parts)), threads=1)
    assert image.shape == (1, 1, 3)
    return [float(v) for v in image[0, 0]]


def test_ambient_is_color_times_ambient_times_ambient_light():
    got = pixel(
        render={"ambient_light": [1.0, 0.5, 2.0]},
        materials={"m": material(color=[0.5, 0.25, 1.0], ambient=0.2)},
        lights=[LIGHT],
        objects=[sphere([0, 0, 0], 1.0)],
    )
    assert got == pytest.approx([0.5 * 0.2 * 1.0, 0.25 * 0.2 * 0.5, 1.0 * 0.2 * 2.0], rel=REL)


def test_lambert_is_diffuse_times_color_times_light_times_n_dot_l():
    got = pixel(
        materials={"m": material(color=[0.5, 0.25, 1.0], diffuse=0.7)},
        lights=[LIGHT],
        objects=[sphere([0, 0, 0], 1.0)],
    )
    assert got == pytest.approx(
        [0.7 * c * lc * 0.8 for c, lc in zip([0.5, 0.25, 1.0], LIGHT["color"], strict=True)],
        rel=REL,
    )


def test_phong_is_specular_times_light_times_r_dot_l_to_the_shininess_untinted():
    got = pixel(
        materials={"m": material(color=[0.1, 0.9, 0.3], specular=0.5, shininess=10.0)},
        lights=[LIGHT],
        objects=[sphere([0, 0, 0], 1.0)],
    )
    assert got == pytest.approx([0.5 * lc * 0.8**10 for lc in LIGHT["color"]], rel=REL)


def test_all_terms_add_and_two_lights_add():
    second = {"type": "directional", "direction": [0.0, 0.0, -2.0], "color": [0.3, 0.3, 0.3]}
    m = material(color=[0.5, 0.25, 1.0], ambient=0.1, diffuse=0.7, specular=0.5, shininess=10.0)
    got = pixel(materials={"m": m}, lights=[LIGHT, second], objects=[sphere([0, 0, 0], 1.0)])
    # The directional light travels along -z: L = (0, 0, 1), N.L = 1, R.L = 1.
    want = [
        c * 0.1 + 0.7 * c * lc * 0.8 + 0.5 * lc * 0.8**10 + 0.7 * c * 0.3 + 0.5 * 0.3
        for c, lc in zip([0.5, 0.25, 1.0], LIGHT["color"], strict=True)
    ]
    assert got == pytest.approx(want, rel=REL)


def test_light_behind_the_surface_adds_nothing():
    behind = {"type": "point", "position": [0.0, 0.0, -10.0], "color": [1.0, 1.0, 1.0]}
    got = pixel(
        materials={"m": material(ambient=0.25, diffuse=0.7, specular=0.5)},
        lights=[behind],
        objects=[sphere([0, 0, 0], 1.0)],
    )
    assert got == pytest.approx([0.25] * 3, rel=REL)


def test_miss_returns_background():
    got = pixel(render={"background": [0.1, 0.2, 0.3]}, objects=[sphere([0, 5, 0], 1.0)])
    assert got == pytest.approx([0.1, 0.2, 0.3], rel=REL)


def test_no_distance_falloff():
    """The classic model's point light does not fall off: moving it away along L changes nothing."""
    far = dict(LIGHT, position=[3.0e3, 0.0, 1.0 + 4.0e3])
    near = pixel(
        materials={"m": material(diffuse=0.7)}, lights=[LIGHT], objects=[sphere([0, 0, 0], 1.0)]
    )
    got = pixel(
        materials={"m": material(diffuse=0.7)}, lights=[far], objects=[sphere([0, 0, 0], 1.0)]
    )
    assert got == pytest.approx(near, rel=REL)


@pytest.mark.parametrize("packets", [True, False], ids=["packets", "one-ray"])
def test_phong_uses_the_mirror_direction_off_axis(packets):
    """Seen head on, R = N and R.L = N.L: the tests above cannot tell them apart. Here the eye
    looks down at 45 degrees. The floor z = 0 (N = (0, 0, 1)), the eye at (0, -3, 3) looking at
    the origin: the one primary ray d = (0, 1, -1)/sqrt(2) hits the origin, its mirror
    direction is R = d - 2 (d.N) N = (0, 1, 1)/sqrt(2). The light at (0, 4, 3) is seen along
    L = (0, 0.8, 0.6): N.L = 0.6, R.L = 1.4/sqrt(2) = 0.98995. With n = 10 the highlight is
    0.5 * 0.98995^10 = 0.452 of the light; N in place of R would give 0.5 * 0.6^10 = 0.003."""
    data = scene_dict(
        camera={"eye": [0.0, -3.0, 3.0], "look_at": [0.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0]},
        materials={"m": material(color=[0.1, 0.9, 0.3], specular=0.5, shininess=10.0)},
        lights=[{"type": "point", "position": [0.0, 4.0, 3.0], "color": [1.0, 0.5, 0.25]}],
        objects=[{"type": "plane", "point": [0, 0, 0], "normal": [0, 0, 1], "material": "m"}],
    )
    result = tracer.render_with_stats(tracer.load_scene(data), threads=1, packets=packets)
    r_dot_l = 1.4 / math.sqrt(2.0)
    want = [0.5 * lc * r_dot_l**10 for lc in (1.0, 0.5, 0.25)]
    assert [float(v) for v in result.image[0, 0]] == pytest.approx(want, rel=REL)
    assert want[2] / 30 > 0.5 * 0.6**10  # the value N.L would give is far from it
