"""Helpers shared by the tests: the repository's paths and small scenes built as dicts in the
scene language. (Fixtures live in conftest.py; helpers are imported from here.)"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]  # the repository
SCENES = ROOT / "reference" / "scenes"  # the canonical scenes

BASE: dict[str, Any] = {
    "camera": {
        "eye": [0.0, 0.0, 5.0],
        "look_at": [0.0, 0.0, 0.0],
        "up": [0.0, 1.0, 0.0],
        "fov_y": 30.0,
        "width": 1,
        "height": 1,
    },
    "render": {"max_depth": 5, "background": [0.0, 0.0, 0.0], "ambient_light": [1.0, 1.0, 1.0]},
    "materials": {
        "m": {
            "color": [1.0, 1.0, 1.0],
            "ambient": 0.0,
            "diffuse": 0.0,
            "specular": 0.0,
            "shininess": 10.0,
            "reflectivity": 0.0,
        }
    },
    "lights": [],
    "objects": [],
}


def scene_dict(**parts: Any) -> dict[str, Any]:
    """A copy of BASE with top-level tables merged (dicts) or replaced (lists)."""
    data = copy.deepcopy(BASE)
    for key, value in parts.items():
        if isinstance(value, dict) and key in ("camera", "render"):
            data[key].update(value)
        else:
            data[key] = copy.deepcopy(value)
    return data


def sphere(center: list[float], radius: float, material: str = "m") -> dict[str, Any]:
    return {"type": "sphere", "center": center, "radius": radius, "material": material}


def plane(point: list[float], normal: list[float], material: str = "m") -> dict[str, Any]:
    return {"type": "plane", "point": point, "normal": normal, "material": material}


def material(**terms: Any) -> dict[str, Any]:
    m = copy.deepcopy(BASE["materials"]["m"])
    m.update(terms)
    return m


def classic_scenes() -> list[Path]:
    """The canonical scenes of the classic model (the path-traced ones are checked
    statistically, in tests/tracer/test_path.py and tests/reference/test_path_stats.py)."""
    import tracer

    return [
        p
        for p in sorted(SCENES.glob("*.toml"))
        if tracer.load_scene(p).render.integrator == "classic"
    ]


def left_eye(camera: Any) -> tuple[np.ndarray, float]:
    """The eye and image-window shift of tracer/cpp/03_camera.h stereo_eye(..., side=-1) for a
    camera (tracer.scene.model.Camera) with a stereo pair, or the camera's own eye and 0."""
    from reference.bench import camera_frame

    eye, _, right, _, _, _ = camera_frame(camera)
    if camera.stereo is None:
        return eye, 0.0
    half = -camera.stereo.eye_separation / 2
    return eye + half * right, -half / camera.stereo.convergence


def pixel_direction(camera: Any, i: float, j: float) -> np.ndarray:
    """03_camera.h primary_ray()'s unit direction through image point (i, j), in pixel units
    ((k + 0.5, l + 0.5) is the centre of pixel (k, l)); the left eye's for a stereo pair."""
    from reference.bench import camera_frame

    _, forward, right, up, w, h = camera_frame(camera)
    shift = left_eye(camera)[1]
    d = (
        forward
        + ((i / camera.width - 0.5) * w + shift) * right
        + (0.5 - j / camera.height) * h * up
    )
    return d / np.linalg.norm(d)
