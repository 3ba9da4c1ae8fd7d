"""The meshes' faster search (tracer/cpp/21_wide_bvh.h, used with packets=True) finds what the
lecture's one-ray traversal (16_mesh.h Mesh::traverse, packets=False) finds.

Both test every triangle with the same intersect_triangle() arithmetic and keep the closest hit;
they may visit leaves in different orders. The one place where order can change the answer is a
tie: two triangles (sharing an edge) hit at exactly the same t, where each search keeps the one
it visits last. So every differing pixel or ray must be shown to be such a tie: both searches
report the same t, each for its own triangle (each t is intersect_triangle()'s for that
triangle, so both triangles are hit at that t)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from reference.bench import diffuse_rays
from tests.helpers import SCENES
from tracer import _core
from tracer.render import render_with_stats, to_core
from tracer.scene import Mesh, load_scene

MESH_SCENES = ["bunny.toml", "bunny_smooth.toml", "boxes_triangles.toml", "inside_mesh.toml",
               "cornell_box.toml"]  # fmt: skip


def _both(scene, **kw):
    fast = render_with_stats(scene, threads=2, progress=False, packets=True, **kw)
    plain = render_with_stats(scene, threads=2, progress=False, packets=False, **kw)
    return fast, plain


def _assert_ties(core, origins, directions):
    """Each ray is a tie: the same t from both searches, for two different triangles."""
    t_fast, obj_fast, tri_fast = _core.closest_mesh_hits(core, origins, directions, 1, True)
    t_plain, obj_plain, tri_plain = _core.closest_mesh_hits(core, origins, directions, 1, False)
    assert np.array_equal(t_fast, t_plain)
    assert np.all(np.isfinite(t_fast))
    assert np.all((tri_fast != tri_plain) | (obj_fast != obj_plain))


@pytest.mark.parametrize("name", MESH_SCENES)
def test_aov_depth_object_and_normal_agree(name):
    scene = load_scene(SCENES / name).with_overrides(width=96, height=64, integrator="aov")
    fast, plain = _both(scene)
    if name.startswith("bunny"):  # the flag reached the meshes: four-box nodes, not pairs
        assert fast.rays["box_tests"] != plain.rays["box_tests"]  # (a mesh of <= 4 triangles
        # is one leaf either way, one box test per ray)
    differ = np.argwhere(np.any(fast.image != plain.image, axis=-1))
    assert len(differ) <= fast.image.shape[0] * fast.image.shape[1] // 100
    if len(differ):
        core = to_core(scene)
        rays = [core.primary_ray(i + 0.5, j + 0.5) for j, i in differ]
        _assert_ties(core, np.array([o for o, _ in rays]), np.array([d for _, d in rays]))


@pytest.mark.parametrize("name", ["bunny.toml", "boxes_triangles.toml", "inside_mesh.toml"])
def test_classic_images_agree(name):
    """Closest hits, shadow rays (blocks(): any hit) and reflections through meshes."""
    scene = load_scene(SCENES / name).with_overrides(width=64, height=48)
    fast, plain = _both(scene)
    assert np.array_equal(fast.image, plain.image)


def test_path_tracer_uses_the_wide_search_and_agrees():
    """The path tracer reaches meshes through Mesh::hit()/blocks(), so packets=True gives it the
    wide search. A tie at a shared edge (the room's quads are two triangles each, and a path
    can meet a diagonal exactly) keeps the other triangle, whose hit point differs in its last
    bits, and the path after it wanders off: so not every pixel is bit-identical here (one of
    576 when this was written). The same paths are traced (equal ray counts), and all but 1% of
    the pixels must be identical; the ties themselves are shown for primary rays above."""
    scene = load_scene(SCENES / "cornell_box.toml").with_overrides(width=24, height=24, spp=4)
    fast, plain = _both(scene)
    assert fast.rays["box_tests"] != plain.rays["box_tests"]
    for kind in ("primary", "secondary", "shadow"):
        assert fast.rays[kind] == plain.rays[kind]
    differ = np.sum(np.any(fast.image != plain.image, axis=-1))
    assert differ <= 24 * 24 // 100


def _bunny():
    """The bunny's mesh, and a core scene of it alone."""
    scene = load_scene(SCENES / "bunny.toml")
    mesh = next(o for o in scene.objects if isinstance(o, Mesh))
    return mesh, to_core(dataclasses.replace(scene, objects=(mesh,)))


