"""Issue 11's far cameras with narrow fields of view (study/families_scenes.py ``far-camera``):
the rays are rtlab's own pixel rays (the core's camera, tracer/cpp/03_camera.h, through the
binding Scene.primary_ray at pixel centres), judged two ways (protocol "camera"):

- every method's decisions on those very rays against their exact truth (study/metrics.py
  decision(); study/truth.py), as any family's;
- the camera itself (rtlab's rows only: the rays are its camera's): the angle between each of
  its pixel rays and the exact pixel ray computed at DIGITS digits from the camera description
  (eye, look_at, up, fov_y, the image size: 03_camera.h's construction in real arithmetic, pi
  exact): ``camera_angle_max_rad``, and that angle in pixels (the angle one pixel spans at the
  image centre, plane_height / height), ``camera_error_pixels_max``: whether the camera itself
  loses the image at 1e8 and 1e-7 degrees."""

from __future__ import annotations

import dataclasses
from typing import Any

import mpmath
import numpy as np

from study import metrics
from study import truth as oracle
from study.families import Array, Case
from study.methods import Method


@dataclasses.dataclass(frozen=True)
class CameraCase(Case):
    camera: dict[str, Any] | None = None  # the scene language's camera table


def pixel_rays(shape: object, camera: dict[str, Any]) -> tuple[Array, Array]:
    """The core's primary rays through every pixel centre of the camera (row-major)."""
    import tracer
    from tracer.render import to_core

    scene = tracer.load_scene({"camera": camera, "materials": {"m": {"color": [1.0, 1.0, 1.0]}},
                               "objects": [shape.scene_object() | {"material": "m"}]})  # type: ignore[attr-defined]  # fmt: skip
    core = to_core(scene)
    o, d = [], []
    for j in range(camera["height"]):
        for i in range(camera["width"]):
            a, b = core.primary_ray(i + 0.5, j + 0.5)
            o.append(a)
            d.append(b)
    return np.array(o), np.array(d)


def _unit(v: list) -> list:
    n = mpmath.sqrt(oracle._mdot(v, v))
    return [x / n for x in v]


def exact_directions(camera: dict[str, Any]) -> list[list]:
    """The exact unit pixel rays (row-major), at the current mpmath precision."""
    eye, at, up = (oracle._m(camera[k]) for k in ("eye", "look_at", "up"))
    w, h = camera["width"], camera["height"]
    forward = _unit([a - e for a, e in zip(at, eye, strict=True)])
    right = _unit(oracle._cross_m(forward, up))
    true_up = oracle._cross_m(right, forward)
    ph = 2 * mpmath.tan(mpmath.mpf(camera["fov_y"]) * mpmath.pi / 360)
    pw = ph * w / h
    out = []
    for j in range(h):
        for i in range(w):
            x = (i + mpmath.mpf(0.5)) / w - mpmath.mpf(0.5)
            y = mpmath.mpf(0.5) - (j + mpmath.mpf(0.5)) / h
            out.append(_unit([forward[k] + x * pw * right[k] + y * ph * true_up[k]
                              for k in range(3)]))  # fmt: skip
    return out


def camera_error(case: CameraCase) -> dict[str, float]:
    assert case.camera is not None
    exact = exact_directions(case.camera)
    angles = []
    for d, e in zip(case.directions, exact, strict=True):
        dm = [mpmath.mpf(float(x)) for x in d]
        c = oracle._cross_m(dm, e)
        angles.append(float(mpmath.atan2(mpmath.sqrt(oracle._mdot(c, c)), oracle._mdot(dm, e))))
    pitch = 2 * np.tan(np.radians(case.camera["fov_y"]) / 2) / case.camera["height"]
    eye_exact = all(float(a) == float(b) for a, b in zip(case.origins[0], case.camera["eye"],
                                                          strict=True))  # fmt: skip
    return {
        "camera_angle_max_rad": max(angles),
        "camera_error_pixels_max": max(angles) / pitch,
        "camera_eye_moved": float(not eye_exact),
    }


_cache: dict[int, tuple[Case, Any]] = {}


def _cached(case: Case, make: Any) -> Any:
    key = id(case)
    if key not in _cache or _cache[key][0] is not case:
        if len(_cache) > 64:
            _cache.clear()
        _cache[key] = (case, make(case))
    return _cache[key][1]


def camera(case: Case, method: Method) -> metrics.Result:
    assert isinstance(case, CameraCase)
    tru = _cached(case, lambda c: oracle.truth(c.shape, c.origins, c.directions, check_every=4))
    m, undecidable, fails = metrics.decision(case, method, tru)
    if method.name == "rtlab":
        m |= camera_error(case)
    return m, undecidable, fails
