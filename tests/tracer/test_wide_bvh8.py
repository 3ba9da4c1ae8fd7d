"""The eight-wide tree of 21_wide_bvh.h (Search8), its nodes quantised (QNode8), in both of
its leaf forms: IndexBlock, for a mesh whose vertices are all floats (the bunny, read from a
PLY file of floats; its triangles with their vertices, up to eight a block), and
TriangleBlock, for any other mesh; and the four-wide tree a mesh falls back to when a box
reaches beyond float's range. Each finds what the lecture's one-ray traversal finds
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


def _bunny_scene():
    """The bunny's scene and its mesh."""
    scene = load_scene(SCENES / "bunny.toml")
    return scene, next(o for o in scene.objects if isinstance(o, Mesh))


def _core_of(vertices, faces):
    """The bunny's scene with the bunny replaced by this mesh, alone."""
    scene, mesh = _bunny_scene()
    mesh = dataclasses.replace(mesh, vertices=vertices, faces=faces)
    return to_core(dataclasses.replace(scene, objects=(mesh,)))


def _bunny_core(scale: float):
    """The bunny alone, its vertices times `scale` (1: floats, as read; else doubles that no
    float equals, so its leaves are TriangleBlocks)."""
    _, mesh = _bunny_scene()
    mesh = dataclasses.replace(mesh, vertices=np.asarray(mesh.vertices) * scale)
    return mesh, _core_of(mesh.vertices, mesh.faces)


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


def test_leaves_whose_triangles_share_no_vertex_agree_with_the_lecture():
    """An IndexBlock holds at most eight vertices: the bunny as a soup of triangles (three
    vertices of their own each, all floats) puts two triangles in a block (six vertices; a
    third would need nine), so each of its leaves of three or four triangles is cut into two
    blocks, where the bunny's own leaves (4 to 8 vertices) are one each."""
    _, mesh = _bunny_scene()
    faces = np.asarray(mesh.faces)
    vertices = np.asarray(mesh.vertices)[faces.ravel()]
    soup = np.arange(len(vertices), dtype=np.int32).reshape(-1, 3)
    assert np.array_equal(vertices.astype(np.float32).astype(np.float64), vertices)
    origins, directions = diffuse_rays(vertices, soup, 30_000, seed=5)
    _agree(_core_of(vertices, soup), origins, directions)


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


def _agree(core, origins, directions, most_hit: bool = False, any_ties: bool = False):
    """The fast search and the lecture's agree on every ray but ties: at most one in 1000, or
    (any_ties) as many as there are, for rays aimed at shared vertices and coincident grids,
    where nearly every hit is a tie. A box that lost a triangle would show as a different t."""
    origins, directions = np.ascontiguousarray(origins), np.ascontiguousarray(directions)
    fast = _core.closest_mesh_hits(core, origins, directions, 1, True)
    plain = _core.closest_mesh_hits(core, origins, directions, 1, False)
    hit = np.mean(np.isfinite(plain[0]))
    assert hit > (0.9 if most_hit else 0.01)
    differ = np.flatnonzero((fast[0] != plain[0]) | (fast[2] != plain[2]))
    assert any_ties or len(differ) <= len(origins) // 1000
    if len(differ):
        _assert_ties(core, origins[differ], directions[differ])


def _grid(offset, size: float, n: int = 48, floats: bool = True, lift: float = 0.0):
    """Two n x n grids of quads (4 n^2 triangles: the eight-wide tree has many nodes), of side
    `size`, at `offset`: one in the plane z = offset z (nodes flat on z), one `lift` above it
    (0: the same plane). Its vertices as floats, or nudged off every float."""
    u = np.linspace(0.0, size, n + 1)
    xx, yy = np.meshgrid(u, u)
    flat = np.stack([xx.ravel(), yy.ravel(), np.zeros(xx.size)], axis=1)
    vertices = np.concatenate([flat, flat + np.array([0.0, 0.0, lift])]) + np.asarray(offset)
    vertices = vertices.astype(np.float32).astype(np.float64)
    if not floats:
        vertices = vertices * (1 + 2**-40)
    k = (np.arange(n)[:, None] * (n + 1) + np.arange(n)[None, :]).ravel()
    quads = np.concatenate([np.stack([k, k + 1, k + n + 2, k + n + 1], 1), (n + 1) ** 2 +
                            np.stack([k, k + 1, k + n + 2, k + n + 1], 1)])  # fmt: skip
    faces = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]]).astype(np.int32)
    return vertices, faces