def test_incoherent_rays_from_the_bunny_agree():
    """The bench's bunny-diffuse rays: start just off the surface (the t-error guard and
    starts_off_the_plane_heading_in() decide the triangle they leave), go anywhere."""
    mesh, core = _bunny()
    origins, directions = diffuse_rays(mesh.vertices, mesh.faces, 50_000, seed=3)
    fast = _core.closest_mesh_hits(core, origins, directions, 2, True)
    plain = _core.closest_mesh_hits(core, origins, directions, 2, False)
    assert 0.01 < np.mean(np.isfinite(plain[0])) < 0.99  # some rays hit the bunny again
    differ = np.flatnonzero((fast[0] != plain[0]) | (fast[2] != plain[2]))
    assert len(differ) <= len(origins) // 1000
    if len(differ):
        _assert_ties(core, origins[differ], directions[differ])


def test_batch_threads_change_nothing():
    mesh, core = _bunny()
    origins, directions = diffuse_rays(mesh.vertices, mesh.faces, 20_000, seed=5)
    one = _core.closest_mesh_hits(core, origins, directions, 1, True)
    two = _core.closest_mesh_hits(core, origins, directions, 2, True)
    for a, b in zip(one, two, strict=True):
        assert np.array_equal(a, b)
    with pytest.raises(ValueError, match="threads"):
        _core.closest_mesh_hits(core, origins, directions, 0, True)


def test_a_batch_answer_held_is_never_written_by_the_next():
    """closest_mesh_hits() writes its three columns into one block from the images' cache
    (bindings.cpp allocate_image()): the columns of one answer must not overlap, an answer still
    held must not be written by a later batch, and a block reused after an answer was dropped
    must hold the new batch's answer only."""
    mesh, core = _bunny()
    origins, directions = diffuse_rays(mesh.vertices, mesh.faces, 4_000, seed=11)
    others = diffuse_rays(mesh.vertices, mesh.faces, 4_000, seed=12)
    first = _core.closest_mesh_hits(core, origins, directions, 2)
    kept = [column.copy() for column in first]
    t, objects, triangles = first
    assert not np.shares_memory(t, objects) and not np.shares_memory(objects, triangles)
    assert not np.shares_memory(t, triangles)
    other = _core.closest_mesh_hits(core, *others, 2)
    expected = [column.copy() for column in other]
    assert not np.array_equal(expected[2], kept[2])  # so an overwrite of `first` would show
    del other  # its block becomes the spare: the next batch of this size writes into it
    again = _core.closest_mesh_hits(core, *others, 2)
    for held, copy in zip(first, kept, strict=True):
        assert np.array_equal(held, copy)
    for column, copy in zip(again, expected, strict=True):
        assert np.array_equal(column, copy)
    empty = _core.closest_mesh_hits(core, origins[:0], directions[:0], 1)
    assert [len(column) for column in empty] == [0, 0, 0]


def test_the_hierarchy_built_on_two_threads_is_the_one_built_on_one():
    """16_mesh.h builds the root's two halves side by side on a large mesh; the right half's
    nodes, moved after the left's, must be the one-thread build's node for node."""
    scene = load_scene(SCENES / "bunny.toml")
    mesh = next(o for o in scene.objects if isinstance(o, Mesh))
    vertices = np.ascontiguousarray(mesh.vertices, dtype=np.float64)
    faces = np.ascontiguousarray(mesh.faces, dtype=np.int32)
    assert len(faces) >= 4096  # large enough for the parallel build (parallel_build_triangles)
    one = _core.mesh_hierarchy(vertices, faces, 1)
    two = _core.mesh_hierarchy(vertices, faces, 2)
    assert len(one[1]) > 10_000
    for a, b in zip(one, two, strict=True):
        assert a == b
