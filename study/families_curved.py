"""Self-intersection on the curved primitives the first family leaves out (issue 11: "for every
primitive"): pbrt-v4's re-intersection protocol (study/families.py self_intersection()) on
capped cylinders and on tori, at coordinates 10^-8 to 10^8.

A torus is not convex: a ray leaving it outward may meet it again elsewhere, and one leaving
inward leaves the tube through its far side. So a spawned ray is judged against the exact first
hit from its own spawned origin (study/metrics.py spawn(), TRUTH_JUDGED). The cylinder is judged
the same way; its rays stay clear of the caps (points at mid-height, inward rays nearly
perpendicular to the axis), so Mitsuba's uncapped cylinder traces the same surface there."""

from __future__ import annotations

import numpy as np

from study.families import FAMILIES, Array, Case, Family, _f32, _normalize, _units
from study.shapes import Cylinder, Torus


def _leaving(nn: Array, k: int, rng: np.random.Generator) -> tuple[Array, Array]:
    """k directions, half leaving to the outward side of the normals nn and half inward, each
    at least 0.3 from the tangent plane (so that the side they leave to is the same for a hit a
    little away from the aimed point), and which of them leave outward."""
    leave = _units(rng, k)
    along = np.sum(leave * nn, axis=1)
    leave = _normalize(leave + nn * (np.sign(along) * 0.35)[:, None])
    outward = np.arange(k) % 2 == 0
    facing = np.sum(leave * nn, axis=1) > 0
    return np.where((facing != outward)[:, None], -leave, leave), outward


def _primary(q: Array, nn: Array, reach: float, rng: np.random.Generator) -> tuple[Array, Array]:
    """Rays from the outward side onto the points q, within about 18 degrees of the normal and
    from at most ``reach`` away (a torus: less than its hole, so no other part lies between)."""
    back = _normalize(nn + 0.3 * _units(rng, len(q)))
    o = q + back * (reach * rng.uniform(0.1, 1, len(q)))[:, None]
    return o, _normalize(q - o)


def self_intersection_curved(knob: float, n: int, rng: np.random.Generator) -> list[Case]:
    cases = []
    k = n // 4
    for _ in range(2):
        # A cylinder along a coordinate axis (the core's frame is then exact, as in
        # study/families_scenes.py), 20 radii long; points at mid-height.
        r = _f32(knob * 10.0 ** rng.uniform(-2, 0))
        axis = int(rng.integers(0, 3))
        base = np.array([_f32(x) for x in rng.uniform(-1, 1, 3) * knob])
        top = base.copy()
        top[axis] = _f32(base[axis] + 20 * r)
        phi = rng.uniform(0, 2 * np.pi, k)
        u, v = (axis + 1) % 3, (axis + 2) % 3
        nn = np.zeros((k, 3))
        nn[:, u], nn[:, v] = np.cos(phi), np.sin(phi)
        q = base + r * nn
        q[:, axis] = base[axis] + (top[axis] - base[axis]) * rng.uniform(0.4, 0.6, k)
        o, d = _primary(q, nn, 2 * r, rng)
        leave, outward = _leaving(nn, k, rng)
        # Inward rays nearly across the axis: they leave through the side, not a cap.
        leave[~outward, axis] *= 0.1
        leave = _normalize(leave)
        cases.append(Case(Cylinder(tuple(base), tuple(top), r), o, d, protocol="spawn",
                          leave=leave, outward=outward))  # fmt: skip
        # A torus around z, tube ratio 10^-0.5 .. 10^-2.
        big = _f32(knob * 10.0 ** rng.uniform(-2, 0))
        small = _f32(big * 10.0 ** rng.uniform(-2, -0.5))
        c = np.array([_f32(x) for x in rng.uniform(-1, 1, 3) * knob])
        phi, theta = rng.uniform(0, 2 * np.pi, (2, k))
        nn = np.c_[np.cos(theta) * np.cos(phi), np.cos(theta) * np.sin(phi), np.sin(theta)]
        ring = np.c_[big * np.cos(phi), big * np.sin(phi), np.zeros(k)]
        q = c + ring + small * nn
        o, d = _primary(q, nn, 2 * small, rng)
        leave, outward = _leaving(nn, k, rng)
        cases.append(Case(Torus(tuple(c), big, small), o, d, protocol="spawn", leave=leave,
                          outward=outward))  # fmt: skip
    return cases


# Appended after every other family (a family's seed is its place in FAMILIES: study/run.py).
FAMILIES["self-intersection-curved"] = Family(
    "self-intersection-curved", "coordinate scale", tuple(10.0**e for e in range(-8, 9)),
    (1e-8, 1e8), ("cylinder", "torus"), self_intersection_curved, "self_hits",
    stiffer="both")  # fmt: skip

# Self-intersection on cylinders and tori under random transforms, appended after this family
# (imported here, after it is in FAMILIES, so that the order is fixed): study/families_placed.py.
from study import families_placed  # noqa: E402, F401