@pytest.mark.parametrize("floats", [True, False])
@pytest.mark.parametrize(
    "offset, size, lift",
    # (the grids' floats: at x = 1e5 a float's step is 2^-7, so a side of 20 keeps 48 distinct
    # steps; a lift of 1e-7 at z = 0.5 is two steps of 2^-24 apart, 16 at z = 1e8 two of 8)
    [((0.0, 0.0, 0.0), 1.0, 0.0), ((1e5, -3e4, 0.5), 20.0, 1e-7), ((-2.5, 4.0, 1e8), 3e3, 16.0)],
)
def test_quantised_boxes_hold_every_triangle(offset, size, lift, floats):
    """Rays at points a millionth of a triangle from one of its corners (inside it, so that one
    triangle is hit, not a tie of six: a corner lies on its leaf's box, and a quantised plane
    rounded inward by as little as a 255th of its node would lose the point), and at centroids,
    on grids far from the origin, small, and flat on one axis (a node's extent 0, or a
    ten-millionth of its side). With lift 0 the two grids coincide: every hit is a tie of two
    triangles, at the same t."""
    vertices, faces = _grid(offset, size, floats=floats, lift=lift)
    floats_in = np.array_equal(vertices.astype(np.float32).astype(np.float64), vertices)
    assert floats_in == floats
    core = _core_of(vertices, faces)
    rng = np.random.default_rng(5)
    corners = vertices[faces[rng.integers(0, len(faces), 8000)]]  # (n, 3 corners, 3)
    e = 1e-6
    b = np.where(np.arange(3) == rng.integers(0, 3, 8000)[:, None], 1 - 2 * e, e)
    b[4000:] = 1 / 3
    targets = np.sum(b[..., None] * corners, axis=1)
    # From above, slanted, so that each ray crosses several boxes before its target.
    d = rng.normal(size=targets.shape) * [0.3, 0.3, 0.0] + [0.0, 0.0, -1.0]
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    origins = targets - d * (size + lift + 1.0)
    _agree(core, origins, d, most_hit=True, any_ties=lift == 0)


@pytest.mark.parametrize("floats", [True, False])
def test_a_leaf_of_many_blocks_agrees_with_the_lecture(floats):
    """A grid with a star of 22 triangles about one point above it, each triangle's box
    centred exactly on that point (corners centre + a, centre - a and centre + b, |b| <= |a|
    per axis): the binary build splits by box centres, none separates them, so they stay in
    one leaf, which the eight-wide tree reads as a chain of blocks (eleven IndexBlocks: the
    star's triangles share no vertex, so a block holds two; six TriangleBlocks). Rays through
    the star from every side; where two of its triangles cross, a ray may meet both at one t
    (a tie)."""
    vertices, faces = _grid((0.0, 0.0, 0.0), 1.0, n=16, floats=floats)
    rng = np.random.default_rng(3)
    centre = np.array([0.5, 0.5, 2.0])
    a = rng.integers(1, 9, size=(22, 3)) * rng.choice([-1, 1], size=(22, 3)) / 16
    b = a * rng.integers(-8, 9, size=(22, 3)) / 8  # all exact: multiples of 2^-7
    star = np.stack([centre + a, centre - a, centre + b], axis=1)
    centres = (star.max(axis=1) + star.min(axis=1)) / 2
    assert np.all(centres == centre)
    star = star.reshape(-1, 3) * (1.0 if floats else 1 + 2**-40)
    star_faces = len(vertices) + np.arange(len(star)).reshape(-1, 3)
    faces = np.concatenate([faces, star_faces]).astype(np.int32)
    vertices = np.concatenate([vertices, star])
    _, _, count, _ = _core.mesh_hierarchy(vertices, faces, 1)
    assert max(count) == 22
    n = 20_000
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    targets = centre + rng.uniform(-0.4, 0.4, size=(n, 3))
    _agree(_core_of(vertices, faces), targets - 3 * d, d, any_ties=True)


