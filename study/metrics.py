"""The metrics of one method on one case, each against the truth (study/truth.py) of the very
rays the method traced:

- ``wrong_decisions``: share of decidable rays whose hit/miss differs from the truth (rays a
  one-ulp move decides differently are counted apart, in ``undecidable``);
- ``t_error_ulps_median`` / ``t_error_ulps_max``: |t - t_true| in ulps of t_true, over the rays
  both call a hit; ``t_error_ulps_max_separated``: over those whose roots are well apart; left
  out (no row) where no ray is a hit for both, never 0 for "no data"; a knob value's median is
  the mean of its cases' medians weighted by their rays;
- ``both_hits``: share of the rays that the method and the truth both call a (decidable) hit:
  what the t metrics are over;
- ``t_error_conditioned_max``: the largest |t - t_true| over how many ulps a one-ulp move of
  the ray moves t_true (at least 1): t's error in units of its own conditioning;
- ``bound_violations``: share of hit points whose own error box holds no point of the true
  surface (methods that report a bound: rtlab);
- ``self_hits``: share of spawned rays that meet the surface they leave (an outward ray at all;
  an inward one before half the true distance to the far side of a closed shape);
  ``missed_far``: inward rays of a closed shape that never reach its far side;
  ``wrong_side``: spawned origins on the wrong side of the true surface (exact);
- ``false_occlusions``: share of shadow rays blocked where nothing lies between;
- ``scale_mismatches``: share of rays whose t does not scale by exactly 2^k;
- ``nan_inf``: share of reported hits with a NaN or infinite t or point;
- ``undecidable_differs``: share of the undecidable rays decided otherwise than the exact truth
  (not an error: it shows the method's convention on edges, faces and planes);
- ``leaks``: for closed meshes, share of the decidable true hits reported as misses;
- ``time_per_ray_s``: wall time of the method's batch over its rays (the same rays for all).

Every function returns (metrics, undecidable count, the indices of the failing rays per
metric)."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import mpmath
import numpy as np

from study import truth as oracle
from study.families import Case
from study.methods import Method, Traced, ulps
from study.shapes import Box, Sphere

Result = tuple[dict[str, float], int, dict[str, np.ndarray]]


def timed(fn: Callable[..., Traced], *args: Any) -> tuple[Traced, float]:
    """The call's result and its wall time (after a warm-up call on two rays, so that building
    a scene or compiling a kernel is not counted)."""
    fn(args[0], args[1][:2], args[2][:2])
    start = time.perf_counter()
    out = fn(*args)
    return out, time.perf_counter() - start


def _share(mask: np.ndarray, of: np.ndarray) -> float:
    n = int(np.sum(of))
    return float(np.sum(mask & of)) / n if n else 0.0


def _nan_inf(tr: Traced) -> float:
    bad = tr.hit & ~(np.isfinite(tr.t) & np.all(np.isfinite(tr.p), axis=1))
    return _share(bad, np.ones(len(bad), dtype=bool))


def decision(case: Case, method: Method, tru: oracle.Truth) -> Result:
    tr, seconds = timed(method.trace, case.shape, case.origins, case.directions)
    decidable = ~tru.undecidable
    wrong = (tr.hit != tru.hit) & decidable
    # The rays both call a hit, for the t metrics (none where the method reports no t).
    both = tr.hit & tru.hit & decidable & method.reports_t
    err = ulps(tr.t, tru.t)
    err = np.where(both, err, np.nan)
    sep = both & (tru.separation >= 0.5)
    m: dict[str, float] = {
        "wrong_decisions": _share(wrong, decidable),
        # How many rays the t metrics are over: where it is 0 they are left out (a method that
        # hits nothing has no t error, not a t error of 0).
        "both_hits": _share(both, np.ones(len(both), dtype=bool)),
        "nan_inf": _nan_inf(tr),
        "time_per_ray_s": seconds / len(case.origins),
        # Inside the band no method is wrong, but which way it goes says which convention it
        # follows (rtlab: edges and faces belong to the shape, like the truth).
        "undecidable_differs": _share(tr.hit != tru.hit, tru.undecidable),
    }
    if both.any():
        m["t_error_ulps_median"] = float(np.nanmedian(err))
        m["t_error_ulps_max"] = float(np.nanmax(err))
    if sep.any():
        # Where the roots are well apart (half chord >= r / 2): t is well conditioned there.
        m["t_error_ulps_max_separated"] = float(np.nanmax(np.where(sep, err, np.nan)))
    if both.any() and tru.t_spread is not None:
        # t's error in units of its own conditioning (how far a one-ulp move of the ray moves
        # the exact t, at least one ulp): a few for a method exact for inputs within an ulp or
        # two, on any ray (for planar shapes, the only root there is may still be ill
        # conditioned: a ray nearly in the plane).
        rel = err / np.maximum(tru.t_spread, 1.0)
        m["t_error_conditioned_max"] = float(np.nanmax(np.where(both, rel, np.nan)))
    fails = {"wrong_decisions": np.flatnonzero(wrong)}
    if case.shape.kind == "mesh":
        # A closed mesh: a decidable true hit reported as a miss went through a crack.
        leak = tru.hit & ~tr.hit & decidable
        m["leaks"] = _share(leak, tru.hit & decidable)
        fails["leaks"] = np.flatnonzero(leak)
    if tr.p_error is not None:
        outside = np.array([bool(h) and not oracle.within_bound(case.shape, p, e)
                            for h, p, e in zip(tr.hit, tr.p, tr.p_error, strict=True)])  # fmt: skip
        m["bound_violations"] = _share(outside, tr.hit)
        fails["bound_violations"] = np.flatnonzero(outside)
    return m, int(np.sum(tru.undecidable)), fails


def spawn(case: Case, method: Method) -> Result:
    assert case.leave is not None and case.outward is not None
    tr, seconds = timed(method.trace, case.shape, case.origins, case.directions)
    hit = tr.hit & np.all(np.isfinite(tr.p), axis=1)
    o2 = method.spawn(tr, case.leave)
    o2 = np.where(hit[:, None], o2, case.origins)  # rays that missed are not spawned
    tr2 = method.trace(case.shape, o2, case.leave)
    by_truth = case.shape.kind in TRUTH_JUDGED
    closed = by_truth or isinstance(case.shape, Sphere | Box)
    outward, inward = hit & case.outward, hit & ~case.outward
    if by_truth:
        self_hit, missed = _judged_by_truth(case, hit, o2, tr2)
    elif closed:
        far = np.array([
            float(t) if (t := oracle.last_exit(case.shape, a, b)) is not None else math.inf
            for a, b in zip(o2, case.leave, strict=True)
        ])  # fmt: skip
        self_hit = (outward & tr2.hit) | (inward & tr2.hit & (tr2.t < 0.5 * far))
        missed = inward & ~tr2.hit
    else:
        self_hit = hit & tr2.hit
        missed = np.zeros(len(hit), dtype=bool)
    want = np.where(case.outward, 1, -1)
    # A spawned origin that is not finite (a float method's offset overflowed) is on no side.
    wrong_side = np.array([bool(h) and (not np.all(np.isfinite(p))
                                        or oracle.side(case.shape, p) != w)
                           for h, p, w in zip(hit, o2, want, strict=True)])  # fmt: skip
    m = {
        "self_hits": _share(self_hit, hit),
        "missed_far": _share(missed, inward) if closed else 0.0,
        "wrong_side": _share(wrong_side, hit),
        "primary_misses": _share(~hit, np.ones(len(hit), dtype=bool)),
        "nan_inf": _nan_inf(tr),
        "time_per_ray_s": seconds / len(case.origins),
    }
    fails = {"self_hits": np.flatnonzero(self_hit), "missed_far": np.flatnonzero(missed)}
    return m, 0, fails


#: Shapes whose spawned rays are judged by the exact first hit from their own spawned origin:
#: a torus is not convex (a ray leaving it may meet it again elsewhere); the cylinder likewise
#: (study/families_curved.py).
TRUTH_JUDGED = ("cylinder", "torus")
#: And the same under a transform (study/families_placed.py).
TRUTH_JUDGED += ("placed-cylinder", "placed-elliptic-cylinder", "placed-torus")


def _judged_by_truth(case: Case, hit: np.ndarray, o2: np.ndarray,
                     tr2: Traced) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """spawn()'s self-hits and missed far sides where the truth says what the spawned ray
    meets: a self-hit is a hit where the exact ray from the spawned origin meets nothing, or
    nearer than half its exact first hit (the surface it leaves, met again at once); a missed
    far side, an inward ray's miss where the exact ray meets the shape. A spawned origin on the
    wrong side is judged from where it starts (and counted in wrong_side); one that is not
    finite is judged by wrong_side alone."""
    assert case.outward is not None and case.leave is not None
    self_hit = np.zeros(len(hit), dtype=bool)
    missed = np.zeros(len(hit), dtype=bool)
    for i in np.flatnonzero(hit & np.all(np.isfinite(o2), axis=1)):
        ok, t = oracle.first_hit(case.shape, o2[i], case.leave[i])
        if tr2.hit[i]:
            self_hit[i] = not ok or tr2.t[i] < 0.5 * float(t)
        else:
            missed[i] = bool(ok) and not case.outward[i]
    return self_hit, missed


def shadow(case: Case, method: Method) -> Result:
    assert case.light is not None
    tr, seconds = timed(method.trace, case.shape, case.origins, case.directions)
    hit = tr.hit & np.all(np.isfinite(tr.p), axis=1)
    light = np.array(case.light)
    o2 = method.spawn(tr, light - tr.p)
    o2 = np.where(hit[:, None], o2, case.origins)
    occ = method.occluded(case.shape, o2, light - o2, np.ones(len(o2))) & hit
    # The truth: nothing lies between a point of a convex surface and a light on its outward
    # side. For the sphere, whether the true hit point sees the light is decided at high
    # precision; within a relative 1e-30 of its horizon the ray is counted undecidable.
    clear = hit.copy()
    undecidable = 0
    if isinstance(case.shape, Sphere):
        c = [mpmath.mpf(x) for x in case.shape.center]
        lm = [mpmath.mpf(x) for x in case.light]
        for i in np.flatnonzero(hit):
            ok, t = oracle.first_hit(case.shape, case.origins[i], case.directions[i])
            if not ok:
                clear[i] = False
                continue
            q = [mpmath.mpf(float(a)) + t * mpmath.mpf(float(b))
                 for a, b in zip(case.origins[i], case.directions[i], strict=True)]  # fmt: skip
            height = sum((lk - qk) * (qk - ck) for lk, qk, ck in zip(lm, q, c, strict=True))
            if abs(height) <= mpmath.mpf("1e-30") * case.shape.radius**2:
                clear[i] = False
                undecidable += 1
            elif height < 0:
                clear[i] = False
    false = occ & clear
    m = {
        "false_occlusions": _share(false, clear),
        "primary_misses": _share(~hit, np.ones(len(hit), dtype=bool)),
        "nan_inf": _nan_inf(tr),
        "time_per_ray_s": seconds / len(case.origins),
    }
    return m, undecidable, {"false_occlusions": np.flatnonzero(false)}


def scale(case: Case, method: Method) -> Result:
    tr, seconds = timed(method.trace, case.shape, case.origins, case.directions)
    s = 2.0**case.scale_k
    tr2 = method.trace(case.shape.scaled(s), case.origins * s, case.directions)
    mismatch = (tr.hit != tr2.hit) | (tr.hit & (tr2.t != tr.t * s))
    m = {
        "scale_mismatches": _share(mismatch, np.ones(len(mismatch), dtype=bool)),
        "nan_inf": _nan_inf(tr),
        "time_per_ray_s": seconds / len(case.origins),
    }
    return m, 0, {"scale_mismatches": np.flatnonzero(mismatch)}
