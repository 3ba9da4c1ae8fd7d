"""A converter bug must fail the regression rule: feed deliberately wrong conversions (a
mirrored image, a wrong field of view, a missing light, a wrong trace depth) and check that
`agrees` rejects each, for POV-Ray and for Mitsuba."""

from __future__ import annotations

import re

import pytest

import tracer
from converters.povray import to_povray
from reference.metrics import FLOAT32_SLACK, MITSUBA_TOLERANCE, agrees
from reference.mitsuba import run_mitsuba
from reference.povray import run_povray
from tests.helpers import SCENES

SCENE = SCENES / "ex25.toml"


@pytest.fixture(scope="module")
def scene_and_image():
    scene = tracer.load_scene(SCENE).with_overrides(width=96, height=72)
    return scene, tracer.render(scene, threads=2)


def _drop_first_light(sdl: str) -> str:
    return re.sub(r"^light_source \{[^\n]*\n", "", sdl, count=1, flags=re.M)


POVRAY_BUGS = {
    "mirrored": lambda sdl: sdl.replace("right -x*", "right x*"),
    "vertical fov as horizontal": lambda sdl: re.sub(r"angle [\d.]+", "angle 40.0", sdl),
    "missing light": _drop_first_light,
    "trace level off by one": lambda sdl: sdl.replace("max_trace_level 6", "max_trace_level 5"),
    "phong tinted": lambda sdl: sdl.replace("specular 0\n", "specular 0 metallic\n"),
}


def test_the_correct_povray_conversion_passes(scene_and_image):
    scene, ours = scene_and_image
    pov = run_povray(scene, threads=2)
    assert agrees(pov.image, ours, pov.error_bound + FLOAT32_SLACK)[0]


@pytest.mark.parametrize("bug", POVRAY_BUGS, ids=list(POVRAY_BUGS))
def test_a_wrong_povray_conversion_fails(scene_and_image, bug):
    scene, ours = scene_and_image
    sdl = to_povray(scene)
    wrong = POVRAY_BUGS[bug](sdl)
    assert wrong != sdl, "the bug was not injected"
    pov = run_povray(scene, threads=2, sdl=wrong)
    ok, text = agrees(pov.image, ours, pov.error_bound + FLOAT32_SLACK)
    assert not ok, f"{bug} went unnoticed: {text}"


def _fov_axis_x(d):
    d["sensor"]["fov_axis"] = "x"


def _drop_light(d):
    del d["light_0"]


def _upside_down(d):
    import mitsuba as mi

    scene = tracer.load_scene(SCENE)
    cam = scene.camera
    d["sensor"]["to_world"] = mi.ScalarTransform4f().look_at(
        origin=cam.eye, target=cam.look_at, up=[-u for u in cam.up]
    )


def _shallow(d):
    d["integrator"]["max_depth"] = 5


MITSUBA_BUGS = {
    "horizontal fov": _fov_axis_x,
    "missing light": _drop_light,
    "upside down": _upside_down,
    "trace depth off by one": _shallow,
}


@pytest.mark.parametrize("bug", MITSUBA_BUGS, ids=list(MITSUBA_BUGS))
def test_a_wrong_mitsuba_conversion_fails(scene_and_image, bug):
    scene, ours = scene_and_image
    result = run_mitsuba(scene, variant="llvm_ad_rgb", warm=False, edit=MITSUBA_BUGS[bug])
    ok, text = agrees(result.image, ours, MITSUBA_TOLERANCE)
    assert not ok, f"{bug} went unnoticed: {text}"


def test_a_wrong_geometry_conversion_fails():
    """Geometry converters too: a torus left lying in POV-Ray's own xz plane, a mesh whose
    smooth normals are dropped, and a box given Mitsuba's cube without its scale each fail."""
    tori = tracer.load_scene(SCENES / "torus_cylinder.toml").with_overrides(width=96, height=72)
    ours = tracer.render(tori, threads=2)
    sdl = to_povray(tori)
    wrong = re.sub(r"(torus \{[^}]*?sturm texture \{ \w+ \}) matrix <[^>]*>", r"\1", sdl, count=1)
    assert wrong != sdl
    pov = run_povray(tori, threads=2, sdl=wrong)
    assert not agrees(pov.image, ours, pov.error_bound + FLOAT32_SLACK)[0]

    smooth = tracer.load_scene(SCENES / "bunny_smooth.toml").with_overrides(width=96, height=72)
    ours = tracer.render(smooth, threads=2)
    sdl = to_povray(smooth)
    wrong = re.sub(r"  normal_vectors \{.*?\n  \}\n", "", sdl, count=1, flags=re.S)
    assert wrong != sdl
    pov = run_povray(smooth, threads=2, sdl=wrong)
    assert not agrees(pov.image, ours, pov.error_bound + FLOAT32_SLACK)[0]

    boxes = tracer.load_scene(SCENES / "boxes_triangles.toml").with_overrides(width=96, height=72)
    ours = tracer.render(boxes, threads=2)

    def unscaled_cube(d):
        import mitsuba as mi

        d["object_1"]["to_world"] = mi.ScalarTransform4f().translate([0.3, -0.55, 0.15])

    result = run_mitsuba(boxes, variant="llvm_ad_rgb", warm=False, edit=unscaled_cube)
    assert not agrees(result.image, ours, MITSUBA_TOLERANCE)[0]
