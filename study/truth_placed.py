"""Ground truth for cylinders and tori under a transform (study/shapes.py PlacedCylinder,
PlacedTorus), from the scene description and the ray alone.

The core is given a double 3x4 matrix [A | b] (object to world: the scene's transform after the
object's own frame, tracer/scene/placement.py to_world()); the truth takes those doubles as exact,
as study/truth_scenes.py does for rotated boxes: the rounding of a rotation to doubles is the
scene's, shared by every method. A world ray o + t d is the ray A^-1 (o - b) + t A^-1 d in the
object's coordinates, with the same t.

Route 1: A^-1 exactly in rationals (the adjugate over the determinant), the object-space ray
exactly, then the untransformed shape's exact route on that rational ray: the cylinder's exact
quadratic (study/truth_scenes.py _cylinder1, which takes Fractions as they come), the torus's
quartic with integer coefficients over the rays' common denominator and Sturm's theorem
(study/truth_torus.py first_root_exact). Route 2: A^-1 by mpmath's LU decomposition at the
working precision (not the adjugate), then the untransformed shape's route 2 in mpmath (the
cylinder's closest approach and half chord; the torus by Ferrari's closed form)."""

from __future__ import annotations

import functools
from fractions import Fraction

import mpmath
import numpy.typing as npt

from study import truth as _t
from study import truth_scenes, truth_torus
from study.shapes import PlacedCylinder, PlacedTorus

Vec = tuple[Fraction, Fraction, Fraction]
Placed = PlacedCylinder | PlacedTorus


@functools.lru_cache(maxsize=256)
def exact_inverse(shape: Placed) -> tuple[tuple[tuple[Fraction, ...], ...], Vec]:
    """(A^-1, b) for the shape's matrix [A | b], exact (study/truth_scenes.py _exact_inverse)."""
    inv, b = truth_scenes._exact_inverse(shape)  # type: ignore[arg-type]
    return tuple(tuple(row) for row in inv), b


def to_object(shape: Placed, o: Vec, d: Vec) -> tuple[Vec, Vec]:
    """The world ray (o, d), rationals, in the shape's own coordinates, exactly (the rotated
    boxes' route, study/truth_scenes.py to_object, which reads only the shape's matrix)."""
    return truth_scenes.to_object(shape, o, d)  # type: ignore[arg-type]


_ZERO: Vec = (Fraction(0), Fraction(0), Fraction(0))


def _to_object_mp(shape: Placed, o: list, d: list) -> tuple[list, list]:
    """Route 2's object-space ray: A^-1 by mpmath's LU decomposition at the current precision."""
    m = mpmath.matrix([[mpmath.mpf(float(x)) for x in row] for row in shape.matrix()])
    inv = mpmath.inverse(m[:, :3])
    w = mpmath.matrix([o[k] - m[k, 3] for k in range(3)])
    qo, qd = inv * w, inv * mpmath.matrix(d)
    return [qo[k] for k in range(3)], [qd[k] for k in range(3)]


def _cylinder1(cy: PlacedCylinder, o: Vec, d: Vec, tmax: float) -> tuple[bool, object]:
    qo, qd = to_object(cy, o, d)
    return truth_scenes._cylinder1(cy.local(), qo, qd, tmax)


def _cylinder2(cy: PlacedCylinder, o: list, d: list, tmax: float) -> tuple[bool, object, object]:
    qo, qd = _to_object_mp(cy, o, d)
    return truth_scenes._cylinder2(cy.local(), qo, qd, tmax)


def _torus1(tor: PlacedTorus, o: Vec, d: Vec, tmax: float) -> tuple[bool, object]:
    qo, qd = to_object(tor, o, d)
    return truth_torus.first_root_exact(tor.local(), qo, qd, tmax)


def _torus2(tor: PlacedTorus, o: list, d: list, tmax: float) -> tuple[bool, object, object]:
    # At Ferrari's working precision (twice DIGITS), the inverse too; the centre is the origin.
    with mpmath.workdps(2 * _t.DIGITS):
        qo, qd = _to_object_mp(tor, [mpmath.mpf(x) for x in o], [mpmath.mpf(x) for x in d])
        return truth_torus.route2_mp(tor.local(), qo, qd, tmax)


def cylinder_side(cy: PlacedCylinder, p: npt.ArrayLike) -> int:
    """+1 outside the solid cylinder, -1 inside, 0 on its surface (exact, in its coordinates)."""
    q, _ = to_object(cy, _t._v(p), _ZERO)
    return truth_scenes.cylinder_side_exact(cy.local(), q)


def torus_side(tor: PlacedTorus, p: npt.ArrayLike) -> int:
    q, _ = to_object(tor, _t._v(p), _ZERO)
    return truth_torus.side_exact(tor.local(), q)


KINDS = (PlacedCylinder.kind_circular, PlacedCylinder.kind_elliptic, PlacedTorus.kind)
ROUTE1 = {**dict.fromkeys(KINDS[:2], _cylinder1), PlacedTorus.kind: _torus1}
ROUTE2 = {**dict.fromkeys(KINDS[:2], _cylinder2), PlacedTorus.kind: _torus2}
SIDE = {**dict.fromkeys(KINDS[:2], cylinder_side), PlacedTorus.kind: torus_side}

_t._ROUTE1.update(ROUTE1)
_t._ROUTE2.update(ROUTE2)
