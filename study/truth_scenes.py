"""Ground truth for issue 11's scene families: capped cylinders, groups of shapes (nearly
touching surfaces: which member a ray meets first) and mirror chains between them. The same two
routes as study/truth.py, from the scene description and the ray alone.

Cylinder, route 1: the side is the sphere's quadratic in the two dimensions across the axis
a = top - base: |(w + t d) x a|^2 = r^2 |a|^2 (w = o - base), its discriminant exact in
Fractions, every comparison of a root with a rational (t > 0, the height range, a cap's t)
decided exactly by squaring; t itself by an mpmath square root. The caps are the planes
(p - base).a = 0 and (p - top).a = 0, exact. Route 2: the unit axis in mpmath, the ray's part
across it, the closest approach and the half chord (the sphere's route 2 in two dimensions)."""

from __future__ import annotations

import math
from fractions import Fraction

import mpmath
import numpy as np
import numpy.typing as npt

from study import truth as _t
from study.shapes import Box, Cylinder, Group, Plane, RotatedBox, Sphere

Vec = tuple[Fraction, Fraction, Fraction]


# ------------------------------------------------------------------------- cylinder, route 1


def _root_vs(b: Fraction, disc: Fraction, a: Fraction, sign: int, q: Fraction) -> int:
    """The sign of t - q for the root t = (-b + sign sqrt(disc)) / a (a > 0), exactly."""
    m = b + q * a  # t - q = (sign sqrt(disc) - m) / a
    if sign > 0:  # sqrt(disc) - m
        if m < 0:
            return 1
        return (disc > m * m) - (disc < m * m)
    if m > 0:  # -sqrt(disc) - m < 0
        return -1
    return (m * m > disc) - (m * m < disc)


def _cylinder1(cy: Cylinder, o: Vec, d: Vec, tmax: float) -> tuple[bool, object]:
    base, top = _t._v(cy.base), _t._v(cy.top)
    ax = _t._sub(top, base)
    aa = _t._dot(ax, ax)
    w = _t._sub(o, base)
    r2aa = Fraction(cy.radius) ** 2 * aa
    wa, da = _t._dot(w, ax), _t._dot(d, ax)
    limit = None if tmax == math.inf else Fraction(tmax)
    # Candidates: (exact key for ordering, t as mpmath or Fraction). Each side root is kept as
    # (b, disc, a, sign); caps as Fractions.
    best: tuple | None = None  # ("root", b, disc, a, sign) or ("frac", t)

    def less(x: tuple, y: tuple) -> bool:
        if x[0] == "frac" and y[0] == "frac":
            return x[1] < y[1]
        if x[0] == "root" and y[0] == "frac":
            return _root_vs(*x[1:], y[1]) < 0
        if x[0] == "frac" and y[0] == "root":
            return _root_vs(*y[1:], x[1]) > 0
        return x[4] < y[4]  # the same quadratic: the - root first

    def vs(x: tuple, q: Fraction) -> int:
        return _root_vs(*x[1:], q) if x[0] == "root" else (x[1] > q) - (x[1] < q)

    def take(x: tuple) -> None:
        nonlocal best
        positive = vs(x, Fraction(0)) > 0 and (limit is None or vs(x, limit) < 0)
        if positive and (best is None or less(x, best)):
            best = x

    u, v = _t._cross(w, ax), _t._cross(d, ax)
    a = _t._dot(v, v)
    if a > 0:
        b, c = _t._dot(u, v), _t._dot(u, u) - r2aa
        disc = b * b - a * c
        if disc >= 0:
            for sign in (-1, 1):
                x = ("root", b, disc, a, sign)
                # Within the height: 0 <= wa + t da <= aa.
                if da == 0:
                    inside = 0 <= wa <= aa
                else:
                    q1, q2 = -wa / da, (aa - wa) / da
                    lo, hi = min(q1, q2), max(q1, q2)
                    inside = vs(x, lo) >= 0 and vs(x, hi) <= 0
                if inside:
                    take(x)
    if da != 0:
        for level in (Fraction(0), aa):
            t = (level - wa) / da
            p = tuple(w[k] + t * d[k] for k in range(3))
            q = _t._cross(p, ax)  # type: ignore[arg-type]
            if _t._dot(q, q) <= r2aa:
                take(("frac", t))
    if best is None:
        return False, None
    if best[0] == "frac":
        return True, best[1]
    _, b, disc, a, sign = best
    return True, (-_t._mpf(b) + sign * mpmath.sqrt(_t._mpf(disc))) / _t._mpf(a)


