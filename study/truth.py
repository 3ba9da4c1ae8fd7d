"""Ground truth from the scene description and the ray alone, never from a method's values.

Every double is a rational number, so what a ray meets is decided exactly: a sphere's
discriminant sign, a plane's, triangle's or box's parameter t are rational functions of the
inputs, computed with fractions.Fraction (route 1). A sphere's t needs a square root: mpmath at
DIGITS significant digits, of the exact discriminant. Route 2 recomputes each answer another way
in mpmath alone (the sphere from the centre's distance to the line, the triangle from signed
volumes, the box face by face) at the same precision; the two must agree or TruthError is raised.

Conditioning: a ray whose exact answer flips when its origin and direction components move by
one ulp (PERTURBATIONS, evaluated exactly) cannot be decided by any double-precision method; such
rays are counted apart (``undecidable``), never silently excused."""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction

import mpmath
import numpy as np
import numpy.typing as npt

from study import truth_torus
from study.shapes import Box, Mesh, Plane, Shape, Sphere, Torus, Triangle

#: Significant digits of the square roots and of route 2; far beyond the 17 of a double, so
#: rounding the truth's t to the nearest double is exact whenever route 1 and 2 agree.
DIGITS = 120
mpmath.mp.dps = DIGITS
#: Relative agreement the two routes must reach for t (they round differently at 120 digits;
#: 1e-60 leaves 60 digits for the square root's amplification near a tangent).
AGREE = mpmath.mpf("1e-60")

#: The one-ulp moves of (ox, oy, oz, dx, dy, dz) tried for a ray's conditioning: all up, all
#: down, and the two alternations (a few deterministic ones, the same for every method).
PERTURBATIONS = ((1,) * 6, (-1,) * 6, (1, -1) * 3, (-1, 1) * 3)
#: The same four patterns on a vertex's three coordinates.
PERTURBATIONS_3 = tuple(p[:3] for p in PERTURBATIONS)

Vec = tuple[Fraction, Fraction, Fraction]


class TruthError(AssertionError):
    """The two routes to the truth disagree: the study's oracle is broken, not a method."""


def _v(p: npt.ArrayLike) -> Vec:
    a = np.asarray(p, dtype=np.float64)
    return (Fraction(float(a[0])), Fraction(float(a[1])), Fraction(float(a[2])))


def _sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _dot(a: Vec, b: Vec) -> Fraction:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _cross(a: Vec, b: Vec) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _mpf(x: Fraction) -> mpmath.mpf:
    return mpmath.mpf(x.numerator) / x.denominator


# ------------------------------------------------------------------------------------ route 1
# The first hit t in (0, tmax) of the ray (o, d), exact: (hit, t) with t a Fraction or, for a
# sphere, an mpmath number from the exact discriminant; (False, None) on a miss.


def _sphere1(s: Sphere, o: Vec, d: Vec, tmax: float) -> tuple[bool, object]:
    f = _sub(o, _v(s.center))
    a, b = _dot(d, d), _dot(f, d)
    c0 = _dot(f, f) - Fraction(s.radius) ** 2
    disc = b * b - a * c0
    if disc < 0:
        return False, None
    # Which roots are positive, decided exactly (no square root): t0 > 0 iff b < 0 and c0 > 0;
    # t1 > 0 iff b < 0 or c0 < 0 (Vieta: t0 t1 = c0 / a, t0 + t1 = -2 b / a).
    root = mpmath.sqrt(_mpf(disc))
    for positive, sign in ((b < 0 and c0 > 0, -1), (b < 0 or c0 < 0, 1)):
        if positive:
            t = (-_mpf(b) + sign * root) / _mpf(a)
            if t < tmax:
                return True, t
            return False, None
    return False, None


def _plane1(pl: Plane, o: Vec, d: Vec, tmax: float) -> tuple[bool, object]:
    n = _v(pl.normal)
    den = _dot(d, n)
    if den == 0:
        return False, None
    t = _dot(_sub(_v(pl.point), o), n) / den
    return (True, t) if 0 < t < tmax else (False, None)


