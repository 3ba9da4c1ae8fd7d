"""Every canonical scene, rendered by rtlab, POV-Ray and Mitsuba, must agree.

Tolerances (reference/metrics.py and reference/povray.py give the arguments):
- POV-Ray: per pixel, the precision of its output (16-bit PNG: 7.6e-6; where a value exceeds 1,
  its half-float EXR: 2^-11 relative) plus FLOAT32_SLACK for our own float32 output.
- Mitsuba: MITSUBA_TOLERANCE (float32 visibility, amplified at most by the Phong exponent).
- For both, at most MAX_SHARE_OVER (0.05%) of the pixels may exceed that: silhouettes that the
  renderers decide in different precision. The README explains why.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

import numpy as np
import pytest

import tracer
from reference.metrics import (
    FLOAT32_SLACK,
    MAX_SHARE_OVER,
    MAX_SHARE_TESSELLATED,
    MITSUBA_TOLERANCE,
    agrees,
)
from reference.mitsuba import run_mitsuba
from reference.povray import run_povray
from tests.helpers import classic_scenes
from tracer.scene import Torus

CLASSIC = classic_scenes()
IDS = [p.stem for p in CLASSIC]


@cache
def scene_and_image(path: Path, width: int | None = None) -> tuple[tracer.Scene, np.ndarray]:
    scene = tracer.load_scene(path)
    if width is not None:
        scene = scene.with_overrides(width=width, height=width * 3 // 4)
    elif scene.camera.width > 200:  # the demo scene: tests use a smaller copy
        scene = scene.with_overrides(width=160, height=120)
    return scene, tracer.render(scene, threads=2)


def mitsuba_share(scene: tracer.Scene) -> float:
    """Tori are tessellated for Mitsuba: their silhouettes get the argued, larger bound."""
    tori = any(isinstance(obj, Torus) for obj in scene.objects)
    return MAX_SHARE_TESSELLATED if tori else MAX_SHARE_OVER


def test_there_are_canonical_scenes():
    names = set(IDS)
    assert {"ex25", "lambert", "phong", "shadows", "directional", "mirrors", "background"} <= names
    assert {"case_inside", "case_internal", "case_tangent", "case_none"} <= names
    assert {"bunny", "bunny_smooth", "boxes_triangles", "torus_cylinder", "inside_mesh"} <= names


@pytest.mark.parametrize("path", CLASSIC, ids=IDS)
def test_matches_povray(path):
    scene, ours = scene_and_image(path)
    pov = run_povray(scene, threads=2)
    ok, text = agrees(pov.image, ours, pov.error_bound + FLOAT32_SLACK)
    assert ok, f"{path.name} vs POV-Ray: {text}"


@pytest.mark.parametrize("path", CLASSIC, ids=IDS)
def test_matches_mitsuba_llvm(path):
    scene, ours = scene_and_image(path)
    result = run_mitsuba(scene, variant="llvm_ad_rgb", warm=False)
    assert result.variant == "llvm_ad_rgb"
    ok, text = agrees(result.image, ours, MITSUBA_TOLERANCE, mitsuba_share(scene))
    assert ok, f"{path.name} vs Mitsuba llvm_ad_rgb: {text}"


@pytest.mark.parametrize("path", CLASSIC, ids=IDS)
def test_matches_mitsuba_scalar(path):
    """scalar_rgb runs the Python integrator once per ray: a smaller image keeps it quick.
    Silhouette pixels grow with an image's width, all pixels with its area: at 64 pixels wide
    instead of 160, the same silhouettes are a 160/64 times larger share."""
    scene, ours = scene_and_image(path, width=64)
    result = run_mitsuba(scene, variant="scalar_rgb", warm=False)
    ok, text = agrees(result.image, ours, MITSUBA_TOLERANCE, mitsuba_share(scene) * 160 / 64)
    assert ok, f"{path.name} vs Mitsuba scalar_rgb: {text}"


def test_the_comparisons_are_not_vacuous():
    """Each canonical scene is a real picture, and in the mirrors scene both max_depth and
    min_coefficient change over a thousand pixels, so a renderer ignoring either would fail."""
    for path in CLASSIC:
        _, image = scene_and_image(path)
        assert image.std() > 0.02, path.name
    scene, image = scene_and_image(CLASSIC[IDS.index("mirrors")])
    deeper = tracer.render(scene.with_overrides(max_depth=30), threads=2)
    data = scene.to_dict()
    data["render"]["min_coefficient"] = 0.0
    uncut = tracer.render(tracer.load_scene(data), threads=2)
    assert np.sum(np.abs(deeper - image).max(-1) > 1e-3) > 1000
    assert np.sum(np.abs(uncut - image).max(-1) > 1e-3) > 1000