# ------------------------------------------------------------------------- cylinder, route 2


def _cylinder2(cy: Cylinder, o: list, d: list, tmax: float) -> tuple[bool, object, mpmath.mpf]:
    base, top = _t._m(cy.base), _t._m(cy.top)
    ax = [y - x for x, y in zip(base, top, strict=True)]
    length = mpmath.sqrt(_t._mdot(ax, ax))
    e = [x / length for x in ax]
    w = [x - y for x, y in zip(o, base, strict=True)]
    wz, dz = _t._mdot(w, e), _t._mdot(d, e)
    wp = [w[k] - wz * e[k] for k in range(3)]
    dp = [d[k] - dz * e[k] for k in range(3)]
    r = mpmath.mpf(cy.radius)
    ts = []
    margin = mpmath.mpf(1)
    dd = _t._mdot(dp, dp)
    if dd > 0:
        tc = -_t._mdot(wp, dp) / dd
        closest = [wp[k] + tc * dp[k] for k in range(3)]
        gap = r * r - _t._mdot(closest, closest)
        margin = gap / (_t._mdot(wp, wp) + r * r)
        if gap >= 0:
            half = mpmath.sqrt(gap / dd)
            ts += [t for t in (tc - half, tc + half) if 0 <= wz + t * dz <= length]
    if dz != 0:
        for level in (mpmath.mpf(0), length):
            t = (level - wz) / dz
            p = [wp[k] + t * dp[k] for k in range(3)]
            if _t._mdot(p, p) <= r * r:
                ts.append(t)
    ts = sorted(t for t in ts if t > 0)
    if not ts or not ts[0] < tmax:
        return False, None, margin
    return True, ts[0], margin


# ----------------------------------------------------------------------------------- groups


def first_member(group: Group, o: npt.ArrayLike, d: npt.ArrayLike,
                 tmax: float = math.inf) -> tuple[bool, object, int]:  # fmt: skip
    """Route 1 for a group: (hit, t, the index of the member met first; -1 on a miss). Members'
    t are compared at DIGITS digits: two equal to that precision would be a ray through a point
    both surfaces share, which a gap excludes (and its ray is undecidable anyway)."""
    ov, dv = _t._v(o), _t._v(d)
    best: tuple[object, int] | None = None
    for i, m in enumerate(group.members):
        h, t = _t._ROUTE1[m.kind](m, ov, dv, tmax)
        if h and (best is None or _t._as_mpf(t) < _t._as_mpf(best[0])):
            best = (t, i)
    return (True, best[0], best[1]) if best is not None else (False, None, -1)


def member_ts(group: Group, o: npt.ArrayLike, d: npt.ArrayLike) -> list[mpmath.mpf]:
    """Every member's exact first t along the ray (those it meets), sorted."""
    ov, dv = _t._v(o), _t._v(d)
    hits = [_t._ROUTE1[m.kind](m, ov, dv, math.inf) for m in group.members]
    return sorted(_t._as_mpf(t) for h, t in hits if h)


def _group1(group: Group, o: Vec, d: Vec, tmax: float) -> tuple[bool, object]:
    h, t, _ = first_member(group, [float(x) for x in o], [float(x) for x in d], tmax)
    return h, t


def _group2(group: Group, o: list, d: list, tmax: float) -> tuple[bool, object, mpmath.mpf]:
    best, margin = None, mpmath.mpf(1)
    for m in group.members:
        h, t, mg = _t._ROUTE2[m.kind](m, o, d, tmax)
        margin = min(margin, abs(mg))
        if h and (best is None or t < best):
            best = t
    return best is not None, best, margin


ROUTE1 = {"cylinder": _cylinder1, "group": _group1}
ROUTE2 = {"cylinder": _cylinder2, "group": _group2}


# ------------------------------------------------------------------ sides and error bounds


def cylinder_side(cy: Cylinder, p: npt.ArrayLike) -> int:
    """+1 outside the solid cylinder, -1 inside, 0 on its surface (exact)."""
    return cylinder_side_exact(cy, _t._v(p))


