"""Rays the study found rtlab failing on until 15_triangle.h was fixed, frozen as hex floats
(from failures.json of `rtlab study stiff --quick`, family triangles, knob 1): the truth, the
textbook formula and rtlab on each, without running the study. And the rays other methods fail
on, frozen per family in tests/study/frozen/ (study/freeze.py): the truth decides each, rtlab
gets each right, and the method it was frozen for still fails it."""

from __future__ import annotations

import functools
import json
from pathlib import Path

import numpy as np
import pytest

from study import truth
from study.methods import _rtlab_trace, _textbook
from study.shapes import Triangle
from tracer.cli import main

#: (vertices, origin, direction): rays nearly in the triangle's plane (within 1e-12 radians),
#: aimed at interior points; the exact answer is a hit no one-ulp move flips.
NEARLY_IN_PLANE = [
    (
        [["-0x1.6ee4d40000000p-1", "0x1.39a28c0000000p-1", "-0x1.5fa52a0000000p-2"],
         ["-0x1.728bc20000000p-1", "0x1.387c820000000p-1", "-0x1.61fb320000000p-2"],
         ["-0x1.70832e0000000p-1", "0x1.3b6f880000000p-1", "-0x1.5903580000000p-2"]],
        ["-0x1.77bb990bc59e2p-1", "0x1.40ccd2fa4f3d4p-1", "-0x1.444929b73dc7ap-2"],
        ["0x1.f42a6825cfb00p-7", "-0x1.9cb0cd61d2b00p-7", "-0x1.890d2e215fb00p-6"],
    ),
    (
        [["0x1.e576c20000000p-1", "0x1.ec32e00000000p-3", "-0x1.a77d280000000p-3"],
         ["0x1.e6aee60000000p-1", "0x1.ed9e220000000p-3", "-0x1.a5cbf40000000p-3"],
         ["0x1.e597fe0000000p-1", "0x1.ec51700000000p-3", "-0x1.9edd6c0000000p-3"]],
        ["0x1.e8315a926475ep-1", "0x1.ef79fbf20dc37p-3", "-0x1.bedebce5f5b9bp-3"],
        ["-0x1.2b741c1f4b500p-8", "-0x1.6a95da4cc4780p-10", "0x1.a14e9abca6b40p-7"],
    ),
]  # fmt: skip


def _case(entry):
    v, o, d = entry
    tri = Triangle(*(tuple(float.fromhex(x) for x in p) for p in v))
    return tri, np.array([[float.fromhex(x) for x in o]]), np.array([[float.fromhex(x) for x in d]])


@pytest.mark.parametrize("entry", NEARLY_IN_PLANE)
def test_the_truth_and_moeller_trumbore_hit_them(entry):
    tri, o, d = _case(entry)
    t = truth.truth(tri, o, d)
    assert t.hit[0] and not t.undecidable[0]
    assert _textbook(np.float64)(tri, o, d).hit[0]


def _delta_t(tri, o, d):
    """15_triangle.h's intersect_triangle up to its t and triangle_t_error (pbrt-v4 6.8.3's
    conservative deltaT), in double as written there (the core is built -ffp-contract=off)."""
    u = 2.0**-53
    g = lambda n: n * u / (1 - n * u)  # noqa: E731
    kz = int(np.argmax(np.abs(d)))
    kx, ky = (kz + 1) % 3, (kz + 2) % 3
    sx, sy, sz = -d[kx] / d[kz], -d[ky] / d[kz], 1 / d[kz]
    rel = [np.array(v) - o for v in (tri.a, tri.b, tri.c)]
    xs = [r[kx] + sx * r[kz] for r in rel]
    ys = [r[ky] + sy * r[kz] for r in rel]
    zs = [sz * r[kz] for r in rel]
    e = [xs[j] * ys[k] - ys[j] * xs[k] for j, k in ((1, 2), (2, 0), (0, 1))]
    inv = 1 / (e[0] + e[1] + e[2])
    t = (e[0] * zs[0] + e[1] * zs[1] + e[2] * zs[2]) * inv
    mx, my, mz = (max(abs(c) for c in cs) for cs in (xs, ys, zs))
    dz, dx, dy = g(3) * mz, g(5) * (mx + mz), g(5) * (my + mz)
    de = 2 * (g(2) * mx * my + dy * mx + dx * my)
    me = max(abs(x) for x in e)
    return t, 3 * (g(3) * me * mz + de * mz + dz * me) * abs(inv), e


