"""The torus families (study/families.py lists them in FAMILIES): thin tubes with grazing rays,
and far cameras whose rays are a pinhole camera's pixel rays as POV-Ray makes them."""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from study.shapes import PinholeCamera, Torus

Array = npt.NDArray[np.float64]


def _f32(x: float) -> float:
    return float(np.float32(x))


def _units(rng: np.random.Generator, n: int) -> Array:
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1)[:, None]


def _random_torus(ratio: float, rng: np.random.Generator, size: tuple[float, float]) -> Torus:
    """A torus of major radius 10^size (uniform exponent), tube ratio ``ratio``, centred within a
    few radii of the origin; every number float32."""
    big_r = _f32(10.0 ** rng.uniform(*size))
    r = _f32(ratio * big_r)
    c = tuple(_f32(x) for x in rng.uniform(-3, 3, 3) * big_r)
    return Torus(c, big_r, r)  # type: ignore[arg-type]


def _meridian(tor: Torus, k: int, rng: np.random.Generator) -> tuple[Array, Array, Array]:
    """k points q of the tube's circle, a unit n in each one's meridian plane (the plane of the
    axis and q) and the unit m in that plane perpendicular to n."""
    phi = rng.uniform(0, 2 * math.pi, k)
    radial = np.c_[np.cos(phi), np.sin(phi), np.zeros(k)]
    q = np.array(tor.center) + tor.major_radius * radial
    gamma = rng.uniform(0, 2 * math.pi, k)
    z = np.array([0.0, 0.0, 1.0])
    n = np.cos(gamma)[:, None] * radial + np.sin(gamma)[:, None] * z
    m = -np.sin(gamma)[:, None] * radial + np.cos(gamma)[:, None] * z
    return q, n, m


def torus_tube(ratio: float, n: int, rng: np.random.Generator) -> list:
    """Tori of tube ratio r / R = ``ratio``: half the rays aimed at random points of the tube
    from outside it, half grazing it: lines in a meridian plane whose distance from the tube's
    circle is r (1 +- 2^-k), k = 1 .. 52 (issue 11's grazing rays on torus tubes)."""
    from study.families import Case

    cases = []
    for _ in range(4):
        tor = _random_torus(ratio, rng, (-2.0, 2.0))
        big_r, r = tor.major_radius, tor.minor_radius
        k = n // 4
        q, nn, m = _meridian(tor, k, rng)
        # Origins 2 .. 30 radii and 4 (R + r) beyond: no origin near the torus, where t would be
        # far below the coordinates and their rounding alone would cost it many of its ulps.
        far = big_r * 10.0 ** rng.uniform(0.3, 1.5, k) + 4 * (big_r + r)
        # Aimed at the tube point q + r n from the outward side of n.
        u = _units(rng, k)
        u = np.where((np.sum(u * nn, axis=1) < 0)[:, None], -u, u)
        target = q + r * nn
        o_aim = target + u * far[:, None]
        d_aim = target - o_aim
        # Grazing: the line through q + miss n along m, miss = r (1 +- 2^-k).
        kk = rng.integers(1, 53, k).astype(float)
        miss = r * (1 + rng.choice([-1.0, 1.0], k) * 2.0**-kk)
        side = rng.choice([-1.0, 1.0], k)[:, None]
        o_graze = q + miss[:, None] * nn - side * m * far[:, None]
        d_graze = side * m
        graze = (np.arange(k) % 2 == 1)[:, None]
        o = np.where(graze, o_graze, o_aim)
        d = np.where(graze, d_graze, d_aim)
        cases.append(Case(tor, o, d / np.linalg.norm(d, axis=1)[:, None]))
    return cases


def pixel_rays(cam: PinholeCamera, shift: tuple[float, float] = (0.0, 0.0)) -> tuple[Array, Array]:
    """The camera's pixel rays, row by row from the top, in double exactly as POV-Ray 3.7
    computes them without antialiasing (source/backend/render/tracepixel.cpp, v3.7.0.9,
    TracePixel::CreateCameraRay, PERSPECTIVE_CAMERA): the pixel's centre x = i + 0.5,
    y = j - 0.5; x0 = x / W - 0.5, y0 = ((H - 1) - y) / H - 0.5; direction = 1 D + x0 R + y0 U
    (VLinComb3, left to right); then VNormalize: times 1 / sqrt(x^2 + y^2 + z^2). ``shift``
    moves every pixel's point by that many pixels in x and in y (tests: 0, POV-Ray's rays)."""
    w, h = cam.width, cam.height
    i = np.tile(np.arange(w, dtype=np.float64), h) + shift[0]
    j = np.repeat(np.arange(h, dtype=np.float64), w) + shift[1]
    x0 = (i + 0.5) / w - 0.5
    y0 = ((h - 1) - (j - 0.5)) / h - 0.5
    dv, rv, uv = (np.array(v, dtype=np.float64) for v in (cam.direction, cam.right, cam.up))
    d = 1.0 * dv[None, :] + x0[:, None] * rv[None, :]
    d = d + y0[:, None] * uv[None, :]
    length = np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2])
    d = d * (1.0 / length)[:, None]
    o = np.tile(np.array(cam.location, dtype=np.float64), (w * h, 1))
    return o, d


def torus_distance(distance: float, n: int, rng: np.random.Generator) -> list:
    """A torus seen from ``distance`` major radii away, the field of view narrowed so that the
    torus fills it: one pinhole camera's sqrt(n) x sqrt(n) pixel rays (POV-Ray renders the same
    camera). Its major radius 10^-2.5 .. 10^-1.5 keeps every t within (1e-4, 1e7), the depths
    POV-Ray's torus accepts (DEPTH_TOLERANCE, MAX_DISTANCE in its torus.cpp): what it misses
    there is its root solver's doing, not its range."""
    from study.families import Case

    tor = _random_torus(10.0 ** rng.uniform(-2, -0.5), rng, (-2.5, -1.5))
    big_r, r = tor.major_radius, tor.minor_radius
    w = _units(rng, 1)[0]
    e1 = np.cross(w, _units(rng, 1)[0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(w, e1)
    eye = np.array(tor.center) + w * (distance * big_r)
    # The view's full width at the centre: 2.1 (R + r), over the distance.
    spread = 2.1 * (big_r + r) / (distance * big_r)
    side = round(math.sqrt(n))
    cam = PinholeCamera(tuple(float(x) for x in eye), tuple(float(x) for x in -w),  # type: ignore[arg-type]
                        tuple(float(x) for x in e1 * spread), tuple(float(x) for x in e2 * spread),  # type: ignore[arg-type]
                        side, side)  # fmt: skip
    o, d = pixel_rays(cam)
    return [Case(Torus(tor.center, big_r, r, cam), o, d)]
