"""rtlab-float is rtlab's own algorithms in float only if the port is faithful: run in float64,
study/rtlab_float.py must decide every quick ray of every family as the extension does, give
the same t (meshes: within one ulp, see below), spawn the same origins and occlude the same
shadow rays."""

from __future__ import annotations

import numpy as np
import pytest

from study import rtlab_float
from study.families import FAMILIES, Case
from study.methods import _rtlab_occluded, _rtlab_spawn, _rtlab_trace, methods, ulps
from study.run import QUICK_RAYS, SEED

PORTED = {"sphere", "plane", "triangle", "box", "mesh"}


def _quick_cases() -> list[tuple[str, float, Case]]:
    out = []
    for index, (name, family) in enumerate(FAMILIES.items()):
        for value in family.quick_values:
            rng = np.random.default_rng([SEED, index, family.values.index(value)])
            out += [(name, value, c) for c in family.generate(value, QUICK_RAYS, rng)
                    if c.shape.kind in PORTED]  # fmt: skip
    return out


CASES = _quick_cases()
TRACE64, SPAWN64, OCCLUDED64 = rtlab_float.port(np.float64)


def test_the_quick_rays_cover_every_ported_primitive():
    assert {c.shape.kind for _, _, c in CASES} == PORTED


@pytest.mark.parametrize("protocol", ["decision", "spawn", "shadow", "scale"])
def test_in_double_the_port_decides_as_the_extension(protocol):
    checked = 0
    for name, value, case in CASES:
        if case.protocol != protocol:
            continue
        ours = _rtlab_trace(case.shape, case.origins, case.directions)
        port = TRACE64(case.shape, case.origins, case.directions)
        where = f"{name} at {value:g}, {case.shape.kind}"
        assert np.array_equal(ours.hit, port.hit), where
        both = ours.hit & port.hit
        # Exactly the same t for the primitives the port computes in the C++'s order. A mesh's
        # closest triangle is found through the extension's hierarchy, in another order than
        # the port's triangle by triangle; two triangles sharing the edge a ray crosses have t
        # one ulp apart, and which one wins the closed comparison t_scaled <= t_max det (both
        # rounded) depends on the order: one ulp.
        allowed = 1.0 if case.shape.kind == "mesh" else 0.0
        assert np.max(ulps(port.t[both], ours.t[both]), initial=0) <= allowed, where
        if case.shape.kind != "mesh":
            assert np.array_equal(port.p[both], ours.p[both]), where
            assert np.array_equal(port.p_error[both], ours.p_error[both]), where
            assert np.array_equal(port.n[both], ours.n[both]), where
        checked += int(both.sum())
    assert checked > 100  # the protocol's rays were traced, and hit


def test_in_double_the_port_spawns_and_occludes_as_the_extension():
    spawned = occluded = 0
    for name, value, case in CASES:
        if case.protocol not in ("spawn", "shadow"):
            continue
        where = f"{name} at {value:g}, {case.shape.kind}"
        tr = _rtlab_trace(case.shape, case.origins, case.directions)
        if not tr.hit.any():
            continue
        keep = tr.hit
        sub = type(tr)(tr.hit[keep], tr.t[keep], tr.p[keep], tr.p_error[keep], tr.n[keep])
        toward = case.leave[keep] if case.leave is not None else np.array(case.light) - sub.p
        o2 = _rtlab_spawn(sub, toward)
        assert np.array_equal(SPAWN64(sub, toward), o2), where
        spawned += len(o2)
        d2 = toward if case.leave is not None else np.array(case.light) - o2
        reach = np.ones(len(o2)) if case.leave is None else np.full(len(o2), np.inf)
        a = _rtlab_occluded(case.shape, o2, d2, reach)
        assert np.array_equal(OCCLUDED64(case.shape, o2, d2, reach), a), where
        occluded += int(a.sum()) + int((~a).sum())
    assert spawned > 100 and occluded == spawned


def test_gamma_is_the_unit_roundoff_of_the_type():
    # gamma(1) = u / (1 - u): u = 2^-24 for float (float's 24-bit significand), 2^-53 for double.
    assert rtlab_float.gamma(1, np.float32) == np.float32(2.0**-24) / np.float32(1 - 2.0**-24)
    assert rtlab_float.gamma(1, np.float64) == 2.0**-53 / (1 - 2.0**-53)
    assert rtlab_float.gamma(3, np.float32).dtype == np.float32


def test_the_identity_transform_turns_minus_zero_into_zero():
    """Why the port keeps 13_transform.h's apply(): a box's ray in a face plane with a -0.0
    direction component is a hit in the extension (the identity makes it +0.0) and would be a
    miss without it ((face - o) * (1 / -0.0) = 0 * -inf)."""
    from study.shapes import Box

    box = Box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
    o, d = np.array([[2.0, 0.5, 1.0]]), np.array([[-1.0, 0.0, -0.0]])  # in the face z = 1
    assert _rtlab_trace(box, o, d).hit[0] and TRACE64(box, o, d).hit[0]
    d32 = d.astype(np.float32)
    assert np.signbit(d32[0, 2]) and not np.signbit(rtlab_float.apply_identity(d32, 0)[0, 2])


def test_rtlab_float_is_a_method_of_the_study():
    m = {x.name: x for x in methods(include_mitsuba=False, include_embree=False)}["rtlab-float"]
    assert m.precision == "float" and m.kinds >= PORTED
    tr = m.trace(CASES[0][2].shape, CASES[0][2].origins, CASES[0][2].directions)
    assert tr.p_error is not None  # it keeps its own error bound, as rtlab does
