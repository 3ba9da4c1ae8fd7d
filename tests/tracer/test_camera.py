"""Pixel-centre camera geometry: right-handed, vertical field of view, row 0 at the top."""

from __future__ import annotations

import math

import numpy as np
import pytest

import tracer
from tests.helpers import material, scene_dict, sphere
from tracer.render import to_core


def camera_scene(**camera):
    return to_core(tracer.load_scene(scene_dict(camera=camera)))


def test_primary_rays_go_through_pixel_centres():
    """An axis-aligned camera: the image plane at distance 1 is 2 tan(fov/2) high, W/H wide."""
    W, H, fov = 8, 4, 60.0
    core = camera_scene(eye=[1, 2, 3], look_at=[1, 2, 2], width=W, height=H, fov_y=fov)
    h = 2 * math.tan(math.radians(fov) / 2)
    w = h * W / H
    for i, j in [(0, 0), (7, 0), (0, 3), (7, 3), (3, 2)]:
        o, d = core.primary_ray(i + 0.5, j + 0.5)
        x = (i + 0.5) / W - 0.5
        y = 0.5 - (j + 0.5) / H
        want = np.array([x * w, y * h, -1.0])  # right = +x, up = +y, forward = -z
        assert o == pytest.approx((1, 2, 3), abs=0)
        assert d == pytest.approx(want / np.linalg.norm(want), abs=1e-15)


def test_right_is_forward_cross_up_for_a_general_camera():
    eye, at, up = np.array([3.0, -1.0, 2.0]), np.array([-1.0, 0.5, 0.25]), np.array([0.1, 1.0, 0.2])
    core = camera_scene(eye=list(eye), look_at=list(at), up=list(up), width=2, height=1, fov_y=90.0)
    f = (at - eye) / np.linalg.norm(at - eye)
    right = np.cross(f, up)
    right /= np.linalg.norm(right)
    _, d_right = core.primary_ray(1.5, 0.5)  # the right-hand pixel
    _, d_left = core.primary_ray(0.5, 0.5)
    assert np.dot(d_right, right) > 0.4 > -0.4 > np.dot(d_left, right)
    assert np.dot(np.array(d_right) + np.array(d_left), f) > 0


def test_a_sphere_up_and_to_the_right_lands_in_the_top_right():
    data = scene_dict(
        camera={"eye": [0, 0, 10], "look_at": [0, 0, 0], "width": 40, "height": 20, "fov_y": 40.0},
        materials={"m": material(ambient=1.0)},
        objects=[sphere([1.5, 1.0, 0.0], 0.5)],
    )
    image = tracer.render(tracer.load_scene(data), threads=1)[..., 0]
    rows, cols = np.nonzero(image > 0.5)
    assert rows.size > 0
    assert rows.max() < 10 and cols.min() >= 20  # upper half, right half

    # And where exactly: the sphere's centre projects to x = 1.5 / (10 tan 20deg) of half-height.
    half_h = 10 * math.tan(math.radians(20))
    col = 20 + 1.5 / half_h * 10  # pixels: half width = W/2 = 20 px covers half_h * 2 units
    row = 10 - 1.0 / half_h * 10
    # Pixel index i covers image x from i to i + 1 and is sampled at its centre i + 0.5. The
    # projected disc is slightly elliptical off-axis; its centroid stays within 0.3 px here.
    assert cols.mean() + 0.5 == pytest.approx(col, abs=0.3)
    assert rows.mean() + 0.5 == pytest.approx(row, abs=0.3)
