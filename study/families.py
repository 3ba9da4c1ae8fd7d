"""The families of stiff cases: each a name, a knob swept over its range and a deterministic
ray generator from a seed. A generator returns Cases: one shape and a batch of rays (and, for
the protocols of self-intersection and shadows, the extra data they need)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from study.shapes import Box, Plane, Shape, Sphere, Triangle

Array = npt.NDArray[np.float64]


@dataclass(frozen=True)
class Case:
    shape: Shape
    origins: Array
    directions: Array
    #: "decision": the first hit judged against the truth; "spawn": pbrt-v4's re-intersection
    #: protocol (directions: the primary rays; leave: the spawned directions); "shadow": shadow
    #: rays from the primary hits towards ``light``; "scale": t must scale by 2^k exactly.
    protocol: str = "decision"
    leave: Array | None = None
    outward: npt.NDArray[np.bool_] | None = None  # spawn: which rays leave to the outward side
    light: tuple[float, float, float] | None = None
    scale_k: int = 0


@dataclass(frozen=True)
class Family:
    name: str
    knob: str
    values: tuple[float, ...]  # the full sweep
    quick_values: tuple[float, ...]
    primitives: tuple[str, ...]
    generate: Callable[[float, int, np.random.Generator], list[Case]] = field(repr=False)
    metric: str = "wrong_decisions"  # the one the plot shows
    log_knob: bool = True
    #: Which way the cases get harder: "up" (larger knob values), "down", or "both" ends.
    stiffer: str = "up"


def _units(rng: np.random.Generator, n: int) -> Array:
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1)[:, None]


def _perp(u: Array, rng: np.random.Generator) -> Array:
    """Unit vectors perpendicular to each row of u."""
    w = np.cross(u, _units(rng, len(u)))
    return w / np.linalg.norm(w, axis=1)[:, None]


def _normalize(d: Array) -> Array:
    return d / np.linalg.norm(d, axis=1)[:, None]


def _f32(x: float) -> float:
    """The nearest float32, as a double: scenes are float-representable so that the float
    methods (Mitsuba keeps its scene in float) are given the same scene as the double ones."""
    return float(np.float32(x))


# ------------------------------------------------------------------ (a) sphere size, distance


def sphere_distance(knob: float, n: int, rng: np.random.Generator) -> list[Case]:
    """Spheres of radius 1e-6 .. 1e6 seen from ``knob`` radii away, rays aimed at random points
    of the disc facing the eye (the silhouette is its rim) and just outside it."""
    cases = []
    radii = 10.0 ** rng.uniform(-6, 6, size=4)
    for r0 in radii:
        r = _f32(r0)
        c = tuple(_f32(x) for x in rng.uniform(-1, 1, 3) * r * 10.0 ** rng.uniform(0, 2))
        axis = _units(rng, 1)[0]
        k = n // len(radii)
        eye = np.array(c) + axis * knob * r
        side = _perp(np.tile(axis, (k, 1)), rng)
        # Half spread over the disc and past it, half near the rim (1 +- 10^-u, u up to 12).
        s = np.where(np.arange(k) % 2 == 0, rng.uniform(0, 1.2, k),
                     1 + rng.choice([-1, 1], k) * 10.0 ** -rng.uniform(1, 12, k))  # fmt: skip
        targets = np.array(c) + side * (s * r)[:, None]
        cases.append(Case(Sphere(c, r), np.tile(eye, (k, 1)), _normalize(targets - eye)))
    return cases


# ------------------------------------------------------------------------ (b) grazing rays


def grazing(knob: float, n: int, rng: np.random.Generator) -> list[Case]:
    """Rays whose line passes the centre at r (1 +- 2^-k): k = 52 is one ulp of r."""
    cases = []
    for _ in range(4):
        r = _f32(10.0 ** rng.uniform(-3, 3))
        c = tuple(_f32(x) for x in rng.uniform(-1, 1, 3) * r * 10.0 ** rng.uniform(0, 3))
        k = n // 4
        d = _units(rng, k)
        side = _perp(d, rng)
        miss = r * (1 + rng.choice([-1.0, 1.0], k) * 2.0**-knob)
        o = np.array(c) + side * miss[:, None] - d * (10 * r)
        cases.append(Case(Sphere(c, r), o, d))
    return cases


# ------------------------------------------------------------------ (c) self-intersection


def _random_shape(kind: str, scale: float, rng: np.random.Generator) -> tuple[Shape, Callable]:
    """A shape at coordinates about ``scale`` with size scale * 10^-2..1, and a function giving
    (points on it, their outward normals) for n random rays to aim at."""
    size = scale * 10.0 ** rng.uniform(-2, 0)
    centre = rng.uniform(-1, 1, 3) * scale
    if kind == "sphere":
        shape = Sphere(tuple(centre), size)

        def points(k: int) -> tuple[Array, Array]:
            u = _units(rng, k)
            return centre + size * u, u
    elif kind == "plane":
        nrm = _units(rng, 1)[0]
        shape = Plane(tuple(centre), tuple(nrm))

        def points(k: int) -> tuple[Array, Array]:
            return centre + _perp(np.tile(nrm, (k, 1)), rng) * (size * rng.uniform(0, 1, k))[
                :, None
            ], np.tile(nrm, (k, 1))
    elif kind == "triangle":
        verts = centre + _units(rng, 3) * size
        shape = Triangle(*(tuple(v) for v in verts))
        ng = np.cross(verts[1] - verts[0], verts[2] - verts[0])
        ng /= np.linalg.norm(ng)

        def points(k: int) -> tuple[Array, Array]:
            w = rng.dirichlet([1, 1, 1], k)
            return w @ verts, np.tile(ng, (k, 1))
    else:
        half = size * rng.uniform(0.2, 1, 3)
        shape = Box(tuple(centre - half), tuple(centre + half))

        def points(k: int) -> tuple[Array, Array]:
            axis = rng.integers(0, 3, k)
            sign = rng.choice([-1.0, 1.0], k)
            q = centre + rng.uniform(-0.95, 0.95, (k, 3)) * half
            q[np.arange(k), axis] = centre[axis] + sign * half[axis]
            nn = np.zeros((k, 3))
            nn[np.arange(k), axis] = sign
            return q, nn

    return shape, points


def self_intersection(knob: float, n: int, rng: np.random.Generator) -> list[Case]:
    """pbrt-v4's re-intersection protocol: hit the shape, spawn from the hit a ray leaving to
    the outward or the inward side; it must not meet the surface it leaves."""
    cases = []
    for kind in ("sphere", "plane", "triangle", "box"):
        shape, points = _random_shape(kind, knob, rng)
        k = n // 4
        q, nn = points(k)
        size = getattr(shape, "radius", None) or knob * 0.1
        # The primary rays come from the outward side, from 1 to 100 sizes away.
        back = _units(rng, k)
        back = np.where((np.sum(back * nn, axis=1) < 0)[:, None], -back, back)
        o = q + back * (size * 10.0 ** rng.uniform(0, 2, k))[:, None]
        d = _normalize(q - o)
        leave = _units(rng, k)
        outward = np.arange(k) % 2 == 0  # half leave outward, half inward
        facing = np.sum(leave * nn, axis=1) > 0
        leave = np.where((facing != outward)[:, None], -leave, leave)
        cases.append(Case(shape, o, d, protocol="spawn", leave=leave, outward=outward))
    return cases


# ----------------------------------------------------------------- (d) a light near a surface


def light_near_surface(knob: float, n: int, rng: np.random.Generator) -> list[Case]:
    """A point light at height knob (relative to the scene's size) above a plane and a sphere
    (0: exactly on the plane); shadow rays from the surface around it must reach it."""
    cases = []
    k = n // 2
    # The plane z = z0 (the normal axis-aligned, so that "exactly on" is exact).
    size = _f32(10.0 ** rng.uniform(-2, 2))
    z0 = _f32(rng.uniform(-1, 1) * size)
    foot = np.array([_f32(rng.uniform(-1, 1) * size), _f32(rng.uniform(-1, 1) * size), z0])
    light = (float(foot[0]), float(foot[1]), float(z0 + knob * size))
    q = foot + np.c_[rng.uniform(-1, 1, (k, 2)) * size, np.zeros(k)]
    q[:, 2] = z0
    o = q + _units(rng, k) * size
    o[:, 2] = z0 + np.abs(o[:, 2] - z0) + 0.1 * size  # from above
    cases.append(Case(Plane((0.0, 0.0, z0), (0.0, 0.0, 1.0)), o, _normalize(q - o),
                      protocol="shadow", light=light))  # fmt: skip
    if knob > 0:
        # A sphere, the light at (1 + knob) r along u: the points that see it lie in a cap of
        # half-angle acos(1 / (1 + knob)); aim at points within 0.9 of it.
        r = _f32(10.0 ** rng.uniform(-2, 2))
        c = np.array([_f32(x) for x in rng.uniform(-1, 1, 3) * r])
        u = _units(rng, 1)[0]
        light_s = tuple(float(x) for x in c + (1 + knob) * r * u)
        cap = math.acos(1 / (1 + knob)) if knob > 1e-8 else math.sqrt(2 * knob)
        angle = 0.9 * cap * np.sqrt(rng.uniform(0, 1, k))
        w = _perp(np.tile(u, (k, 1)), rng)
        nrm = np.cos(angle)[:, None] * u + np.sin(angle)[:, None] * w
        qs = c + r * nrm
        os_ = qs + nrm * r
        cases.append(Case(Sphere(tuple(c), r), os_, _normalize(qs - os_), protocol="shadow",
                          light=light_s))  # fmt: skip
    return cases


# --------------------------------------------------------------------- (e) scaling by 2^k


def scaling(knob: float, n: int, rng: np.random.Generator) -> list[Case]:
    """The scene and the rays' origins scaled by 2^k (directions kept): every t must scale by
    exactly 2^k. No oracle needed; the knob is k."""
    cases = []
    for kind in ("sphere", "plane", "triangle", "box"):
        shape, points = _random_shape(kind, 1.0, rng)
        k = n // 4
        q, nn = points(k)
        o = q + nn * 3 + _units(rng, k)
        cases.append(Case(shape, o, _normalize(q - o), protocol="scale", scale_k=int(knob)))
    return cases


FAMILIES: dict[str, Family] = {
    f.name: f
    for f in (
        Family(
            "sphere-distance",
            "distance / radius",
            tuple(10.0**e for e in range(1, 11)),
            (10.0, 1e5, 1e10),
            ("sphere",),
            sphere_distance,
            # Where the two roots are well apart: near-tangent rays' t is ill-conditioned for
            # every method (the problem's own), and would hide the formulas' difference.
            "t_error_ulps_max_separated",
        ),
        Family(
            "grazing",
            "k (miss distance r(1 +- 2^-k))",
            tuple(float(k) for k in range(1, 53)),
            (4.0, 20.0, 40.0, 52.0),
            ("sphere",),
            grazing,
        ),
        Family(
            "self-intersection",
            "coordinate scale",
            tuple(10.0**e for e in range(-8, 9)),
            (1e-8, 1.0, 1e8),
            ("sphere", "plane", "triangle", "box"),
            self_intersection,
            "self_hits",
            stiffer="both",
        ),
        Family(
            "light-near-surface",
            "light height (relative)",
            (0.0, *(10.0**e for e in range(-15, 0))),
            (0.0, 1e-15, 1e-8, 1e-3),
            ("plane", "sphere"),
            light_near_surface,
            "false_occlusions",
            stiffer="down",
        ),
        Family(
            "scaling",
            "k (scene scaled by 2^k)",
            tuple(float(k) for k in range(-20, 21)),
            (-20.0, 0.0, 20.0),
            ("sphere", "plane", "triangle", "box"),
            scaling,
            "scale_mismatches",
            log_knob=False,
            stiffer="both",
        ),
    )
}
