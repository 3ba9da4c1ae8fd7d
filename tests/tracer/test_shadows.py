"""Shadow rays: a light is counted only when nothing lies strictly between the hit and it.

Geometry: a camera at (0, 10, 0) looks straight down at the floor y = 0; its one ray hits the
origin, N = (0, 1, 0). Lights sit at 45 degrees: from the origin towards (4, 4, 0) or (-4, 4, 0),
so N.L = 1/sqrt(2). A small sphere at (1, 1, 0) lies on the first light's shadow ray and clear
of the camera ray (x = 1 - 0.3 > 0).
"""

from __future__ import annotations

import math

import pytest

import tracer
from tests.helpers import material, plane, scene_dict, sphere

CAM = {"eye": [0, 10, 0], "look_at": [0, 0, 0], "up": [0, 0, -1]}
FLOOR = material(color=[1.0, 1.0, 1.0], ambient=0.1, diffuse=0.8)
RIGHT = {"type": "point", "position": [4.0, 4.0, 0.0], "color": [1.0, 0.0, 0.0]}
LEFT = {"type": "point", "position": [-4.0, 4.0, 0.0], "color": [0.0, 0.0, 1.0]}
LIT = 0.8 / math.sqrt(2)


def floor_pixel(lights, objects, **render):
    data = scene_dict(
        camera=CAM,
        render=render,
        materials={"floor": FLOOR, "m": material()},
        lights=lights,
        objects=[plane([0, 0, 0], [0, 1, 0], "floor"), *objects],
    )
    result = tracer.render_with_stats(tracer.load_scene(data), threads=1)
    return [float(v) for v in result.image[0, 0]], result.rays


def test_unblocked_lights_both_count():
    got, rays = floor_pixel([RIGHT, LEFT], [])
    assert got == pytest.approx([0.1 + LIT, 0.1, 0.1 + LIT], rel=1e-6)
    assert rays["shadow"] == 2


def test_blocker_shadows_one_light_only():
    got, _ = floor_pixel([RIGHT, LEFT], [sphere([1, 1, 0], 0.3)])
    assert got == pytest.approx([0.1, 0.1, 0.1 + LIT], rel=1e-6)


def test_object_beyond_the_light_does_not_shadow():
    near_light = dict(RIGHT, position=[1.0, 1.0, 0.0])
    got, _ = floor_pixel([near_light], [sphere([2, 2, 0], 0.3)])
    assert got == pytest.approx([0.1 + LIT, 0.1, 0.1], rel=1e-6)


def test_directional_light_is_blocked_anywhere_along_its_direction():
    sun = {"type": "directional", "direction": [-1.0, -1.0, 0.0], "color": [0.0, 1.0, 0.0]}
    far_blocker = sphere([1000, 1000, 0], 5.0)
    got, _ = floor_pixel([sun], [far_blocker])
    assert got == pytest.approx([0.1, 0.1, 0.1], rel=1e-6)
    got, _ = floor_pixel([sun], [])
    assert got == pytest.approx([0.1, 0.1 + LIT, 0.1], rel=1e-6)


def test_no_lights_no_shadow_rays():
    """A feature the scene does not use costs nothing."""
    _, rays = floor_pixel([], [sphere([1, 1, 0], 0.3)])
    assert (rays["primary"], rays["secondary"], rays["shadow"]) == (1, 0, 0)
    assert rays["primitive_tests"] == 2  # the one primary ray against the floor and the sphere


def test_no_light_terms_no_shadow_rays():
    data = scene_dict(
        camera=CAM,
        materials={"m": material(ambient=0.5, diffuse=0.0, specular=0.0)},
        lights=[RIGHT, LEFT],
        objects=[plane([0, 0, 0], [0, 1, 0])],
    )
    result = tracer.render_with_stats(tracer.load_scene(data), threads=1)
    assert result.rays["shadow"] == 0
    assert float(result.image[0, 0, 0]) == pytest.approx(0.5, rel=1e-6)


def test_the_surface_does_not_shadow_itself_at_grazing_light():
    """A light almost in the floor's plane (N.L ~ 1e-6): the shadow ray leaves the floor at a
    grazing angle, where a fixed-epsilon offset classically fails; it must still be lit."""
    grazing = {"type": "point", "position": [1.0e6, 1.0, 0.0], "color": [1.0, 1.0, 1.0]}
    got, _ = floor_pixel([grazing], [])
    n_dot_l = 1.0 / math.hypot(1.0e6, 1.0)
    assert got[0] == pytest.approx(0.1 + 0.8 * n_dot_l, rel=1e-6)