def cylinder_side_exact(cy: Cylinder, p: Vec) -> int:
    """cylinder_side() for a point given as exact rationals (study/truth_placed.py)."""
    base, top = _t._v(cy.base), _t._v(cy.top)
    ax = _t._sub(top, base)
    aa = _t._dot(ax, ax)
    w = _t._sub(p, base)
    q = _t._cross(w, ax)
    rho = _t._dot(q, q) - Fraction(cy.radius) ** 2 * aa  # sign of distance^2 - r^2
    h = _t._dot(w, ax)
    if rho > 0 or h < 0 or h > aa:
        return 1
    return 0 if rho == 0 or h == 0 or h == aa else -1


def cylinder_within(cy: Cylinder, p: npt.ArrayLike, err: npt.ArrayLike) -> bool:
    """Whether the box p +- err holds a point of the cylinder's surface, exactly. The side, for
    an axis along a coordinate axis: the box's range of distances to the axis (as a sphere's,
    in the two coordinates across it) holds r, and its range along the axis meets the
    cylinder's. Otherwise (and for the caps): the box's corners on both sides."""
    q, e = _t._v(p), _t._v(err)
    lo = [q[k] - e[k] for k in range(3)]
    hi = [q[k] + e[k] for k in range(3)]
    base, top = _t._v(cy.base), _t._v(cy.top)
    along = [k for k in range(3) if base[k] != top[k]]
    if len(along) == 1:
        z = along[0]
        zlo, zhi = min(base[z], top[z]), max(base[z], top[z])
        if lo[z] <= zhi and hi[z] >= zlo:
            across = [k for k in range(3) if k != z]
            c = base
            near = sum(max(lo[k] - c[k], Fraction(0), c[k] - hi[k]) ** 2 for k in across)
            far = sum(max(abs(lo[k] - c[k]), abs(hi[k] - c[k])) ** 2 for k in across)
            if near <= Fraction(cy.radius) ** 2 <= far:
                return True
    corners = [(x, y, w) for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for w in (lo[2], hi[2])]
    sides = {cylinder_side(cy, [float(c) for c in x]) for x in corners}
    return len(sides) > 1 or 0 in sides


def group_within(group: Group, p: npt.ArrayLike, err: npt.ArrayLike) -> bool:
    return any(_t.within_bound(m, p, err) for m in group.members)


WITHIN = {"cylinder": cylinder_within, "group": group_within}


# ------------------------------------------------------------------------------ conditioning


def _moves(member: Sphere | Plane | Cylinder) -> list:
    """The member moved by one ulp: a sphere's centre (all components up, all down) and its
    radius (up, down); a plane's point (up, down). The gap of nearly touching surfaces is of
    the scene's own coordinates: at one ulp, one such move closes it."""

    def nudge(v: tuple, s: float) -> tuple:
        return tuple(float(np.nextafter(x, math.copysign(math.inf, s))) for x in v)

    if isinstance(member, Sphere):
        return [Sphere(nudge(member.center, s), member.radius) for s in (1, -1)] + [
            Sphere(member.center, float(np.nextafter(member.radius, s * math.inf))) for s in (1, -1)
        ]
    if isinstance(member, Plane):
        return [Plane(nudge(member.point, s), member.normal) for s in (1, -1)]
    return []


def group_undecidable(group: Group, o: np.ndarray, d: np.ndarray, answer: tuple[bool, int]) -> bool:
    """Whether a one-ulp move of the ray (study/truth.py's PERTURBATIONS and, per sphere, its two
    worst moves) or of one member (_moves) changes the hit or the member met first."""
    for signs in (*_t.PERTURBATIONS,
                  *(s for m in group.members for s in _t._worst(m, o, d))):  # fmt: skip
        po, pd = _t.perturbed(o, d, signs)
        h, _, i = first_member(group, po, pd)
        if (h, i) != answer:
            return True
    for j, m in enumerate(group.members):
        for moved in _moves(m):
            g = Group(tuple(moved if k == j else x for k, x in enumerate(group.members)))
            h, _, i = first_member(g, o, d)
            if (h, i) != answer:
                return True
    return False