def _triangle1(tr: Triangle, o: Vec, d: Vec, tmax: float) -> tuple[bool, object]:
    # Cramer's rule on o + t d = a + u e1 + v e2; edges and vertices count as the triangle's.
    a = _v(tr.a)
    e1, e2, s = _sub(_v(tr.b), a), _sub(_v(tr.c), a), _sub(o, a)
    nd = (-d[0], -d[1], -d[2])
    den = _dot(e1, _cross(e2, nd))
    if den == 0:
        return False, None
    u = _dot(s, _cross(e2, nd)) / den
    v = _dot(e1, _cross(s, nd)) / den
    t = _dot(e1, _cross(e2, s)) / den
    if u >= 0 and v >= 0 and u + v <= 1 and 0 < t < tmax:
        return True, t
    return False, None


def _box1(bx: Box, o: Vec, d: Vec, tmax: float) -> tuple[bool, object]:
    lo, hi = _v(bx.lo), _v(bx.hi)
    near: Fraction | None = None
    far: Fraction | None = None
    for k in range(3):
        if d[k] == 0:
            if not lo[k] <= o[k] <= hi[k]:
                return False, None
            continue
        t1, t2 = (lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]
        t1, t2 = min(t1, t2), max(t1, t2)
        near = t1 if near is None else max(near, t1)
        far = t2 if far is None else min(far, t2)
    if near is None or far is None or near > far:
        return False, None
    for t in (near, far):  # entering, or from inside: leaving
        if t > 0:
            return (True, t) if t < tmax else (False, None)
    return False, None


def _mesh1(me: Mesh, o: Vec, d: Vec, tmax: float) -> tuple[bool, object]:
    # The nearest of the triangles' exact hits: a ray through a shared edge or vertex meets
    # every triangle around it there (edges count as each triangle's), at the same t.
    best: Fraction | None = None
    od = np.array([float(x) for x in o]), np.array([float(x) for x in d])
    for tr in me.triangles():
        # Integer arithmetic first (the same decision, exact), Fractions for the hits' t.
        if tmax == math.inf and not _triangle_hits([tr.a, tr.b, tr.c], *od):
            continue
        h, t = _triangle1(tr, o, d, tmax)
        if h and (best is None or t < best):
            best = t
    return (True, best) if best is not None else (False, None)


_ROUTE1 = {"sphere": _sphere1, "plane": _plane1, "triangle": _triangle1, "box": _box1,
           "mesh": _mesh1}  # fmt: skip
_ROUTE1 |= dict.fromkeys(("torus", "torus-camera"), truth_torus.first_root)  # study/truth_torus.py


# ------------------------------------------------------------------------------------ route 2


def _m(p: npt.ArrayLike) -> mpmath.matrix:
    a = np.asarray(p, dtype=np.float64)
    return [mpmath.mpf(float(x)) for x in a]


def _mdot(a: list, b: list) -> mpmath.mpf:
    return mpmath.fsum(x * y for x, y in zip(a, b, strict=True))


def _sphere2(s: Sphere, o: list, d: list, tmax: float) -> tuple[bool, object, mpmath.mpf]:
    # The centre's distance h to the line and the half chord sqrt(r^2 - h^2) (geometry, not the
    # quadratic's coefficients).
    c = _m(s.center)
    f = [oi - ci for oi, ci in zip(o, c, strict=True)]
    dd = _mdot(d, d)
    tc = -_mdot(f, d) / dd
    closest = [fi + tc * di for fi, di in zip(f, d, strict=True)]
    r = mpmath.mpf(s.radius)
    gap = r * r - _mdot(closest, closest)
    scale = _mdot(f, f) + r * r
    if gap < 0:
        return False, None, gap / scale
    half = mpmath.sqrt(gap / dd)
    for t in (tc - half, tc + half):
        if t > 0:
            return (True, t, gap / scale) if t < tmax else (False, None, gap / scale)
    return False, None, gap / scale


