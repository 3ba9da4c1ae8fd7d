"""The five ray/sphere cases of the slide "Intersecting a Sphere", on a unit sphere at the origin.

Every number below is exact in binary floating point, so the expected t and points are exact
up to the rounding of the arithmetic itself (rel 1e-12 is ~5000 ulps of double: far above that
rounding, far below any wrong root).
"""

from __future__ import annotations

import pytest

import tracer
from tests.helpers import material, scene_dict, sphere
from tracer import _core

C, R = (0.0, 0.0, 0.0), 1.0


def case(origin, direction):
    return _core.intersect_sphere(C, R, origin, direction)


def test_none_the_line_misses():
    name, hit = case((0, 2, 5), (0, 0, -1))
    assert (name, hit) == ("none", None)


def test_none_the_sphere_is_behind_the_ray():
    name, hit = case((0, 0, 5), (0, 0, 1))
    assert (name, hit) == ("none", None)


def test_twice_the_nearer_root_is_the_hit():
    name, hit = case((0, 0, 5), (0, 0, -1))
    assert name == "twice"
    assert hit["t"] == pytest.approx(4.0, rel=1e-12)
    assert hit["point"] == pytest.approx((0, 0, 1), abs=1e-12)
    assert hit["normal"] == pytest.approx((0, 0, 1), abs=1e-12)


def test_once_from_inside_the_far_side_is_the_hit():
    name, hit = case((0, 0, 0.5), (0, 0, -1))
    assert name == "once_from_inside"
    assert hit["t"] == pytest.approx(1.5, rel=1e-12)
    assert hit["point"] == pytest.approx((0, 0, -1), abs=1e-12)
    assert hit["normal"] == pytest.approx((0, 0, -1), abs=1e-12)  # outward, turned later


def test_tangent_one_double_root():
    name, hit = case((-5, 1, 0), (1, 0, 0))
    assert name == "tangent"
    assert hit["t"] == pytest.approx(5.0, rel=1e-12)
    assert hit["point"] == pytest.approx((0, 1, 0), abs=1e-12)


def test_internal_the_root_at_the_start_is_not_a_hit():
    name, hit = case((1, 0, 0), (-1, 0, 0))
    assert name == "internal"
    assert hit["t"] == pytest.approx(2.0, rel=1e-12)
    assert hit["point"] == pytest.approx((-1, 0, 0), abs=1e-12)


def test_leaving_the_surface_outward_is_no_hit():
    name, hit = case((1, 0, 0), (1, 0, 0))
    assert (name, hit) == ("none", None)


def test_direction_need_not_be_unit():
    """t is in units of the direction given: twice as long a direction, half the t."""
    _, hit = case((0, 0, 5), (0, 0, -2))
    assert hit["t"] == pytest.approx(2.0, rel=1e-12)


def test_camera_inside_a_sphere_sees_its_inside_lit_by_a_light_inside():
    """'Once from inside' in a render: N is turned to face the ray, the light at the centre
    reaches the inner wall (N.L = 1), and the sphere's own wall does not shadow it."""
    data = scene_dict(
        camera={"eye": [0, 0, 0], "look_at": [0, 0, -1]},
        materials={"m": material(color=[0.5, 0.6, 0.7], ambient=0.1, diffuse=0.8)},
        lights=[{"type": "point", "position": [0.0, 0.0, 0.0]}],
        objects=[sphere([0, 0, 0], 2.0)],
    )
    got = tracer.render(tracer.load_scene(data), threads=1)[0, 0]
    assert [float(v) for v in got] == pytest.approx([c * 0.9 for c in (0.5, 0.6, 0.7)], rel=1e-6)


def test_mirror_sphere_seen_from_its_centre_is_the_internal_case_repeated():
    """Each reflected ray leaves the inner wall inward, back through the centre to the opposite
    wall: the internal case at every level. All levels see the same local colour C, so the chain
    sums to C (1 + a + ... + a^(n-1)) for max_depth n."""
    a, n, c = 0.5, 6, 0.3
    data = scene_dict(
        camera={"eye": [0, 0, 0], "look_at": [0, 0, -1]},
        render={"max_depth": n},
        materials={"m": material(color=[1, 1, 1], ambient=c, reflectivity=a)},
        objects=[sphere([0, 0, 0], 3.0)],
    )
    result = tracer.render_with_stats(tracer.load_scene(data), threads=1)
    want = c * (1 - a**n) / (1 - a)
    assert [float(v) for v in result.image[0, 0]] == pytest.approx([want] * 3, rel=1e-6)
    assert result.rays["secondary"] == n - 1