def worst_cylinder(cy: Cylinder, o: np.ndarray, d: np.ndarray) -> list[tuple[int, ...]]:
    """study/truth.py _worst() for a cylinder's side: the sphere's gradient of the discriminant
    in the two dimensions across the axis (the parts along it change nothing at mid-height)."""
    e = np.array(cy.top) - np.array(cy.base)
    e = e / np.linalg.norm(e)
    w = o - np.array(cy.base)
    f, dd = w - (w @ e) * e, d - (d @ e) * e
    a, b = float(dd @ dd), float(f @ dd)
    c0 = float(f @ f) - cy.radius**2
    grad = np.concatenate([b * dd - a * f, b * f - c0 * dd])
    up = tuple(1 if g >= 0 else -1 for g in grad)
    return [up, tuple(-x for x in up)]


# ---------------------------------------------------------------------------- rotated boxes
# The matrix [A | b] the core is given, exact (its doubles as rationals): a ray in world space is
# the ray A^-1 (o - b) + t A^-1 d in the box's own coordinates, with the same t.


def _exact_inverse(rb: RotatedBox) -> tuple[list[list[Fraction]], Vec]:
    m = [[Fraction(float(x)) for x in row] for row in rb.matrix()]
    a = [row[:3] for row in m]
    b = (m[0][3], m[1][3], m[2][3])
    cof = [[a[(i + 1) % 3][(j + 1) % 3] * a[(i + 2) % 3][(j + 2) % 3]
            - a[(i + 1) % 3][(j + 2) % 3] * a[(i + 2) % 3][(j + 1) % 3] for j in range(3)]
           for i in range(3)]  # fmt: skip
    det = sum(a[0][j] * cof[0][j] for j in range(3))
    inv = [[cof[j][i] / det for j in range(3)] for i in range(3)]  # the adjugate over det
    return inv, b


def to_object(rb: RotatedBox, o: Vec, d: Vec) -> tuple[Vec, Vec]:
    """The ray in the box's own coordinates, exactly."""
    inv, b = _exact_inverse(rb)
    w = _t._sub(o, b)
    qo = tuple(sum(inv[i][k] * w[k] for k in range(3)) for i in range(3))
    qd = tuple(sum(inv[i][k] * d[k] for k in range(3)) for i in range(3))
    return qo, qd  # type: ignore[return-value]


def _rbox1(rb: RotatedBox, o: Vec, d: Vec, tmax: float) -> tuple[bool, object]:
    qo, qd = to_object(rb, o, d)
    return _t._box1(Box(rb.lo, rb.hi), qo, qd, tmax)


def _rbox2(rb: RotatedBox, o: list, d: list, tmax: float) -> tuple[bool, object, mpmath.mpf]:
    # The inverse by mpmath's LU at DIGITS digits (not the adjugate), then face by face.
    m = mpmath.matrix([[mpmath.mpf(float(x)) for x in row] for row in rb.matrix()])
    inv = mpmath.inverse(m[:, :3])
    w = mpmath.matrix([o[k] - m[k, 3] for k in range(3)])
    qo, qd = inv * w, inv * mpmath.matrix(d)
    return _t._box2(Box(rb.lo, rb.hi), [qo[k] for k in range(3)], [qd[k] for k in range(3)], tmax)


def rbox_side(rb: RotatedBox, p: npt.ArrayLike) -> int:
    q, _ = to_object(rb, _t._v(p), (Fraction(0), Fraction(0), Fraction(0)))
    lo, hi = _t._v(rb.lo), _t._v(rb.hi)
    if all(lo[k] < q[k] < hi[k] for k in range(3)):
        return -1
    return 0 if all(lo[k] <= q[k] <= hi[k] for k in range(3)) else 1


def rbox_last_exit(rb: RotatedBox, o: npt.ArrayLike, d: npt.ArrayLike) -> mpmath.mpf | None:
    """study/truth.py last_exit() for a rotated box: the far slab crossing, in its coordinates."""
    qo, qd = to_object(rb, _t._v(o), _t._v(d))
    lo, hi = _t._v(rb.lo), _t._v(rb.hi)
    far: Fraction | None = None
    for k in range(3):
        if qd[k] != 0:
            t2 = max((lo[k] - qo[k]) / qd[k], (hi[k] - qo[k]) / qd[k])
            far = t2 if far is None else min(far, t2)
    return _t._mpf(far) if far is not None and far > 0 else None


ROUTE1["rbox"] = _rbox1
ROUTE2["rbox"] = _rbox2


_t._ROUTE1.update(ROUTE1)
_t._ROUTE2.update(ROUTE2)
