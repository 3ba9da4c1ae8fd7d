"""The stiff study's tori: the exact truth on rays checked by hand, rtlab's decisions in the
quick run of the two torus families (run here alone: the whole quick run is
tests/study/test_quick.py's), POV-Ray with and without
``sturm`` on rays rebuilt as its camera makes them, and what the numbers show about the
textbook's closed-form quartic."""

from __future__ import annotations

import math

import numpy as np
import pytest

from study import truth
from study.families_torus import pixel_rays
from study.methods import methods
from study.methods_torus import povray_hits, povray_version
from study.shapes import PinholeCamera, Torus
from tests.study.test_quick import value


@pytest.fixture(scope="module")
def quick():
    """The quick run's rows of the torus families (the same seeds as the whole quick run)."""
    from study.families import FAMILIES
    from study.run import run_family

    everyone = methods(include_mitsuba=False, include_embree=False)
    rows = []
    for name in ("torus-tube", "torus-distance"):
        rows += run_family(FAMILIES[name], True, everyone)[0]
    return None, rows


RING = Torus((0.0, 0.0, 0.0), 2.0, 0.5)


def _truth(shape, o, d):
    return truth.truth(shape, np.array(o, dtype=float), np.array(d, dtype=float))


def test_truth_on_rays_checked_by_hand():
    # Along the x axis through the centre: the outer equator at x = -(R + r) = -2.5, so t is
    # 7.5 (and 1.875 for the direction 4 times as long); from the centre along y, the inner
    # equator at R - r = 1.5; down the axis, through the hole: a miss. The centre moved by
    # dyadic amounts changes none of it. Both routes run on every ray (truth() checks them).
    moved = Torus((1.5, -2.0, 0.25), 2.0, 0.5)
    tr = _truth(RING, [(-10, 0, 0), (-10, 0, 0), (0, 0, 0), (0, 0, -10)],
                [(1, 0, 0), (4, 0, 0), (0, 1, 0), (0, 0, 1)])  # fmt: skip
    assert tr.hit.tolist() == [True, True, True, False]
    assert tr.t[:3].tolist() == [7.5, 1.875, 1.5]
    assert [x == y for x, y in zip(tr.t_exact[:3], (7.5, 1.875, 1.5), strict=True)] == [True] * 3
    assert not tr.undecidable.any()
    tm = _truth(moved, [(1.5 - 10, -2.0, 0.25)], [(1, 0, 0)])
    assert tm.hit[0] and tm.t[0] == 7.5
    # A tube 2^-30 thin: t = 9 - 2^-30 exactly (34 bits, a double), decided and exact.
    thin = Torus((0.0, 0.0, 0.0), 1.0, 2.0**-30)
    tt = _truth(thin, [(-10, 0, 0)], [(1, 0, 0)])
    assert tt.t[0] == 9 - 2.0**-30 and tt.t_exact[0] == 9 - 2.0**-30


def test_a_tangent_ray_is_a_hit_and_undecidable():
    # y = R + r in the plane z = 0 touches the outer equator at x = 0 (a double root); z = r
    # over the ring's circle at y = R touches the tube's top: rho >= R, so (rho - R)^2 + r^2
    # >= r^2 with equality only at x = 0. One ulp of y either way misses or cuts: no double
    # method can decide them, and the truth says so. 1e-9 away they are decided.
    tr = _truth(RING, [(-10, 2.5, 0), (-10, 2.0, 0.5), (-10, 2.5 + 1e-9, 0), (-10, 2.5 - 1e-9, 0)],
                [(1, 0, 0)] * 4)  # fmt: skip
    assert tr.hit.tolist() == [True, True, False, True]
    assert tr.t[0] == 10.0 and tr.t[1] == 10.0
    assert tr.undecidable.tolist() == [True, True, False, False]
    # The hit that cuts 1e-9 inside: the chord's half is sqrt(2.5^2 - y^2) = sqrt(e (5 - e)),
    # e = 2.5 - y (exact: Sterbenz), ~7.07e-5; sqrt's and the subtraction's rounding: 1e-14.
    e = 2.5 - (2.5 - 1e-9)
    assert abs(tr.t[3] - (10 - math.sqrt(e * (5 - e)))) < 1e-14
    assert tr.separation[3] < 1e-3  # grazing: t ill-conditioned, left out of the t metric


def test_side_and_error_bound_of_the_tube():
    assert [truth.side(RING, p) for p in ((2.5, 0, 0), (2.6, 0, 0), (2.0, 0, 0))] == [0, 1, -1]
    assert truth.within_bound(RING, (2.5, 1e-9, 0), (1e-8, 1e-8, 1e-8))
    assert not truth.within_bound(RING, (2.5 + 1e-7, 0, 0), (1e-8, 1e-8, 1e-8))