def test_a_box_beyond_floats_range_falls_back_to_the_four_wide_tree():
    """The bunny with one more triangle reaching to x = 1e300, beyond float's range: the root's
    box cannot be quantised (its float plane is infinite), so the mesh is searched in the
    four-wide tree, whose float planes may be infinite; it still finds what the lecture finds."""
    mesh, _ = _bunny_core(1.0)
    vertices = np.concatenate([np.asarray(mesh.vertices), [[1e300, 0.0, 0.0]]])
    with np.errstate(over="ignore"):
        assert np.isinf(np.float32(vertices[-1, 0]))
    faces = np.concatenate([np.asarray(mesh.faces), [[0, 1, len(vertices) - 1]]]).astype(np.int32)
    core = _core_of(vertices, faces)
    origins, directions = diffuse_rays(mesh.vertices, mesh.faces, 20_000, seed=3)
    _agree(core, origins, directions)


@pytest.mark.parametrize(
    "direction",
    # zero components (1/d infinite), a tiny one (1/d beyond 2^100), a small one (1/d 1e12: from
    # 1e8 away beyond 2^64 times the reach), and a plain slanted ray for contrast
    [
        (0.0, 0.0, -1.0),
        (1.0, 0.0, 0.0),
        (0.0, -1.0, 0.0),
        (0.6, 0.0, -0.8),
        (1e-32, 0.6, -0.8),
        (1e-12, 0.6, -0.8),
        (0.3, -0.5, 0.8),
    ],
)
@pytest.mark.parametrize("distance", [1.0, 1e8])
def test_rays_the_float_node_test_cannot_take_agree(direction, distance):
    """Search8 tests a node's boxes in float (21_wide_bvh.h float_slab_test8()) only where the
    ray's 1/d lies within 2^-100 to 2^100 on every axis and its origin is not far beyond the
    tree (2^64 times its reach); other rays are tested in double as the lecture does. Rays
    parallel to an axis or a plane, nearly so, from near and from 1e8 away (where a double's
    step is 1.5e-8, a ten-millionth of the bunny), aimed at triangle centroids."""
    mesh, core = _bunny_core(1.0)
    vertices, faces = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    rng = np.random.default_rng(13)
    targets = np.mean(vertices[faces[rng.integers(0, len(faces), 4000)]], axis=1)
    d = np.tile(np.asarray(direction, dtype=np.float64), (len(targets), 1))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    _agree(core, targets - distance * d, d, most_hit=True)


def test_a_ray_whose_float_node_test_would_overflow_agrees():
    """The grid of quads at z = 1e8, 3e3 across (a node's step in x is about 12), met by rays
    whose x component is 1e-36: in float, 1/d (1e36) times a node's step times a q of 255 is
    beyond float's range, an infinite entry t that would lose the box. Such a ray (1/d beyond
    2^100) is tested in double."""
    vertices, faces = _grid((-2.5, 4.0, 1e8), 3e3, lift=16.0)
    core = _core_of(vertices, faces)
    rng = np.random.default_rng(17)
    targets = np.mean(vertices[faces[rng.integers(0, len(faces), 4000)]], axis=1)
    d = np.tile([1e-36, 0.6, -0.8], (len(targets), 1))
    _agree(core, targets - 10.0 * d, d, most_hit=True)
