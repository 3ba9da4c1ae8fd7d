"""The packet tracer (12_packet.h, the default) against the one-ray tracer (10_classic.h, the
lecture's code as written): the same image bit for bit, and the same ray counts. Both do the
same IEEE-754 operations in the same order and the build forbids fused multiply-add, so any
difference at all is a bug in the packet code."""

from __future__ import annotations

import numpy as np
import pytest

import tracer
from tests.helpers import classic_scenes, material, scene_dict, sphere

CLASSIC = classic_scenes()


def both(scene):
    a = tracer.render_with_stats(scene, threads=2, packets=False)
    b = tracer.render_with_stats(scene, threads=2, packets=True)
    return a, b


@pytest.mark.parametrize("path", CLASSIC, ids=[p.stem for p in CLASSIC])
@pytest.mark.parametrize("spp", [1, 3])
def test_packets_equal_single_rays(path, spp):
    scene = tracer.load_scene(path).with_overrides(width=97, height=61, spp=spp, seed=3)
    a, b = both(scene)
    assert np.array_equal(a.image, b.image), f"{int((a.image != b.image).sum())} values differ"
    assert a.rays == b.rays


def test_packets_equal_single_rays_on_a_stiff_scene():
    """Tiny and huge spheres far from the origin, where every rounding shows."""
    c = [1.0e5, -2.0e5, 3.0e5]
    data = scene_dict(
        camera={"eye": [c[0], c[1] + 1.0, c[2] + 4.0], "look_at": c, "width": 37, "height": 29},
        render={"max_depth": 4},
        materials={"m": material(ambient=0.1, diffuse=0.7, specular=0.5, reflectivity=0.5)},
        lights=[
            {"type": "directional", "direction": [-0.3, -0.5, -1.0]},
            {"type": "point", "position": [c[0] + 2, c[1] + 3, c[2] + 1]},
        ],
        objects=[
            sphere(c, 1.0),
            sphere([c[0] + 0.9, c[1], c[2] + 0.9], 1e-3),
            sphere([c[0], c[1] - 1e6 - 1.0, c[2]], 1e6),
        ],
    )
    a, b = both(tracer.load_scene(data))
    assert np.array_equal(a.image, b.image)
    assert a.rays == b.rays
