"""The eight-wide tree of 21_wide_bvh.h (Search8) in both of its leaf forms: FloatBlock, for a
mesh whose vertices are all floats (the bunny, read from a PLY file of floats), and
TriangleBlock, for any other mesh. Either finds what the lecture's one-ray traversal finds
(packets=False), but at ties (tests/tracer/test_wide_bvh.py says why a tie may differ)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from reference.bench import diffuse_rays
from tests.helpers import SCENES
from tests.tracer.test_wide_bvh import _assert_ties
from tracer import _core
from tracer.render import to_core
from tracer.scene import Mesh, load_scene


def _bunny_core(scale: float):
    """The bunny alone, its vertices times `scale` (1: floats, as read; else doubles that no
    float equals, so its leaves are TriangleBlocks)."""
    scene = load_scene(SCENES / "bunny.toml")
    mesh = next(o for o in scene.objects if isinstance(o, Mesh))
    mesh = dataclasses.replace(mesh, vertices=np.asarray(mesh.vertices) * scale)
    return mesh, to_core(dataclasses.replace(scene, objects=(mesh,)))


@pytest.mark.parametrize("scale", [1.0, 1 + 2**-40])
def test_both_leaf_forms_agree_with_the_lecture(scale):
    mesh, core = _bunny_core(scale)
    vertices = np.asarray(mesh.vertices)
    floats = np.array_equal(vertices.astype(np.float32).astype(np.float64), vertices)
    assert floats == (scale == 1.0)
    origins, directions = diffuse_rays(mesh.vertices, mesh.faces, 30_000, seed=7)
    fast = _core.closest_mesh_hits(core, origins, directions, 2, True)
    plain = _core.closest_mesh_hits(core, origins, directions, 2, False)
    assert 0.01 < np.mean(np.isfinite(plain[0])) < 0.99
    differ = np.flatnonzero((fast[0] != plain[0]) | (fast[2] != plain[2]))
    assert len(differ) <= len(origins) // 1000
    if len(differ):
        _assert_ties(core, origins[differ], directions[differ])


def test_rays_from_outside_and_inside_the_bunny_agree():
    """Rays from far away (many children met per node, so the key sort orders up to eight) and
    from the bunny's centre (every direction meets it)."""
    mesh, core = _bunny_core(1.0)
    rng = np.random.default_rng(11)
    n = 20_000
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    centre = np.mean(np.asarray(mesh.vertices), axis=0)
    for origins, directions in ((centre - 200 * d, d), (np.tile(centre, (n, 1)), d)):
        origins = np.ascontiguousarray(origins)
        directions = np.ascontiguousarray(directions)
        fast = _core.closest_mesh_hits(core, origins, directions, 1, True)
        plain = _core.closest_mesh_hits(core, origins, directions, 1, False)
        assert np.mean(np.isfinite(plain[0])) > 0.1
        differ = np.flatnonzero((fast[0] != plain[0]) | (fast[2] != plain[2]))
        assert len(differ) <= n // 1000
        if len(differ):
            _assert_ties(core, origins[differ], directions[differ])