def _plane2(pl: Plane, o: list, d: list, tmax: float) -> tuple[bool, object, mpmath.mpf]:
    n = _m(pl.normal)
    p0 = _m(pl.point)
    # Signed heights of the origin and of the point one unit along d above the plane.
    h0 = _mdot([a - b for a, b in zip(o, p0, strict=True)], n)
    h1 = _mdot([a + e - b for a, e, b in zip(o, d, p0, strict=True)], n)
    if h0 == h1:
        return False, None, mpmath.mpf(1)
    t = h0 / (h0 - h1)
    return (True, t, mpmath.mpf(1)) if 0 < t < tmax else (False, None, mpmath.mpf(1))


def _vol(a: list, b: list, c: list) -> mpmath.mpf:
    # a . (b x c) expanded (no pivoting, no division): exact at DIGITS digits for coordinates
    # of a double's range here, so an exact zero (a ray through an edge) stays zero.
    return _mdot(a, _cross_m(b, c))


def _triangle2(tr: Triangle, o: list, d: list, tmax: float) -> tuple[bool, object, mpmath.mpf]:
    # Edge functions: the signed volumes the ray's line makes with each edge (the watertight
    # test's idea, pbrt-v4 6.5.3), then t from the plane.
    a, b, c = _m(tr.a), _m(tr.b), _m(tr.c)
    rel = [[x - y for x, y in zip(p, o, strict=True)] for p in (a, b, c)]
    w = [_vol(rel[1], rel[2], d), _vol(rel[2], rel[0], d), _vol(rel[0], rel[1], d)]
    total = sum(w)
    if total == 0:
        return False, None, mpmath.mpf(1)
    if not (all(x >= 0 for x in w) or all(x <= 0 for x in w)):
        return False, None, mpmath.mpf(1)
    n = mpmath.matrix(_cross_m([b[i] - a[i] for i in range(3)], [c[i] - a[i] for i in range(3)]))
    t = _mdot(list(n), rel[0]) / _mdot(list(n), d)
    return (True, t, mpmath.mpf(1)) if 0 < t < tmax else (False, None, mpmath.mpf(1))


def _cross_m(a: list, b: list) -> list:
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _box2(bx: Box, o: list, d: list, tmax: float) -> tuple[bool, object, mpmath.mpf]:
    # Face by face: each of the six face planes' t, kept when its point lies within the face.
    lo, hi = _m(bx.lo), _m(bx.hi)
    ts = []
    for k in range(3):
        if d[k] == 0:
            continue
        for bound in (lo[k], hi[k]):
            t = (bound - o[k]) / d[k]
            p = [o[i] + t * d[i] for i in range(3)]
            if all(lo[i] <= p[i] <= hi[i] for i in range(3) if i != k):
                ts.append(t)
    ts = sorted(t for t in ts if t > 0)
    if not ts:
        return False, None, mpmath.mpf(1)
    return (True, ts[0], mpmath.mpf(1)) if ts[0] < tmax else (False, None, mpmath.mpf(1))


def _mesh2(me: Mesh, o: list, d: list, tmax: float) -> tuple[bool, object, mpmath.mpf]:
    hits = [t for h, t, _ in (_triangle2(tr, o, d, tmax) for tr in me.triangles()) if h]
    return (True, min(hits), mpmath.mpf(1)) if hits else (False, None, mpmath.mpf(1))


_ROUTE2 = {"sphere": _sphere2, "plane": _plane2, "triangle": _triangle2, "box": _box2,
           "mesh": _mesh2}  # fmt: skip
_ROUTE2 |= dict.fromkeys(("torus", "torus-camera"), truth_torus.route2)


# ------------------------------------------------------------------------------ the interface


