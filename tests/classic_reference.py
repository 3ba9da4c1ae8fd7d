"""An independent, deliberately plain implementation of the classic model, for cross-checks.

Written from the issue's text, not from the C++ core: textbook quadratic, vectors as numpy
arrays, a relative epsilon for secondary and shadow ray origins. Slow (pure Python per pixel),
so only for small images of well-conditioned scenes, where its simpler numerics are exact
enough: any difference from the core there is a bug in one of the two.
"""

from __future__ import annotations

import math

import numpy as np

from tracer.scene import DirectionalLight, Plane, Scene, Sphere

EPS = 1e-12
# Secondary and shadow rays start this far (relative) off the surface: far above the ~1e-15
# rounding of the hit point, small enough not to move shading by more than ~1e-9.
OFFSET = 1e-10


def _hit_sphere(obj: Sphere, o: np.ndarray, d: np.ndarray) -> float:
    f = o - np.array(obj.center)
    b = float(np.dot(f, d))
    c = float(np.dot(f, f)) - obj.radius**2
    disc = b * b - c  # d is unit length
    if disc < 0:
        return math.inf
    s = math.sqrt(disc)
    for t in (-b - s, -b + s):
        if t > EPS:
            return t
    return math.inf


def _hit_plane(obj: Plane, o: np.ndarray, d: np.ndarray) -> float:
    n = np.array(obj.normal)
    denom = float(np.dot(d, n))
    if denom == 0:
        return math.inf
    t = float(np.dot(np.array(obj.point) - o, n)) / denom
    return t if t > EPS else math.inf


def _closest(scene: Scene, o: np.ndarray, d: np.ndarray) -> tuple[float, int]:
    best, index = math.inf, -1
    for i, obj in enumerate(scene.objects):
        t = _hit_sphere(obj, o, d) if isinstance(obj, Sphere) else _hit_plane(obj, o, d)
        if t < best:
            best, index = t, i
    return best, index


def trace(scene: Scene, o: np.ndarray, d: np.ndarray) -> np.ndarray:
    color = np.zeros(3)
    coef = 1.0
    for _level in range(scene.render.max_depth):
        if coef < scene.render.min_coefficient:
            break
        t, i = _closest(scene, o, d)
        if i < 0:
            color += coef * np.array(scene.render.background)
            break
        obj = scene.objects[i]
        m = scene.materials[obj.material]
        p = o + t * d
        if isinstance(obj, Sphere):
            n = (p - np.array(obj.center)) / obj.radius
        else:
            n = np.array(obj.normal)
        if np.dot(n, d) > 0:
            n = -n
        r = d - 2 * np.dot(d, n) * n
        mc = np.array(m.color)
        local = mc * m.ambient * np.array(scene.render.ambient_light)
        start = p + n * OFFSET * (1 + np.abs(p).max())
        for light in scene.lights:
            if isinstance(light, DirectionalLight):
                L = -np.array(light.direction)
                dist = math.inf
            else:
                v = np.array(light.position) - p
                dist = float(np.linalg.norm(v))
                L = v / dist
            nl = float(np.dot(n, L))
            if nl <= 0:
                continue
            tb, _ = _closest(scene, start, L)
            if tb < dist:
                continue
            lc = np.array(light.color)
            local = local + m.diffuse * mc * lc * nl
            rl = float(np.dot(r, L))
            if rl > 0:
                local = local + m.specular * lc * rl**m.shininess
        color += coef * local
        coef *= m.reflectivity
        if m.reflectivity == 0:
            break
        o, d = start if np.dot(r, n) > 0 else p - n * OFFSET * (1 + np.abs(p).max()), r
    return color


def render(scene: Scene) -> np.ndarray:
    cam = scene.camera
    eye, at, up = (np.array(v, dtype=float) for v in (cam.eye, cam.look_at, cam.up))
    fwd = (at - eye) / np.linalg.norm(at - eye)
    right = np.cross(fwd, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, fwd)
    h = 2 * math.tan(math.radians(cam.fov_y) / 2)
    w = h * cam.width / cam.height
    image = np.zeros((cam.height, cam.width, 3))
    for j in range(cam.height):
        for i in range(cam.width):
            x = (i + 0.5) / cam.width - 0.5
            y = 0.5 - (j + 0.5) / cam.height
            d = fwd + x * w * right + y * h * true_up
            image[j, i] = trace(scene, eye, d / np.linalg.norm(d))
    return image