def test_rtlab_decides_every_decidable_torus_ray(quick):
    _, rows = quick
    mine = [r for r in rows if r["family"].startswith("torus-") and r["method"] == "rtlab"]
    assert {r["family"] for r in mine} == {"torus-tube", "torus-distance"}
    for r in mine:
        if r["metric"] in ("wrong_decisions", "nan_inf", "bound_violations"):
            assert r["value"] == 0, r
        if r["metric"] == "t_error_ulps_max_separated":
            # The bisection on the tube distance ends on adjacent doubles of s (one ulp), t =
            # (s0 + s) / |d| adds two roundings and the truth's own rounding half an ulp: 4.
            assert r["value"] <= 4, r
    # The thinnest tube's grazing rays reach the undecidable band (counted apart, not
    # excused): k up to 52 on a tube of r = 1e-8 R, where one ulp of the origin moves the ray
    # by about 1e-8 of r.
    (thin,) = [r for r in mine if r["knob_value"] == 1e-8 and r["metric"] == "wrong_decisions"]
    assert thin["undecidable"] > thin["rays"] // 20


def test_povray_with_and_without_sturm_named_with_its_version(quick):
    _, rows = quick
    versions = {r["method"]: r["version"] for r in rows if r["method"].startswith("povray")}
    assert set(versions) == {"povray", "povray-sturm"}
    assert set(versions.values()) == {povray_version()}
    assert povray_version().startswith("POV-Ray 3.7")
    # Only on the camera's own rays: every POV-Ray row is a torus-distance row.
    assert {r["family"] for r in rows if r["method"].startswith("povray")} == {"torus-distance"}
    # Its image tells hit from miss only: no t error rows (its t is a placeholder), and
    # both_hits 0 says why, while rtlab's t rows are there on the same rays.
    mine = [r for r in rows if r["method"].startswith("povray")]
    assert not [r for r in mine if r["metric"].startswith("t_error")]
    assert {r["value"] for r in mine if r["metric"] == "both_hits"} == {0.0}
    assert any(r["method"] == "rtlab" and r["family"] == "torus-distance"
               and r["metric"] == "t_error_ulps_max" for r in rows)  # fmt: skip


