"""rtlab's aov integrator (what each primary ray hits, how far, with what normal) against a
rasteriser (pyrender, offscreen) and Mitsuba's own aov integrator, on the geometry scenes."""

from __future__ import annotations

import numpy as np
import pytest

import tracer
from reference.geometry import mitsuba_geometry, pyrender_geometry, rtlab_geometry
from reference.metrics import MAX_SHARE_OVER
from tests.helpers import SCENES

NAMES = ["bunny", "bunny_smooth", "boxes_triangles", "torus_cylinder", "inside_mesh", "ex25"]


def load(name):
    scene = tracer.load_scene(SCENES / f"{name}.toml")
    return scene.with_overrides(width=160, height=120)


@pytest.mark.parametrize("name", NAMES)
def test_visibility_and_depth_match_a_rasteriser(name):
    scene = load(name)
    ours = rtlab_geometry(scene)
    theirs, tolerance = pyrender_geometry(scene)
    compare = theirs.compare
    assert compare.mean() > 0.9
    differ = (ours.object_id != theirs.object_id) & compare
    # Silhouettes of tessellated shapes may differ by a pixel: bounded like the images.
    assert differ.mean() <= MAX_SHARE_OVER, f"{int(differ.sum())} pixels see another object"
    both = compare & ~differ & (ours.object_id >= 0)
    rel = np.abs(ours.depth[both] - theirs.depth[both]) / ours.depth[both]
    # Grazing rays turn the tessellation's sagitta into a longer depth error: at most 1% of
    # the pixels may exceed the per-pixel bound.
    assert (rel <= tolerance[both]).mean() >= 0.99, f"max relative depth error {rel.max():.2e}"


@pytest.mark.parametrize("name", NAMES)
def test_visibility_depth_and_normals_match_mitsuba_aov(name):
    scene = load(name)
    ours = rtlab_geometry(scene)
    theirs = mitsuba_geometry(scene)
    differ = ours.object_id != theirs.object_id
    assert differ.mean() <= MAX_SHARE_OVER, f"{int(differ.sum())} pixels see another object"
    both = ~differ & (ours.object_id >= 0)
    # float32 intersection: ~1e-6 relative; the torus's tessellation (sagitta ~1.9e-5 of its
    # radii) within 1e-4; grazing rays at most 1% of pixels beyond.
    rel = np.abs(ours.depth[both] - theirs.depth[both]) / ours.depth[both]
    assert (rel <= 1e-4).mean() >= 0.99, f"max relative depth error {rel.max():.2e}"
    cos = np.sum(ours.normal * theirs.normal, axis=-1)[both]
    # Normals: float32 (1e-6 rad) or interpolated on a fine tessellation (~1e-4 rad at most).
    assert (cos >= np.cos(1e-3)).mean() >= 0.99, f"worst normal angle {np.arccos(cos.min()):.2e}"


def test_a_wrong_camera_is_caught():
    """So the checks above can fail: a rasteriser given a wider field of view disagrees."""
    scene = load("boxes_triangles")
    ours = rtlab_geometry(scene)
    wrong, _ = pyrender_geometry(scene.with_overrides(fov_y=scene.camera.fov_y * 1.05))
    assert ((ours.object_id != wrong.object_id) & wrong.compare).mean() > 0.01
