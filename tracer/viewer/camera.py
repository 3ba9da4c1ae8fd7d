"""The viewer's camera moves, on the scene's look-at camera (eye, look_at, up).

Orbit turns the eye about look_at (the distance stays), pan slides both along the image plane
(a point on the plane through look_at follows the mouse), zoom moves the eye along the view
direction towards look_at, walk moves both (WASD). The scene's ``up`` is kept: the orbit turns
about it and stops short of its poles, where the camera's basis (03_camera.h: right = forward x
up) would degenerate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: How close (radians) an orbit may bring the view direction to +-up: the basis stays defined.
POLE_MARGIN = math.radians(1.0)
#: The nearest the eye may come to look_at, as a share of the distance the scene's file gave:
#: a zoom never passes through look_at (the view direction would flip).
MIN_DISTANCE_SHARE = 1e-3


@dataclass(frozen=True)
class View:
    eye: tuple[float, float, float]
    look_at: tuple[float, float, float]
    up: tuple[float, float, float]

    @property
    def distance(self) -> float:
        return float(np.linalg.norm(np.subtract(self.eye, self.look_at)))

    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """forward, right, true up: the camera's frame as 03_camera.h builds it."""
        forward = np.subtract(self.look_at, self.eye, dtype=np.float64)
        forward /= np.linalg.norm(forward)
        right = np.cross(forward, self.up)
        right /= np.linalg.norm(right)
        return forward, right, np.cross(right, forward)


def _tuple(v: np.ndarray) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))


def _rotate(v: np.ndarray, axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues' rotation of v about the unit axis by angle (radians, right-handed)."""
    c, s = math.cos(angle), math.sin(angle)
    return v * c + np.cross(axis, v) * s + axis * np.dot(axis, v) * (1 - c)


def orbit(view: View, yaw: float, pitch: float) -> View:
    """Turn the eye about look_at: ``yaw`` radians about up (positive: counter-clockwise seen
    from above, from +up), then ``pitch`` radians
    about the camera's right vector (positive: the eye rises), the angle to up kept within
    [POLE_MARGIN, pi - POLE_MARGIN]. The distance to look_at is unchanged."""
    up = np.asarray(view.up, dtype=np.float64)
    up = up / np.linalg.norm(up)
    centre = np.asarray(view.look_at, dtype=np.float64)
    offset = _rotate(np.subtract(view.eye, centre, dtype=np.float64), up, yaw)
    r = float(np.linalg.norm(offset))
    polar = math.acos(max(-1.0, min(1.0, float(np.dot(offset, up)) / r)))
    target = max(POLE_MARGIN, min(math.pi - POLE_MARGIN, polar - pitch))
    right = np.cross(up, offset)  # horizontal, perpendicular to the offset
    if np.linalg.norm(right) > 0:
        # Rotating about up x offset by +a moves the offset away from up (Rodrigues: the
        # term (k x v) sin a, with (up x v) x v pointing down): the polar angle grows by a.
        offset = _rotate(offset, right / np.linalg.norm(right), target - polar)
    return View(_tuple(centre + offset), view.look_at, view.up)


def pan(view: View, dx: float, dy: float, fov_y: float, height: int) -> View:
    """Slide eye and look_at together by a mouse move of (dx, dy) pixels (y down, as on the
    screen) in an image ``height`` pixels tall: the scene point at look_at's depth under the
    mouse stays under it (the image plane at that depth is 2 d tan(fov_y / 2) tall)."""
    _, right, true_up = view.basis()
    per_pixel = 2 * view.distance * math.tan(math.radians(fov_y) / 2) / height
    move = (-dx * right + dy * true_up) * per_pixel
    return View(_tuple(np.add(view.eye, move)), _tuple(np.add(view.look_at, move)), view.up)


def zoom(view: View, factor: float, min_distance: float = 0.0) -> View:
    """Scale the eye's distance to look_at by ``factor`` (below 1: closer) along the view
    direction; never nearer than ``min_distance``."""
    if not factor > 0:
        raise ValueError(f"zoom factor must be positive, got {factor}")
    d = view.distance
    new = max(d * factor, min_distance, 1e-9)
    offset = np.subtract(view.eye, view.look_at, dtype=np.float64) * (new / d)
    return View(_tuple(np.add(view.look_at, offset)), view.look_at, view.up)


def walk(view: View, forward: float, right: float, lift: float) -> View:
    """Move eye and look_at together: ``forward`` along the view direction, ``right`` along
    the camera's right vector, ``lift`` along up (world units)."""
    f, r, _ = view.basis()
    up = np.asarray(view.up, dtype=np.float64)
    move = forward * f + right * r + lift * up / np.linalg.norm(up)
    return View(_tuple(np.add(view.eye, move)), _tuple(np.add(view.look_at, move)), view.up)