@pytest.mark.parametrize("entry", NEARLY_IN_PLANE)
def test_why_the_sheared_bound_alone_rejected_them(entry):
    """Not the edge functions: they have the exact signs (all three one way: inside). The
    self-intersection guard alone would reject the hit: triangle_t_error grows as 1 / det, and
    for a ray this close to the plane det is tiny, so the bound (about 2) exceeds t (about 1);
    hence the world-space check beside it."""
    tri, o, d = _case(entry)
    t, delta_t, e = _delta_t(tri, o[0], d[0])
    assert all(x > 0 for x in e) or all(x < 0 for x in e)
    assert 0.99 < t < 1.01 and delta_t > t


@pytest.mark.parametrize("entry", NEARLY_IN_PLANE)
def test_rtlab_hits_them(entry):
    """They were rtlab's misses until 15_triangle.h kept a hit whose ray certainly starts off
    the plane and heads into it (starts_off_the_plane_heading_in): regression rays."""
    tri, o, d = _case(entry)
    assert _rtlab_trace(tri, o, d).hit[0]


# ------------------------------------------------- rays frozen from the study's failures.json

FROZEN = Path(__file__).parent / "frozen"
ENTRIES = [(p.stem, i, e) for p in sorted(FROZEN.glob("*.json"))
           for i, e in enumerate(json.loads(p.read_text()))]  # fmt: skip


@functools.cache
def _methods():
    from study.methods import methods

    return {m.name: m for m in methods()}


def test_rays_are_frozen_for_most_families_and_methods():
    """Written by `rtlab study freeze --from OUT/failures.json --out tests/study/frozen` from
    the quick run (`rtlab study stiff --quick --out OUT`)."""
    assert len({f for f, _, _ in ENTRIES}) >= 6
    assert {e["method"] for _, _, e in ENTRIES} >= {"textbook-double", "textbook-float",
                                                    "rtlab-float", "embree"}  # fmt: skip
    assert {e["protocol"] for _, _, e in ENTRIES} >= {"decision", "spawn", "shadow"}


IDS = [f"{f}-{i}-{e['method']}-{e['metric']}" for f, i, e in ENTRIES]


@pytest.mark.parametrize(("family", "index", "entry"), ENTRIES, ids=IDS)
def test_frozen_ray_rtlab_right_and_the_failure_reproduced(family, index, entry):
    from study.freeze import failing_metrics

    # The truth still decides it, and rtlab gets it right.
    assert failing_metrics(entry, _methods()["rtlab"]) == set()
    method = _methods()[entry["method"]]
    if method.version != entry["version"]:
        pytest.skip(f"{method.name} is {method.version} here, the ray was frozen with "
                    f"{entry['version']}")  # fmt: skip
    # And the method it was frozen for still fails it the same way: still a stiff ray.
    assert entry["metric"] in failing_metrics(entry, method)


def test_freeze_picks_a_few_per_method_and_refuses_bad_input(tmp_path, capsys):
    from study.freeze import freeze

    base = ENTRIES[0][2] | {"method": "textbook-float"}
    fails = [base | {"knob_value": k, "method": m} for k in (1.0, 1.0, 2.0, 3.0)
             for m in ("textbook-float", "rtlab")]  # fmt: skip
    (entries,) = freeze(fails, per=2).values()
    # Two per method and metric, from different knob values; rtlab's failures are bugs to
    # fix, not rays to freeze.
    picked = [(e["method"], e["knob_value"]) for e in entries]
    assert picked == [("textbook-float", 1.0), ("textbook-float", 2.0)]
    assert main(["study", "freeze", "--from", str(tmp_path / "none.json"), "--out",
                 str(tmp_path)]) == 2  # fmt: skip
    assert "none.json: no such file" in capsys.readouterr().err
    (tmp_path / "f.json").write_text(json.dumps(fails))
    assert main(["study", "freeze", "--from", str(tmp_path / "f.json"), "--out",
                 str(tmp_path / "fz")]) == 0  # fmt: skip
    assert len(json.loads((tmp_path / "fz" / f"{base['family']}.json").read_text())) == 2