def _camera() -> tuple[Torus, PinholeCamera]:
    """A torus 10 radii away, off the view's centre (so that a mirrored or shifted image would
    not match), 24 x 24 pixels."""
    tor = Torus((0.0625, -0.03125, 0.015625), 0.03125, 0.0078125)
    w = np.array([0.48, -0.6, 0.64])  # unit
    e1 = np.cross(w, [0.0, 0.0, 1.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(w, e1)
    eye = np.array(tor.center) + w * 10 * tor.major_radius
    spread = 2.6 * (tor.major_radius + tor.minor_radius) / (10 * tor.major_radius)
    look = -w + 0.3 * spread * e1  # off centre by 0.3 of the view
    cam = PinholeCamera(tuple(eye), tuple(look), tuple(e1 * spread), tuple(e2 * spread), 24, 24)  # type: ignore[arg-type]
    return Torus(tor.center, tor.major_radius, tor.minor_radius, cam), cam


@pytest.mark.parametrize("sturm", [True, False])
def test_the_rebuilt_pixel_rays_are_povrays(sturm):
    shape, cam = _camera()
    o, d = pixel_rays(cam)
    exact = _truth(shape, o, d).hit
    # Well-conditioned pixels: the truth stays the same when the pixel's point moves by 0.01
    # pixel each way (POV-Ray's own solver errs far below that on a torus 10 radii away).
    steady = np.ones(len(o), dtype=bool)
    for shift in ((0.01, 0), (-0.01, 0), (0, 0.01), (0, -0.01)):
        so, sd = pixel_rays(cam, shift)
        steady &= truth.truth(shape, so, sd, conditioning=False, check_every=10**9).hit == exact
    assert np.sum(steady & exact) >= 40 and np.sum(steady & ~exact) >= 40
    pov = povray_hits(shape, sturm)
    assert np.array_equal(pov[steady], exact[steady])
    # The test could fail: rays half a pixel off, or the image mirrored, disagree with POV-Ray.
    ho, hd = pixel_rays(cam, (0.5, 0.0))
    half = truth.truth(shape, ho, hd, conditioning=False, check_every=10**9).hit
    assert np.any(half[steady] != pov[steady])
    mirrored = exact.reshape(24, 24)[:, ::-1].reshape(-1)
    assert np.any(mirrored[steady] != pov[steady])


def test_the_textbook_quartic_loses_the_thin_tube(quick):
    _, rows = quick
    # Suffern's constant coefficient e^2 - 4 R^2 (r^2 - z^2), e = |o|^2 - R^2 - r^2, is the
    # difference of numbers near R^4 whose true value near the tube is about 4 R^2 (m^2 - r^2)
    # (m: the ray's distance from the tube's circle): its rounding, u R^4, is the whole of it
    # once r / R is near sqrt(u) ~ 1e-8 (double) or 2e-4 (float), so the closed form decides
    # those tubes' grazing rays by rounding, where rtlab, on the same rays, decides all.
    thick = value(rows, "torus-tube", 0.1, "textbook-double", "wrong_decisions")
    thin = value(rows, "torus-tube", 1e-8, "textbook-double", "wrong_decisions")
    assert thin > 0.1 and thin > 3 * thick
    assert value(rows, "torus-tube", 1e-8, "rtlab", "wrong_decisions") == 0
    # Float loses a thick tube's grazing rays already (u ~ 6e-8: its band is 2^29 wider).
    assert value(rows, "torus-tube", 0.1, "textbook-float", "wrong_decisions") > 3 * thick
    # Ferrari's formula loses t's digits even where it decides right (Cardano's cube roots of
    # nearly cancelling terms): thousands of ulps on the thick tube, rtlab a few.
    assert value(rows, "torus-tube", 0.1, "textbook-double", "t_error_ulps_max_separated") > 1e3


def test_povray_loses_the_torus_from_far_away(quick):
    _, rows = quick
    # At 10 radii POV-Ray's closed form decides every pixel; with sturm one pixel of the 1024
    # is a hit where the ray misses: a near miss whose quartic's roots are a complex pair of
    # relative imaginary part 6e-5 (measured), within the 1e-4 its Sturm bisection stops at
    # (ROOT_TOLERANCE, torus.cpp): the quartic dips close enough to zero to be called a root.
    assert value(rows, "torus-distance", 10.0, "povray", "wrong_decisions") == 0
    assert value(rows, "torus-distance", 10.0, "povray-sturm", "wrong_decisions") <= 2 / 1024
    # At 1e8 radii it misses every pixel that shows the torus (the whole image black), both
    # ways, though every t is within its (1e-4, 1e7) (study/families_torus.py): the two solvers
    # share the quartic and its bounding test (Torus::Intersect, Test_Thick_Cylinder); which of
    # them loses the torus, the study does not say.
    for method in ("povray", "povray-sturm"):
        far = value(rows, "torus-distance", 1e8, method, "wrong_decisions")
        hits = value(rows, "torus-distance", 1e8, "rtlab", "wrong_decisions")
        assert far > 0.01 and hits == 0


def test_methods_on_tori_are_listed():
    names = {m.name for m in methods(include_mitsuba=False, include_embree=False)
             if "torus" in m.kinds or "torus-camera" in m.kinds}  # fmt: skip
    assert names == {"rtlab", "textbook-double", "textbook-float", "povray", "povray-sturm"}


def test_rtlab_decides_grazing_rays_of_a_tube_1e8_thin():
    # The regression the fix in tracer/cpp/18_torus.h is for: rays along z in the plane y = 0
    # at rho = R + r (1 -+ 2^-k) from the axis, R = 1, r = 2^-27 (about 7e-9): they cut or
    # miss the tube by r 2^-k, 2^-47 at k = 20, far above a one-ulp move of the origin (2^-52:
    # the truth calls them decidable). The quartic's constant term, A^2 - 4 R^2 x^2 with
    # A^2 ~ 4, rounds by 2^-50 where its true value is about 4 r^2 2^-k: the old code decided
    # all of them by rounding; the tube distance's sign decides them.
    thin = Torus((0.0, 0.0, 0.0), 1.0, 2.0**-27)
    ks = np.arange(1, 21, dtype=float)
    x = np.concatenate([1 + 2.0**-27 * (1 - 2.0**-ks), 1 + 2.0**-27 * (1 + 2.0**-ks)])
    o = np.c_[x, np.zeros_like(x), np.full_like(x, -3.0)]
    d = np.tile([0.0, 0.0, 1.0], (len(x), 1))
    tr = truth.truth(thin, o, d)
    assert tr.hit.tolist() == [True] * 20 + [False] * 20
    assert not tr.undecidable.any()
    (rtlab,) = [m for m in methods(include_mitsuba=False, include_embree=False)
                if m.name == "rtlab"]  # fmt: skip
    got = rtlab.trace(thin, o, d)
    assert got.hit.tolist() == tr.hit.tolist()
    # t: where the ray enters the tube, 3 - sqrt(r^2 - (x - R)^2); a few ulps (the bisection's
    # last bit, the shift back to the origin: see test_rtlab_decides_every_decidable_torus_ray).
    assert np.all(np.abs(got.t[:20] - tr.t[:20]) <= 4 * np.spacing(tr.t[:20]))
