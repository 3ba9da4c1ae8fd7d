"""Self-intersection on cylinders and tori under random transforms (issue 11: "self-intersection
for every primitive (pbrt-v4's re-intersection protocol: coordinates 10^-8 to 10^8, random
transforms)"): study/families_curved.py's protocol, with each shape placed by the scene
language's transform (non-uniform scale, rotation about a random axis by a random angle,
translation to coordinates about the knob; study/shapes.py PlacedCylinder, PlacedTorus).

Per knob value: the size in the object and a scale of about 1 (a circular cylinder, stretched
along its axis, and a torus), then the size in the transform's scale about the knob and the
object about 1 (an elliptic cylinder and a torus): the core's matrix then has entries of the
knob's size and its inverse of the reciprocal's. Points, normals, primary rays and spawned
directions are drawn in the object's coordinates as study/families_curved.py draws them and
carried into the world by the matrix (directions by its linear part: a direction leaves to the
side of the surface it left to in the object, since (A l) . (A^-T n) = l . n); each spawned ray
is judged by the exact first hit from its own spawned origin (study/metrics.py spawn()).

A family of its own, appended after every other (a family's seed is its place in FAMILIES:
study/run.py), so that the other families' rows, frozen rays and figures stay as they were."""

from __future__ import annotations

import numpy as np

from study.families import FAMILIES, Array, Case, Family, _f32, _normalize, _units
from study.families_curved import _leaving, _primary
from study.shapes import PlacedCylinder, PlacedTorus, Placement


def _placement(knob: float, scale: float, circular: bool, rng: np.random.Generator) -> Placement:
    """Scale factors of about ``scale`` (each within a factor 10^0.5 of it; x and y equal where
    ``circular``), a random axis and angle, a translation to coordinates about ``knob``."""
    s = [_f32(scale * 10.0 ** rng.uniform(-0.5, 0.5)) for _ in range(3)]
    if circular:
        s[1] = s[0]
    axis = _units(rng, 1)[0]
    return Placement(tuple(s), tuple(float(x) for x in axis), float(rng.uniform(0, 360)),  # type: ignore[arg-type]
                     tuple(_f32(x) for x in rng.uniform(-1, 1, 3) * knob))  # type: ignore[arg-type]  # fmt: skip


def _to_world(m: Array, q: Array, o: Array, leave: Array) -> tuple[Array, Array, Array]:
    """Origins on the world side, primary rays aimed at the world images of the points q, and
    the spawned directions: the object's rays carried by the matrix [A | b]."""
    a, b = m[:, :3], m[:, 3]
    qw, ow = q @ a.T + b, o @ a.T + b
    return ow, _normalize(qw - ow), _normalize(leave @ a.T)


def self_intersection_transformed(knob: float, n: int, rng: np.random.Generator) -> list[Case]:
    cases = []
    k = n // 8
    for inside in (True, False):  # the size in the object, or in the transform's scale
        size, scale = (knob, 1.0) if inside else (1.0, knob)
        # A cylinder 20 radii long, points at mid-height, inward rays nearly across the axis
        # (they leave through the side, not a cap): circular, then elliptic.
        r = _f32(size * 10.0 ** rng.uniform(-2, 0))
        cy = PlacedCylinder(r, _f32(20 * r), _placement(knob, scale, inside, rng))
        phi = rng.uniform(0, 2 * np.pi, k)
        nn = np.c_[np.cos(phi), np.sin(phi), np.zeros(k)]
        q = r * nn
        q[:, 2] = cy.height * rng.uniform(0.4, 0.6, k)
        o, _ = _primary(q, nn, 2 * r, rng)
        leave, outward = _leaving(nn, k, rng)
        leave[~outward, 2] *= 0.1
        o, d, leave = _to_world(np.asarray(cy.matrix()), q, o, _normalize(leave))
        cases.append(Case(cy, o, d, protocol="spawn", leave=leave, outward=outward))  # type: ignore[arg-type]
        # A torus, tube ratio 10^-0.5 .. 10^-2.
        big = _f32(size * 10.0 ** rng.uniform(-2, 0))
        small = _f32(big * 10.0 ** rng.uniform(-2, -0.5))
        tor = PlacedTorus(big, small, _placement(knob, scale, False, rng))
        phi, theta = rng.uniform(0, 2 * np.pi, (2, k))
        nn = np.c_[np.cos(theta) * np.cos(phi), np.cos(theta) * np.sin(phi), np.sin(theta)]
        q = np.c_[big * np.cos(phi), big * np.sin(phi), np.zeros(k)] + small * nn
        o, _ = _primary(q, nn, 2 * small, rng)
        leave, outward = _leaving(nn, k, rng)
        o, d, leave = _to_world(np.asarray(tor.matrix()), q, o, leave)
        cases.append(Case(tor, o, d, protocol="spawn", leave=leave, outward=outward))  # type: ignore[arg-type]
    return cases


# Appended after every other family (a family's seed is its place in FAMILIES: study/run.py).
FAMILIES["self-intersection-transformed"] = Family(
    "self-intersection-transformed", "coordinate scale", tuple(10.0**e for e in range(-8, 9)),
    (1e-8, 1e8), ("cylinder", "torus"), self_intersection_transformed, "self_hits",
    stiffer="both")  # fmt: skip