@dataclass(frozen=True)
class Truth:
    """Per ray: ``hit``; ``t`` (the true t rounded to the nearest double, nan on a miss);
    ``t_exact`` (mpmath numbers or None); ``undecidable`` (a one-ulp move flips ``hit``)."""

    hit: npt.NDArray[np.bool_]
    t: npt.NDArray[np.float64]
    t_exact: list
    undecidable: npt.NDArray[np.bool_]
    #: Sphere hits: the half chord over the radius (1 for other shapes, 0 on a miss): t is
    #: well conditioned only where the two roots are well apart (say above 0.5).
    separation: npt.NDArray[np.float64]
    #: Hits: how many ulps the exact t moves under the one-ulp moves of the ray's inputs
    #: (PERTURBATIONS and the worst ones): t's own conditioning. A method exact for inputs
    #: within an ulp or two may be off by that much, however good it is (a ray 1e-12 rad from a
    #: triangle's plane: 1e12 ulps). None where not measured (tori: their Sturm truth is costly).
    t_spread: npt.NDArray[np.float64] | None = None


def _spread(t: float, t_moved: object) -> float:
    """|t' - t| in ulps of t, for the exact t' of a moved ray."""
    moved = float(_as_mpf(t_moved))
    return abs(moved - t) / math.ulp(t) if t != 0 else 0.0


def first_hit(shape: Shape, o: npt.ArrayLike, d: npt.ArrayLike, tmax: float = math.inf) -> tuple:
    """Route 1 for one ray: (hit, t exact or None)."""
    return _ROUTE1[shape.kind](shape, _v(o), _v(d), tmax)


def _check(
    shape: Shape, o: npt.ArrayLike, d: npt.ArrayLike, tmax: float, hit: bool, t: object
) -> None:
    hit2, t2, margin = _ROUTE2[shape.kind](shape, _m(o), _m(d), tmax)
    if hit2 != hit:
        # Route 2 rounds at DIGITS digits: a sphere's decision may only differ where the gap
        # r^2 - h^2 is within that rounding of zero (then route 1, exact, stands).
        if abs(margin) > mpmath.mpf(10) ** (20 - DIGITS):
            raise TruthError(f"{shape}: routes disagree on hit for o={_hex(o)} d={_hex(d)}")
        return
    if hit and abs(_as_mpf(t) - t2) > AGREE * (abs(t2) + 1e-300):
        raise TruthError(f"{shape}: routes disagree on t ({t} vs {t2}) for o={_hex(o)} d={_hex(d)}")


def _as_mpf(t: object) -> mpmath.mpf:
    return _mpf(t) if isinstance(t, Fraction) else mpmath.mpf(t)


def _hex(v: npt.ArrayLike) -> list[str]:
    return [float(x).hex() for x in np.asarray(v, dtype=np.float64)]


def perturbed(o: npt.ArrayLike, d: npt.ArrayLike, signs: tuple[int, ...]) -> tuple:
    """The ray with each of its six components moved one ulp up (+1) or down (-1)."""
    comps = list(np.asarray(o, dtype=np.float64)) + list(np.asarray(d, dtype=np.float64))
    moved = [np.nextafter(c, math.copysign(math.inf, s)) for c, s in zip(comps, signs, strict=True)]
    return np.array(moved[:3]), np.array(moved[3:])


def _worst(shape: Shape, o: np.ndarray, d: np.ndarray) -> list[tuple[int, ...]]:
    """For a sphere, the two one-ulp moves that change the discriminant most (each component
    moved by the sign of its derivative, and the opposite): to first order the worst of all 64.
    dD/do = 2 (b d - a f), dD/dd = 2 (b f - c0 d), evaluated in double (only signs matter)."""
    if shape.kind == "cylinder":  # the same across its axis: study/truth_scenes.py
        return truth_scenes.worst_cylinder(shape, o, d)  # type: ignore[arg-type]
    if not isinstance(shape, Sphere):
        return []
    f = o - np.array(shape.center)
    a, b = float(d @ d), float(f @ d)
    c0 = float(f @ f) - shape.radius**2
    grad = np.concatenate([b * d - a * f, b * f - c0 * d])
    up = tuple(1 if g >= 0 else -1 for g in grad)
    return [up, tuple(-x for x in up)]


