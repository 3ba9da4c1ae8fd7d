"""Cylinders and tori under a transform (study/shapes.py PlacedCylinder, PlacedTorus;
study/truth_placed.py, study/families_placed.py): the exact inverse of the core's matrix, the
transformed truth against the untransformed one where the transform changes nothing or scales
by a power of two, the two routes on the family's own rays, and a judge that can fail rtlab
(its figures in the quick study: tests/study/test_quick.py)."""

from __future__ import annotations

import dataclasses
from fractions import Fraction

import mpmath
import numpy as np

from study import run, truth
from study.families import FAMILIES
from study.methods import methods
from study.shapes import Cylinder, PlacedCylinder, PlacedTorus, Placement, Torus
from study.truth_placed import exact_inverse, to_object

FAMILY = "self-intersection-transformed"
#: Relative agreement of two exact t's computed from different but equivalent descriptions:
#: each is refined to DIGITS (120) digits, so they agree to about that; 1e-100 leaves 20 digits.
SAME = mpmath.mpf("1e-100")


def _cases(knob: float, n: int = 1000):
    """The family's cases at a knob value, with the study's own seed (study/run.py)."""
    fam = FAMILIES[FAMILY]
    rng = np.random.default_rng([run.SEED, list(FAMILIES).index(FAMILY), fam.values.index(knob)])
    return fam.generate(knob, n, rng)


def _all_shapes():
    return [c.shape for knob in FAMILIES[FAMILY].quick_values for c in _cases(knob)]


def test_the_exact_inverse_inverts_the_cores_matrix():
    """The matrix is what tracer/render.py to_core() gives the core (to_world() of the object
    the scene language reads, rebuilt here from the model's own classes), a real rotation and
    non-uniform scale; its inverse, in rationals, inverts it to the last bit both ways."""
    from tracer.scene.model import Cylinder as ModelCylinder
    from tracer.scene.model import Torus as ModelTorus
    from tracer.scene.model import Transform
    from tracer.scene.placement import to_world

    shapes = _all_shapes()
    assert {s.kind for s in shapes} == {"placed-cylinder", "placed-elliptic-cylinder",
                                        "placed-torus"}  # fmt: skip
    for s in shapes:
        p = s.placement
        tf = Transform(scale=p.scale, rotate_axis=p.axis, rotate_degrees=p.degrees,
                       translate=p.translate)  # fmt: skip
        if isinstance(s, PlacedTorus):
            model = ModelTorus((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), s.major_radius, s.minor_radius,
                               "m", tf)  # fmt: skip
        else:
            model = ModelCylinder((0.0, 0.0, 0.0), (0.0, 0.0, s.height), s.radius, "m", True, tf)
        m = to_world(model)[:3]
        assert np.array_equal(np.asarray(s.matrix()), m)
        a = [[Fraction(float(x)) for x in row[:3]] for row in m]
        # Not a trivial matrix: every entry of the linear part is non-zero (a random axis).
        assert all(x != 0 for row in a for x in row)
        inv, b = exact_inverse(s)
        assert b == tuple(Fraction(float(row[3])) for row in m)
        for i in range(3):
            for j in range(3):
                assert sum(a[i][k] * inv[k][j] for k in range(3)) == (i == j)
                assert sum(inv[i][k] * a[k][j] for k in range(3)) == (i == j)
        # And the double inverse the core computes (13_transform.h: the adjugate in double) is
        # not that one: the truth does not share the core's rounding.
        assert not np.array_equal(np.linalg.inv(m[:, :3]), [[float(x) for x in r] for r in inv])
        # A point of the object's coordinates comes back from the world exactly.
        q = (Fraction(1, 3), Fraction(-2, 7), Fraction(5))
        world = tuple(sum(a[i][k] * q[k] for k in range(3)) + b[i] for i in range(3))
        assert to_object(s, world, q)[0] == q  # type: ignore[arg-type]


def _same(a, b) -> bool:
    (ha, ta), (hb, tb) = a, b
    if ha != hb:
        return False
    return not ha or abs(truth._as_mpf(ta) - truth._as_mpf(tb)) <= SAME * abs(truth._as_mpf(tb))


