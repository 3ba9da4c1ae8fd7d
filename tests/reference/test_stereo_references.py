"""Both eyes of a stereo pair, converted to POV-Ray and Mitsuba, agree with rtlab's like any
other camera, under the reference suite's tolerances (reference/metrics.py argues them; see
tests/reference/test_against_references.py). Each eye is one render (tracer.render.eye_scene):
POV-Ray's perspective ray is direction + x right + y up, so a direction with a component along
right is the off-axis window; Mitsuba's perspective sensor takes principal_point_offset_x.

Injections show the checks see a wrong eye: a window left unshifted (parallel cameras with no
convergence), and Mitsuba's offset with the wrong sign.
"""

from __future__ import annotations

import json
from functools import cache

import numpy as np
import pytest

import tracer
from converters.mitsuba import to_mitsuba_dict
from converters.povray import to_povray
from reference.compare import compare_scene, format_table
from reference.metrics import FLOAT32_SLACK, MAX_SHARE_OVER, MITSUBA_TOLERANCE, agrees
from reference.mitsuba import run_mitsuba
from reference.povray import run_povray
from tests.helpers import SCENES
from tracer.render import eye_scene
from tracer.scene import SceneError, parse_scene

EYES = ("left", "right")


@cache
def pair() -> tracer.Scene:
    """The canonical shadows scene seen by a stereo pair: two lights, shadows falling on a
    sphere, a highlight; eyes 0.5 apart converging on the spheres (the camera is 9.2 away)."""
    data = tracer.load_scene(SCENES / "shadows.toml").to_dict()
    data["camera"].update(width=64, height=48)  # per eye: the references' speed, not the demo's
    data["camera"]["stereo"] = {"eye_separation": 0.5, "convergence": 9.0, "layout": "anaglyph"}
    return parse_scene(data, source="shadows.toml (stereo)")


@cache
def ours(eye: str) -> np.ndarray:
    return tracer.render(eye_scene(pair(), eye), threads=2)


def test_the_eyes_differ_so_the_checks_have_something_to_see():
    assert np.abs(ours("left") - ours("right")).max() > 0.1


@pytest.mark.parametrize("eye", EYES)
def test_each_eye_matches_povray(eye):
    pov = run_povray(eye_scene(pair(), eye), threads=2)
    ok, text = agrees(pov.image, ours(eye), pov.error_bound + FLOAT32_SLACK)
    assert ok, f"{eye} eye vs POV-Ray: {text}"


@pytest.mark.parametrize("eye", EYES)
def test_each_eye_matches_mitsuba(eye):
    result = run_mitsuba(eye_scene(pair(), eye), variant="llvm_ad_rgb", warm=False)
    ok, text = agrees(result.image, ours(eye), MITSUBA_TOLERANCE, MAX_SHARE_OVER)
    assert ok, f"{eye} eye vs Mitsuba: {text}"


def test_an_unshifted_window_fails_against_povray():
    """Injection: the left eye's POV-Ray direction without its shift along right (parallel
    cameras that never converge). The comparison must fail."""
    scene = eye_scene(pair(), "left")
    sdl = to_povray(scene)
    lines = sdl.splitlines()
    k = next(i for i, line in enumerate(lines) if line.strip().startswith("direction"))
    cam = scene.camera
    forward = np.subtract(cam.look_at, cam.eye)
    forward /= np.linalg.norm(forward)
    lines[k] = "  direction <{}, {}, {}>".format(*map(repr, forward.tolist()))
    wrong = "\n".join(lines) + "\n"
    assert wrong != sdl  # injected
    pov = run_povray(scene, threads=2, sdl=wrong)
    ok, _ = agrees(pov.image, ours("left"), pov.error_bound + FLOAT32_SLACK)
    assert not ok


def test_a_principal_point_of_the_wrong_sign_fails_against_mitsuba():
    scene = eye_scene(pair(), "right")
    seen = []

    def flip(d: dict) -> None:
        seen.append(d["sensor"]["principal_point_offset_x"])
        d["sensor"]["principal_point_offset_x"] *= -1

    result = run_mitsuba(scene, variant="llvm_ad_rgb", warm=False, edit=flip)
    assert seen and seen[0] != 0  # injected: there was a shift to flip
    ok, _ = agrees(result.image, ours("right"), MITSUBA_TOLERANCE, MAX_SHARE_OVER)
    assert not ok


def test_the_converters_refuse_two_eyes_in_one_render():
    words = r"camera\.stereo\.layout: expected 'left' or 'right' \({}"
    with pytest.raises(SceneError, match=words.format("POV-Ray renders one eye")):
        to_povray(pair())
    with pytest.raises(SceneError, match=words.format("Mitsuba's sensor is one eye")):
        to_mitsuba_dict(pair())


def test_a_single_camera_converts_as_before():
    """No stereo: the POV-Ray camera is the look_at form every reference was checked with."""
    sdl = to_povray(tracer.load_scene(SCENES / "shadows.toml"))
    assert "look_at" in sdl and "direction" not in sdl


def test_compare_checks_each_eye_of_a_pair(tmp_path):
    """``rtlab compare`` on a stereo scene (reference/compare.py): one row per eye and
    renderer, each reference's verdict naming its eye, images and heat maps per eye."""
    rows = compare_scene(pair(), out_dir=tmp_path, json_path=tmp_path / "m.json")
    assert [(r["eye"], r["renderer"]) for r in rows] == [
        (eye, name) for eye in EYES for name in ("rtlab", "povray", "mitsuba-llvm")
    ]
    verdicts = [r for r in rows if r["renderer"] != "rtlab"]
    assert all(r["agrees"] is True for r in verdicts), [r["verdict"] for r in verdicts]
    assert all(r["verdict"].startswith(f"{r['eye']} eye: ") for r in verdicts)
    assert (tmp_path / "shadows-left-diff-povray.png").is_file()
    assert (tmp_path / "shadows-right-rtlab.exr").is_file()
    assert len(json.loads((tmp_path / "m.json").read_text())) == 6
    assert "R mitsuba-llvm" in format_table(rows)
