"""The families of stiff cases: each a name, a knob swept over its range and a deterministic
ray generator from a seed. A generator returns Cases: one shape and a batch of rays (and, for
the protocols of self-intersection and shadows, the extra data they need)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np
import numpy.typing as npt

from study.shapes import Box, Mesh, Plane, Shape, Sphere, Triangle, Vec, as_mesh

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


# ----------------------------------------------------------- (f) triangles, slivers, meshes
# The rays aimed at a point p of a triangle (a vertex, a point of an edge: exact rationals) get
# d = p - o computed exactly and then rounded: the ray as a renderer would be given it.


def _aim(o: Array, targets: list[tuple[Fraction, Fraction, Fraction]]) -> Array:
    """Directions from each origin (doubles) to each exact target, rounded once."""
    return np.array([[float(p[k] - Fraction(float(o[i, k]))) for k in range(3)]
                     for i, p in enumerate(targets)])  # fmt: skip


def _on_edge(a: Vec, b: Vec, s: Fraction) -> tuple[Fraction, Fraction, Fraction]:
    return tuple(Fraction(a[k]) + s * (Fraction(b[k]) - Fraction(a[k])) for k in range(3))  # type: ignore[return-value]


def _triangle_rays(tri: Triangle, k: int, size: float, rng: np.random.Generator,
                   grazing: bool = True) -> tuple[Array, Array]:  # fmt: skip
    """k rays at a triangle: 40% at random interior points, 20% exactly at a vertex, 30%
    exactly at a point of an edge, 10% nearly in its plane (10^-1 .. 10^-15 radians off it)."""
    verts = [tri.a, tri.b, tri.c]
    v = np.array(verts)
    ng = np.cross(v[1] - v[0], v[2] - v[0])
    norm = np.linalg.norm(ng)
    ng = ng / norm if norm > 0 else _units(rng, 1)[0]
    o = v.mean(axis=0) + _units(rng, k) * (size * 10.0 ** rng.uniform(0, 2, k))[:, None]
    targets: list = []
    kinds = rng.choice(4, size=k, p=[0.4, 0.2, 0.3, 0.1] if grazing else [0.45, 0.2, 0.35, 0.0])
    for i, kind in enumerate(kinds):
        if kind == 0:
            w = rng.dirichlet([1, 1, 1])
            targets.append(tuple(Fraction(float(x)) for x in w @ v))
        elif kind == 1:
            targets.append(tuple(Fraction(x) for x in verts[rng.integers(3)]))
        elif kind == 2:
            j = int(rng.integers(3))
            s = Fraction(int(rng.integers(1, 1024)), 1024)
            targets.append(_on_edge(verts[j], verts[(j + 1) % 3], s))
        else:
            w = rng.dirichlet([1, 1, 1])
            q = w @ v
            inplane = _perp(ng[None, :], rng)[0]
            dd = inplane + ng * 10.0 ** -rng.uniform(1, 15) * rng.choice([-1, 1])
            o[i] = q - dd * size * 10.0 ** rng.uniform(0, 2)
            targets.append(tuple(Fraction(float(x)) for x in q))
    return o, _aim(o, targets)


def triangles(knob: float, n: int, rng: np.random.Generator) -> list[Case]:
    """Triangles at ``knob`` from the origin (size knob 10^-4 .. 1, at least 1e-3), rays at
    their interior, exactly at vertices and edges, and nearly in their plane."""
    cases = []
    for _ in range(4):
        centre = _units(rng, 1)[0] * knob
        size = max(knob * 10.0 ** -rng.uniform(0, 4), 1e-3)
        verts = [tuple(_f32(x) for x in centre + size * u) for u in _units(rng, 3)]
        tri = Triangle(*verts)  # type: ignore[arg-type]
        o, d = _triangle_rays(tri, n // 8, size, rng)
        cases.append(Case(tri, o, d))
    return cases


def slivers(knob: float, n: int, rng: np.random.Generator) -> list[Case]:
    """Slivers of aspect ``knob`` (height / base; 0: zero-area, three collinear vertices or two
    coinciding): rays at their interior, vertices and edges. Coordinates are dyadic (a few
    bits) so that the collinear ones are exactly collinear."""
    cases = []
    for j in range(4):
        base = 2.0 ** int(rng.integers(-4, 5))
        a = np.array([float(int(rng.integers(-64, 64))) * base / 8 for _ in range(3)])
        u = _units(rng, 1)[0]
        e = np.array([float(np.float32(x)) for x in u]) * base * 4  # exact sums with a
        b = a + e
        if knob == 0:
            c = a + e * 0.375 if j % 2 == 0 else a.copy()
        else:
            h = _perp(u[None, :], rng)[0]
            c = a + e * rng.uniform(0, 1) + h * (knob * base * 4)
        tri = Triangle(tuple(a), tuple(b), tuple(c))  # type: ignore[arg-type]
        o, d = _triangle_rays(tri, n // 8, base * 4, rng, grazing=False)
        if knob == 0:
            # Every ray above passes through the segment (undecidable: a one-ulp move of a
            # vertex gives it an area); half of them are moved off it by 10^-3 .. 10^-12 of its
            # length, sideways: decidable misses, a hit reported there is wrong.
            half = np.arange(len(d)) % 2 == 0
            side = np.cross(d, e)
            side /= np.linalg.norm(side, axis=1)[:, None]
            off = (base * 4 * 10.0 ** -rng.uniform(3, 12, len(d)))[:, None]
            d = np.where(half[:, None], d + side * off, d)
        cases.append(Case(tri, o, d))
    return cases


def icosahedron(radius: float, centre: Array) -> Mesh:
    """A closed icosahedron (12 vertices, 20 faces counter-clockwise from outside)."""
    g = (1 + math.sqrt(5)) / 2
    raw = [(-1, g, 0), (1, g, 0), (-1, -g, 0), (1, -g, 0), (0, -1, g), (0, 1, g), (0, -1, -g),
           (0, 1, -g), (g, 0, -1), (g, 0, 1), (-g, 0, -1), (-g, 0, 1)]  # fmt: skip
    s = radius / math.sqrt(1 + g * g)
    verts = tuple(tuple(float(centre[k] + s * p[k]) for k in range(3)) for p in raw)
    faces = ((0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1))  # fmt: skip
    return Mesh(verts, faces)  # type: ignore[arg-type]


def _rotated_cube(size: float, centre: Array, rng: np.random.Generator) -> Mesh:
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    cube = as_mesh(Box((-size, -size, -size), (size, size, size)))
    verts = tuple(tuple(float(x) for x in centre + q @ np.array(v)) for v in cube.vertices)
    return Mesh(verts, cube.faces)  # type: ignore[arg-type]


def _into(mesh: Mesh, faces: list[int], rng: np.random.Generator) -> Array:
    """A unit vector u with u . n > 0.2 for each of the faces' outward normals: a ray coming
    from p + u L towards p on those faces enters the (convex) solid there."""
    v = np.array(mesh.vertices)
    ns = []
    for f in faces:
        a, b, c = (v[i] for i in mesh.faces[f])
        nn = np.cross(b - a, c - a)
        ns.append(nn / np.linalg.norm(nn))
    mean = np.mean(ns, axis=0)
    mean /= np.linalg.norm(mean)
    while True:
        u = mean + 0.6 * _units(rng, 1)[0]
        u /= np.linalg.norm(u)
        if all(u @ nn > 0.2 for nn in ns):
            return u


def mesh_leaks(knob: float, n: int, rng: np.random.Generator) -> list[Case]:
    """A closed icosahedron and a rotated cube of radius 1 at ``knob`` from the origin (their
    vertices in double: a float method rounds them, which is part of its error), rays aimed
    exactly through their vertices and edges from directions that enter the solid there: the
    truth is a hit, a miss is a leak."""
    cases = []
    for j in range(2):
        centre = _units(rng, 1)[0] * knob
        mesh = icosahedron(1.0, centre) if j == 0 else _rotated_cube(0.5, centre, rng)
        k = n // 8
        targets, o = [], np.zeros((k, 3))
        for i in range(k):
            f = int(rng.integers(len(mesh.faces)))
            face = mesh.faces[f]
            if i % 2 == 0:  # a vertex: every face around it
                vi = face[int(rng.integers(3))]
                p = tuple(Fraction(x) for x in mesh.vertices[vi])
                around = [g for g, fc in enumerate(mesh.faces) if vi in fc]
            else:  # a point of an edge: its two faces
                e = int(rng.integers(3))
                a, b = face[e], face[(e + 1) % 3]
                p = _on_edge(mesh.vertices[a], mesh.vertices[b],
                             Fraction(int(rng.integers(1, 1024)), 1024))  # fmt: skip
                around = [g for g, fc in enumerate(mesh.faces) if a in fc and b in fc]
            u = _into(mesh, around, rng)
            o[i] = np.array([float(x) for x in p]) + u * 10.0 ** rng.uniform(0.3, 1.3)
            targets.append(p)
        cases.append(Case(mesh, o, _aim(o, targets)))
    return cases


# ------------------------------------------------------------------------------- (g) boxes


def boxes(knob: float, n: int, rng: np.random.Generator) -> list[Case]:
    """Axis-aligned boxes at coordinate scale ``knob``: rays with +-0.0 direction components
    (origins inside a slab, or exactly on a face's plane), origins exactly on a face, rays
    exactly through edges and corners from directions entering the box there."""
    cases = []
    for _ in range(2):
        centre = rng.uniform(-1, 1, 3) * knob
        half = knob * 10.0 ** rng.uniform(-2, 0, 3)
        lo = tuple(_f32(x) for x in centre - half)
        hi = tuple(_f32(x) for x in centre + half)
        box = Box(lo, hi)  # type: ignore[arg-type]
        lo_a, hi_a = np.array(lo), np.array(hi)
        k = n // 4
        o = np.zeros((k, 3))
        targets: list = []
        for i in range(k):
            kind = i % 4
            inside = lo_a + (hi_a - lo_a) * rng.uniform(0.05, 0.95, 3)
            if kind in (0, 1):
                # Zero components (their signs random): 0, the origin strictly inside those
                # slabs; 1, exactly on one of their face planes.
                zeros = rng.choice(3, size=int(rng.integers(1, 3)), replace=False)
                d = _units(rng, 1)[0]
                d[zeros] = rng.choice([0.0, -0.0], size=len(zeros))
                start = inside - d * (hi_a - lo_a).max() * 3
                start[zeros] = inside[zeros]
                if kind == 1:
                    z = zeros[0]
                    start[z] = lo_a[z] if rng.integers(2) else hi_a[z]
                o[i] = start
                targets.append(None)
                cases_d = d
            elif kind == 2:
                # The origin exactly on a face, the direction random (into or out of the box).
                ax = int(rng.integers(3))
                start = inside.copy()
                start[ax] = lo_a[ax] if rng.integers(2) else hi_a[ax]
                o[i] = start
                cases_d = _units(rng, 1)[0]
                targets.append(None)
            else:
                # Exactly through a corner or a point of an edge, entering the box there.
                corner = np.where(rng.integers(0, 2, 3) > 0, hi_a, lo_a)
                p = [Fraction(float(x)) for x in corner]
                if rng.integers(2):  # an edge: one coordinate free
                    ax = int(rng.integers(3))
                    p[ax] = Fraction(float(inside[ax]))
                out = np.where(corner == hi_a, 1.0, -1.0)
                u = out * rng.uniform(0.2, 1, 3)
                u /= np.linalg.norm(u)
                o[i] = np.array([float(x) for x in p]) + u * (hi_a - lo_a).max() * 2
                targets.append(tuple(p))
                cases_d = None
            if targets[-1] is None:
                targets[-1] = cases_d
        d = np.array([_aim(o[i : i + 1], [t])[0] if isinstance(t, tuple) else t
                      for i, t in enumerate(targets)])  # fmt: skip
        cases.append(Case(box, o, d))
    return cases


FAMILIES.update({
    f.name: f
    for f in (
        Family("triangles", "distance from the origin", tuple(10.0**e for e in range(0, 9)),
               (1.0, 1e4, 1e8), ("triangle",), triangles),
        Family("slivers", "aspect (height / base; 0: zero area)",
               (0.0, *(10.0**-e for e in range(8, -1, -1))), (0.0, 1e-8, 1e-2),
               ("triangle",), slivers, stiffer="down"),
        Family("mesh-leaks", "distance / mesh radius", tuple(10.0**e for e in range(0, 9)),
               (1.0, 1e4, 1e8), ("mesh",), mesh_leaks, "leaks"),
        Family("boxes", "coordinate scale", tuple(10.0**e for e in range(-8, 9)),
               (1e-8, 1.0, 1e8), ("box",), boxes, stiffer="both"),
    )
})  # fmt: skip


# Issue 11's scene families (nearly touching surfaces, mirror chains, grazing cylinders) add
# themselves to FAMILIES: study/families_scenes.py.
from study import families_scenes  # noqa: E402, F401

# ------------------------------------------------------------------------------- (h) tori
from study.families_torus import torus_distance, torus_tube  # noqa: E402

FAMILIES.update({
    f.name: f
    for f in (
        Family("torus-tube", "tube ratio r / R", tuple(10.0**-e for e in range(1, 9)),
               (1e-1, 1e-8), ("torus",), torus_tube, stiffer="down"),
        Family("torus-distance", "camera distance / R", tuple(10.0**e for e in range(1, 9)),
               (10.0, 1e8), ("torus",), torus_distance),
    )
})  # fmt: skip

# Self-intersection on cylinders and tori (last: the seeds go by place): study/families_curved.py.
from study import families_curved  # noqa: E402, F401