def test_the_transformed_torus_is_the_torus_where_the_transform_changes_nothing():
    """A translation (the frame's quarter turn about z is exact and the torus symmetric under
    it), a power-of-two scale (the torus with its radii scaled): the same first hits as the
    untransformed truth (study/truth_torus.py first_root on doubles), to 100 digits. And
    scaling the scene and the origin by 2^k scales t by 2^k exactly."""
    rng = np.random.default_rng(11)
    c = (0.5, -0.25, 3.0)
    pairs = [
        (PlacedTorus(2.0, 0.5, Placement(translate=c)), Torus(c, 2.0, 0.5)),
        (PlacedTorus(2.0, 0.5, Placement(scale=(0.25,) * 3, translate=c)), Torus(c, 0.5, 0.125)),
        (PlacedTorus(0.75, 0.1, Placement(scale=(8.0,) * 3, translate=c)), Torus(c, 6.0, 0.8)),
    ]
    hits = 0
    for placed, plain in pairs:
        # Aimed at points within 1.5 tube radii of the ring: hits and misses.
        big, small = plain.major_radius, plain.minor_radius
        phi = rng.uniform(0, 2 * np.pi, 40)
        ring = np.c_[big * np.cos(phi), big * np.sin(phi), np.zeros(40)] + np.asarray(c)
        target = ring + rng.uniform(-1.5, 1.5, (40, 3)) * small
        o = np.asarray(c) + rng.normal(size=(40, 3)) * 3 * (big + small)
        for oi, di in zip(o, target - o, strict=True):
            a, b = truth.first_hit(placed, oi, di), truth.first_hit(plain, oi, di)
            assert _same(a, b), (placed, oi, di, a, b)
            hits += a[0]
            assert truth.side(placed, oi) == truth.side(plain, oi)
    assert 20 < hits < 100  # of 120: both hits and misses were compared
    tor = PlacedTorus(1.0, 0.3, Placement((1.5, 0.7, 2.0), (1.0, 2.0, -0.5), 41.0, (3.0, 1.0, 2.0)))
    o = np.array([3.0, 1.0, 2.0]) + rng.normal(size=(40, 3)) * 6
    d = np.array([3.0, 1.0, 2.0]) + rng.uniform(-2, 2, (40, 3)) - o
    scaled = 0
    for k in (-20, 7):
        big = tor.scaled(2.0**k)
        for oi, di in zip(o, d, strict=True):
            h, t = truth.first_hit(tor, oi, di)
            h2, t2 = truth.first_hit(big, oi * 2.0**k, di)
            assert h == h2 and (not h or abs(t2 - t * 2**k) <= SAME * t2)
            scaled += h
    assert 10 < scaled < 70  # of 80


def test_the_transformed_cylinder_is_the_cylinder_where_the_transform_changes_nothing():
    """A translation; a stretch by 4 along the axis (the frame keeps z, so scale (1, 1, 4) is
    the cylinder 4 times as tall); a power-of-two scale: the world-space truth
    (study/truth_scenes.py _cylinder1) on the same rays, to 100 digits."""
    rng = np.random.default_rng(12)
    b = (1.0, 2.0, -0.5)
    top = lambda h: (b[0], b[1], b[2] + h)  # noqa: E731
    pairs = [
        (PlacedCylinder(0.5, 3.0, Placement(translate=b)), Cylinder(b, top(3.0), 0.5)),
        (PlacedCylinder(0.5, 3.0, Placement(scale=(1.0, 1.0, 4.0), translate=b)),
         Cylinder(b, top(12.0), 0.5)),
        (PlacedCylinder(0.5, 3.0, Placement(scale=(0.125,) * 3, translate=b)),
         Cylinder(b, top(0.375), 0.0625)),
    ]  # fmt: skip
    hits = 0
    for placed, plain in pairs:
        # Aimed at points within 1.5 radii of the axis, from below the base to above the top.
        h, r = plain.top[2] - plain.base[2], plain.radius
        target = np.asarray(b) + np.c_[rng.uniform(-1.5, 1.5, (40, 2)) * r,
                                       rng.uniform(-0.2, 1.2, 40) * h]  # fmt: skip
        o = np.asarray(top(h / 2)) + rng.normal(size=(40, 3)) * 3 * h
        for oi, di in zip(o, target - o, strict=True):
            x, y = truth.first_hit(placed, oi, di), truth.first_hit(plain, oi, di)
            assert _same(x, y), (placed, oi, di, x, y)
            hits += x[0]
            assert truth.side(placed, oi) == truth.side(plain, oi)
    assert 20 < hits < 100


def test_the_two_routes_agree_on_the_familys_rays():
    """Route 1 (the exact inverse, the exact quadratic or Sturm's quartic) against route 2
    (mpmath's LU inverse, the half chord or Ferrari) on the family's primary rays and on rtlab's
    spawned rays (truth._check raises TruthError where they differ), every 3rd ray of each."""
    (rtlab,) = [m for m in methods(False, False) if m.name == "rtlab"]
    checked = {True: 0, False: 0}
    for knob in FAMILIES[FAMILY].quick_values:
        for case in _cases(knob):
            tr = rtlab.trace(case.shape, case.origins, case.directions)
            o2 = rtlab.spawn(tr, case.leave)
            rays = [(case.origins, case.directions), (o2, case.leave)]
            for o, d in rays:
                for i in range(0, len(o), 3):  # 3: outward (even) and inward (odd) alike
                    h, t = truth.first_hit(case.shape, o[i], d[i])
                    truth._check(case.shape, o[i], d[i], np.inf, h, t)
                    checked[bool(h)] += 1
    # Both decisions were checked: the outward spawned rays of a convex cylinder miss; those
    # of a torus may meet it again, and every inward one does.
    assert checked[True] > 400 and checked[False] > 100, checked


def test_the_metric_catches_a_spawn_without_offset():
    """The judge can fail rtlab: its spawned rays started at the hit point itself (no offset by
    the error bound) meet the surface they leave, on the transformed shapes too."""
    (rtlab,) = [m for m in methods(False, False) if m.name == "rtlab"]
    bare = dataclasses.replace(rtlab, spawn=lambda tr, toward: tr.p)
    from study.metrics import spawn

    worst = max(spawn(case, bare)[0]["self_hits"] for case in _cases(1e8, 200))
    assert worst > 0.05
    assert all(spawn(case, rtlab)[0]["self_hits"] == 0 for case in _cases(1e8, 200))
