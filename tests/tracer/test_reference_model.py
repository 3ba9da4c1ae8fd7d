"""The core against an independent plain-Python implementation of the classic model
(tests/classic_reference.py), pixel by pixel, on whole small images."""

from __future__ import annotations

import numpy as np
import pytest

import tracer
from tests import classic_reference
from tests.helpers import material, plane, scene_dict, sphere
from tracer.cli import demo_scene_path

# Tolerance: the core returns float32 (relative rounding 6e-8 on values up to ~2) and both
# compute in double; the reference's textbook quadratic loses at most ~1e-12 relative on these
# well-conditioned scenes. 1e-6 absolute is ten float32 ulps of the brightest pixels.
ATOL = 1e-6


def compare(scene):
    got = tracer.render(scene, threads=2)
    want = classic_reference.render(scene)
    err = np.abs(got - want)
    assert err.max() <= ATOL, (
        f"max error {err.max():g} at {np.unravel_index(err.argmax(), err.shape)}"
    )
    return got


def test_demo_scene_matches_the_plain_implementation():
    scene = tracer.load_scene(demo_scene_path()).with_overrides(width=48, height=36)
    image = compare(scene)
    assert image.std() > 0.05  # a real picture, not a blank


def test_directional_light_and_chain_with_cutoff():
    data = scene_dict(
        camera={
            "eye": [1.0, 2.0, 6.0],
            "look_at": [0, 0.5, 0],
            "width": 40,
            "height": 30,
            "fov_y": 50.0,
        },
        render={
            "max_depth": 7,
            "min_coefficient": 0.05,
            "background": [0.1, 0.2, 0.3],
            "ambient_light": [0.5, 0.6, 0.7],
        },
        materials={
            "mirror": material(
                color=[0.9, 0.9, 0.9],
                ambient=0.05,
                diffuse=0.2,
                specular=0.9,
                shininess=80.0,
                reflectivity=0.9,
            ),
            "matte": material(color=[0.8, 0.3, 0.2], ambient=0.2, diffuse=0.8),
        },
        lights=[
            {"type": "directional", "direction": [-0.3, -1.0, -0.5], "color": [0.9, 0.8, 0.7]},
            {"type": "point", "position": [-2.0, 3.0, 2.0], "color": [0.4, 0.4, 0.6]},
        ],
        objects=[
            sphere([0, 1, 0], 1.0, "mirror"),
            sphere([-1.6, 0.5, 0.8], 0.5, "matte"),
            plane([0, 0, 0], [0, 1, 0], "matte"),
            plane([0, 0, -3], [0, 0, 1], "mirror"),
        ],
    )
    compare(tracer.load_scene(data))


@pytest.mark.parametrize("eye", [[0.0, 0.0, 0.0], [0.3, -0.2, 0.1]])
def test_camera_inside_a_mirror_sphere(eye):
    data = scene_dict(
        camera={"eye": eye, "look_at": [0, 0, -1], "width": 24, "height": 18, "fov_y": 70.0},
        render={"max_depth": 4},
        materials={
            "m": material(
                color=[0.7, 0.5, 0.3], ambient=0.1, diffuse=0.6, specular=0.4, reflectivity=0.5
            )
        },
        lights=[{"type": "point", "position": [0.5, 0.5, 0.5]}],
        objects=[sphere([0, 0, 0], 2.0), sphere([0.0, -0.6, -1.0], 0.3)],
    )
    compare(tracer.load_scene(data))
