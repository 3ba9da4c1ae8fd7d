"""Small vector helpers on plain tuples, and the rotation matrix of a transform."""

from __future__ import annotations

import math

import numpy as np

Vec3 = tuple[float, float, float]
Color = tuple[float, float, float]


def sub(a: Vec3, b: Vec3) -> Vec3:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a: Vec3, b: Vec3) -> Vec3:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def norm(a: Vec3) -> float:
    return math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


def unit(a: Vec3) -> Vec3:
    n = norm(a)
    if not 0 < n < math.inf:  # its square under- or overflowed: scale it to ~1 first
        big = max(abs(a[0]), abs(a[1]), abs(a[2]))
        a = (a[0] / big, a[1] / big, a[2] / big)
        n = norm(a)
    return (a[0] / n, a[1] / n, a[2] / n)


def rotation(axis: Vec3, degrees: float) -> np.ndarray:
    """Rodrigues' rotation matrix: right-handed, counter-clockwise looking down the axis."""
    k = np.asarray(axis, dtype=np.float64) / np.linalg.norm(axis)
    a = np.radians(degrees)
    cross_k = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) * np.cos(a) + np.sin(a) * cross_k + (1 - np.cos(a)) * np.outer(k, k)