def _integers(values: list[float]) -> list[int]:
    """Doubles as integers over one common power of two (exact; a positive scale changes no
    sign below)."""
    ratios = [float(v).as_integer_ratio() for v in values]
    big = max(den for _, den in ratios)
    return [num * (big // den) for num, den in ratios]


def _triangle_hits(verts: list[tuple[float, ...]], o: np.ndarray, d: np.ndarray) -> bool:
    """route 1's decision for tmax = inf in integer arithmetic (no gcd: many times faster
    than Fraction, for the many moves of the conditioning). Positions share one scale, the
    direction another; Cramer's u, v, t numerators and denominator then have fixed degrees in
    each, so their signs are those of route 1's."""
    pos = _integers([x for v in verts for x in v] + [float(x) for x in o])
    a, b, c, oo = (pos[0:3], pos[3:6], pos[6:9], pos[9:12])
    nd = [-x for x in _integers([float(x) for x in d])]
    e1 = [b[k] - a[k] for k in range(3)]
    e2 = [c[k] - a[k] for k in range(3)]
    s = [oo[k] - a[k] for k in range(3)]
    p = _cross(e2, nd)  # the same helpers as route 1's, on ints
    den = _dot(e1, p)
    if den == 0:
        return False
    u, v, t = _dot(s, p), _dot(e1, _cross(s, nd)), _dot(e1, _cross(e2, s))
    if den < 0:
        den, u, v, t = -den, -u, -v, -t
    return u >= 0 and v >= 0 and u + v <= den and t > 0


#: Every sign pattern of a one-ulp move of six (ray) or three (vertex) components.
_RAY_MOVES = [tuple(1 if (m >> k) & 1 else -1 for k in range(6)) for m in range(64)]
_VERTEX_MOVES = [tuple(1 if (m >> k) & 1 else -1 for k in range(3)) for m in range(8)]
#: The vertex moves t's conditioning is measured with (truth() t_spread): four of the eight.
_SPREAD_VERTEX_MOVES = [(k, s) for k in range(3) for s in PERTURBATIONS_3]


def _ulp_norm(v: npt.ArrayLike) -> mpmath.mpf:
    return mpmath.mpf(float(np.linalg.norm(np.spacing(np.abs(np.asarray(v, dtype=np.float64))))))


def _near_boundary(tr: Triangle, o: np.ndarray, d: np.ndarray) -> bool:
    """Whether the ray's line passes within one ulp move of the triangle's boundary: for some
    edge, the distance between the line and the edge (a segment; for a zero-area triangle its
    edges are all there is) is at most what moving each component of o, of d and of the
    vertices by one ulp can shift them there (|ulp(o)| + |t| |ulp(d)| + max |ulp(vertex)|,
    at the closest points; at DIGITS digits). The worst case of those moves, where the sign
    patterns below only sample: a ray aimed at a sliver's sharp vertex slips into its wedge
    only in a direction no pattern takes."""
    om, dm = _m(o), _m(d)
    verts = [_m(v) for v in (tr.a, tr.b, tr.c)]
    du, ou = _ulp_norm(d), _ulp_norm(o)
    vu = max(_ulp_norm(v) for v in (tr.a, tr.b, tr.c))
    a = _mdot(dm, dm)
    for j in range(3):
        p, q = verts[j], verts[(j + 1) % 3]
        e = [qi - pi for pi, qi in zip(p, q, strict=True)]
        w0 = [oi - pi for oi, pi in zip(om, p, strict=True)]
        b, c = _mdot(dm, e), _mdot(e, e)
        dd, ee = _mdot(dm, w0), _mdot(e, w0)
        den = a * c - b * b
        candidates = [mpmath.mpf(0), mpmath.mpf(1)]
        if den > 0:
            candidates.append(min(max((a * ee - b * dd) / den, mpmath.mpf(0)), mpmath.mpf(1)))
        for sv in candidates:
            t = (b * sv - dd) / a  # the line's closest point to P + s e
            gap = [w0[k] + t * dm[k] - sv * e[k] for k in range(3)]
            if mpmath.sqrt(_mdot(gap, gap)) <= ou + abs(t) * du + vu:
                return True
    return False


def _triangle_undecidable(tr: Triangle, o: np.ndarray, d: np.ndarray, hit: bool) -> bool:
    """A triangle's conditioning. A ray near an edge or a vertex, or nearly in the plane, gets
    every one-ulp move of its six components (64) and of each vertex alone (3 x 8): the
    watertight test's and Moeller-Trumbore's rounding is a few ulps of the vertices (pbrt-v4
    6.8.3 bounds it on the translated vertices), which for a ray nearly in the plane no move of
    the ray alone can model (it moves the three edge functions together). Other rays get the
    fixed PERTURBATIONS."""
    verts = [tuple(float(x) for x in v) for v in (tr.a, tr.b, tr.c)]
    rel = [np.array(v) - o for v in verts]
    near = False
    for j, k in ((1, 2), (2, 0), (0, 1)):
        w = float(rel[j] @ np.cross(rel[k], d))
        size = np.linalg.norm(rel[j]) * np.linalg.norm(rel[k]) * np.linalg.norm(d)
        # "Near": within 1e-6 of its largest possible size (a margin: it only costs moves).
        near = near or not abs(w) > 1e-6 * size
    if near and _near_boundary(tr, o, d):
        return True
    moves = _RAY_MOVES if near else list(PERTURBATIONS)
    for signs in moves:
        po, pd = perturbed(o, d, signs)
        if _triangle_hits(verts, po, pd) != hit:
            return True
    if near:
        for i in range(3):
            for signs in _VERTEX_MOVES:
                moved = list(verts)
                moved[i] = tuple(float(np.nextafter(x, math.copysign(math.inf, sg)))
                                 for x, sg in zip(verts[i], signs, strict=True))  # fmt: skip
                if _triangle_hits(moved, o, d) != hit:
                    return True
    return False


def truth(
    shape: Shape,
    origins: npt.ArrayLike,
    directions: npt.ArrayLike,
    tmax: float = math.inf,
    *,
    conditioning: bool = True,
    check_every: int = 1,
) -> Truth:
    """The truth for each ray; route 2 checks every ``check_every``-th ray (1: all)."""
    o_all = np.asarray(origins, dtype=np.float64)
    d_all = np.asarray(directions, dtype=np.float64)
    n = len(o_all)
    hit = np.zeros(n, dtype=bool)
    t = np.full(n, np.nan)
    exact: list = [None] * n
    undecidable = np.zeros(n, dtype=bool)
    separation = np.zeros(n)
    spread = np.zeros(n)
    for i in range(n):
        h, te = first_hit(shape, o_all[i], d_all[i], tmax)
        if i % check_every == 0:
            _check(shape, o_all[i], d_all[i], tmax, h, te)
        hit[i], exact[i] = h, te
        if h:
            t[i] = float(_as_mpf(te))
            separation[i] = 1.0
            if isinstance(shape, Sphere):
                far = last_exit(shape, o_all[i], d_all[i])
                chord = (far - _as_mpf(te)) * mpmath.sqrt(_mpf(_dot(_v(d_all[i]), _v(d_all[i]))))
                separation[i] = float(chord / 2 / shape.radius) if far is not None else 0.0
            elif isinstance(shape, Torus):
                separation[i] = truth_torus.separation(shape, o_all[i], d_all[i], te)
        if conditioning and isinstance(shape, Torus):
            undecidable[i] = truth_torus.undecidable(shape, o_all[i], d_all[i], h, tmax)
        elif conditioning and isinstance(shape, Triangle) and tmax == math.inf:
            undecidable[i] = _triangle_undecidable(shape, o_all[i], d_all[i], h)
            for signs in PERTURBATIONS if h and not undecidable[i] else ():
                h2, t2 = first_hit(shape, *perturbed(o_all[i], d_all[i], signs), tmax)
                if h2:
                    spread[i] = max(spread[i], _spread(t[i], t2))
            # And moves of each vertex alone by one ulp of its place relative to the ray's
            # origin: every triangle test starts from v - o (Moeller-Trumbore's s = o - v0, the
            # watertight test's translation, pbrt-v4 6.8.3), whose rounding is such a move; a
            # sliver's plane, and so t, turns with it far more than with any move of the ray.
            # (A few of the sign patterns: a lower bound on t's conditioning, so that a method
            # is, if anything, judged too hard.)
            for k, signs in _SPREAD_VERTEX_MOVES if h and not undecidable[i] else ():
                verts = [shape.a, shape.b, shape.c]
                step = np.spacing(np.abs(np.asarray(verts[k], dtype=np.float64) - o_all[i]))
                moved = zip(verts[k], signs, step, strict=True)
                verts[k] = tuple(float(x + sg * st) for x, sg, st in moved)
                h2, t2 = first_hit(Triangle(*verts), o_all[i], d_all[i], tmax)
                if h2:
                    spread[i] = max(spread[i], _spread(t[i], t2))
        elif conditioning:
            for signs in (*PERTURBATIONS, *_worst(shape, o_all[i], d_all[i])):
                po, pd = perturbed(o_all[i], d_all[i], signs)
                h2, t2 = first_hit(shape, po, pd, tmax)
                if h2 != h:
                    undecidable[i] = True
                    break
                if h:
                    spread[i] = max(spread[i], _spread(t[i], t2))
    # Not measured for tori (their Sturm truth is costly: t_error_ulps_max_separated judges
    # them, on rays whose roots are apart), nor without conditioning.
    measured = conditioning and not isinstance(shape, Torus)
    return Truth(hit, t, exact, undecidable, separation, spread if measured else None)


def last_exit(shape: Shape, o: npt.ArrayLike, d: npt.ArrayLike) -> mpmath.mpf | None:
    """The largest t > 0 where the ray's line meets a closed shape (sphere, box), else None: the
    far side an inward spawned ray must reach."""
    if shape.kind == "rbox":  # study/truth_scenes.py
        return truth_scenes.rbox_last_exit(shape, o, d)  # type: ignore[arg-type]
    if isinstance(shape, Sphere):
        ov, dv = _v(o), _v(d)
        f = _sub(ov, _v(shape.center))
        a, b = _dot(dv, dv), _dot(f, dv)
        disc = b * b - a * (_dot(f, f) - Fraction(shape.radius) ** 2)
        if disc < 0:
            return None
        t = (-_mpf(b) + mpmath.sqrt(_mpf(disc))) / _mpf(a)
        return t if t > 0 else None
    if isinstance(shape, Box):
        lo, hi, ov, dv = _v(shape.lo), _v(shape.hi), _v(o), _v(d)
        far: Fraction | None = None
        for k in range(3):
            if dv[k] != 0:
                t2 = max((lo[k] - ov[k]) / dv[k], (hi[k] - ov[k]) / dv[k])
                far = t2 if far is None else min(far, t2)
        return _mpf(far) if far is not None and far > 0 else None
    return None


def side(shape: Shape, p: npt.ArrayLike) -> int:
    """Which side of the surface the point lies on, exactly: +1 outside (or above a plane or a
    triangle's plane, along its normal), -1 inside (below), 0 on it."""
    if shape.kind == "cylinder":  # study/truth_scenes.py
        return truth_scenes.cylinder_side(shape, p)  # type: ignore[arg-type]
    if shape.kind in truth_placed.SIDE:  # transformed cylinders and tori: study/truth_placed.py
        return truth_placed.SIDE[shape.kind](shape, p)  # type: ignore[arg-type]
    if shape.kind == "rbox":
        return truth_scenes.rbox_side(shape, p)  # type: ignore[arg-type]
    if isinstance(shape, Torus):
        return truth_torus.side(shape, p)
    q = _v(p)
    if isinstance(shape, Sphere):
        f = _sub(q, _v(shape.center))
        g = _dot(f, f) - Fraction(shape.radius) ** 2
    elif isinstance(shape, Plane):
        g = _dot(_sub(q, _v(shape.point)), _v(shape.normal))
    elif isinstance(shape, Triangle):
        a = _v(shape.a)
        g = _dot(_sub(q, a), _cross(_sub(_v(shape.b), a), _sub(_v(shape.c), a)))
    else:
        lo, hi = _v(shape.lo), _v(shape.hi)
        if all(lo[k] < q[k] < hi[k] for k in range(3)):
            return -1
        return 0 if all(lo[k] <= q[k] <= hi[k] for k in range(3)) else 1
    return (g > 0) - (g < 0)


def within_bound(shape: Shape, p: npt.ArrayLike, err: npt.ArrayLike) -> bool:
    """Whether the box p +- err (a hit point and its error bound) holds a point of the true
    surface, exactly: the promise offset_ray_origin() relies on."""
    if shape.kind in truth_scenes.WITHIN:  # cylinders, groups: study/truth_scenes.py
        return truth_scenes.WITHIN[shape.kind](shape, p, err)
    if isinstance(shape, Mesh):
        # Some triangle's plane passes through the box (a plane, not the triangle itself: a
        # weaker check, enough to catch a point refined off its surface).
        q, e = np.asarray(p, dtype=np.float64), np.asarray(err, dtype=np.float64)
        for tr in shape.triangles():
            v = np.array([tr.a, tr.b, tr.c])
            # Only triangles whose bounds (widened by the box and a relative 1e-12) reach it.
            pad = e + 1e-12 * (np.abs(q) + np.abs(v).max(axis=0))
            reach = np.all(v.min(axis=0) - pad <= q) and np.all(q <= v.max(axis=0) + pad)
            if reach and within_bound(tr, p, err):
                return True
        return False
    q, e = _v(p), _v(err)
    lo = (q[0] - e[0], q[1] - e[1], q[2] - e[2])
    hi = (q[0] + e[0], q[1] + e[1], q[2] + e[2])
    corners = [(x, y, z) for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    if isinstance(shape, Sphere):
        c, r2 = _v(shape.center), Fraction(shape.radius) ** 2
        near = sum(max(lo[k] - c[k], Fraction(0), c[k] - hi[k]) ** 2 for k in range(3))
        far = sum(max(abs(lo[k] - c[k]), abs(hi[k] - c[k])) ** 2 for k in range(3))
        return near <= r2 <= far
    if shape.kind == "box":
        # Convex: the error box holds a surface point iff it meets the solid and is not wholly
        # inside it. Its corners' sides alone miss an error box wider than the shape (every
        # corner outside: a float hit from a far camera, +-28 about a unit box).
        blo, bhi = _v(shape.lo), _v(shape.hi)
        meets = all(lo[k] <= bhi[k] and blo[k] <= hi[k] for k in range(3))
        return meets and any(side(shape, x) >= 0 for x in corners)
    sides = {side(shape, x) for x in corners}
    return len(sides) > 1 or 0 in sides


# Issue 11's scene families (cylinders, groups of nearly touching shapes): study/truth_scenes.py;
# cylinders and tori under a transform: study/truth_placed.py. Importing them adds their routes
# to _ROUTE1 and _ROUTE2 (they build on the helpers above).
from study import truth_placed, truth_scenes  # noqa: E402
