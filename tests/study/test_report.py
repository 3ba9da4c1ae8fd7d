"""The study's report pieces on rows made by hand, where the answer is known: the Pareto front
of error against run time, and the t-error panel's "no data"."""

from __future__ import annotations

import json

import pytest

from study.report import pareto_points, plot_pareto


def _row(family, knob, method, metric, value, rays=100):
    return {"family": family, "knob": "k", "knob_value": knob, "method": method,
            "version": "1", "metric": metric, "value": value, "rays": rays,
            "undecidable": 0}  # fmt: skip


ROWS = [
    # a: fast and wrong; b: slow and right; c: slower than b and as wrong as a (dominated);
    # d: has only the first family, so the common rows are family f alone.
    *(
        _row("f", 1.0, m, "wrong_decisions", w)
        for m, w in (("a", 0.5), ("b", 0.0), ("c", 0.5), ("d", 0.25))
    ),
    *(
        _row("f", 1.0, m, "time_per_ray_s", t)
        for m, t in (("a", 1e-7), ("b", 1e-6), ("c", 1e-5), ("d", 1e-6))
    ),
    *(_row("g", 1.0, m, "self_hits", w) for m, w in (("a", 0.1), ("b", 0.0), ("c", 0.3))),
    *(_row("g", 1.0, m, "time_per_ray_s", 1e-6) for m in ("a", "b", "c")),
    _row("g", 1.0, "a", "missed_far", 0.9),  # not a headline share: not counted as wrong
]


def test_pareto_front_and_common_rows():
    pts = {p["method"]: p for p in pareto_points(ROWS)}
    assert pts["a"]["error"] == (0.5 + 0.1) / 2  # weighted by rays, equal here
    # (v1 n + v2 n) / 2n rounds differently from (v1 + v2) / 2: a few ulps.
    assert pts["a"]["time_per_ray_s"] == pytest.approx((1e-7 + 1e-6) / 2, rel=1e-14)
    assert pts["d"]["cells"] == 1 and pts["a"]["common_cells"] == 1  # only f is common
    assert pts["a"]["common_error"] == 0.5
    assert [m for m, p in pts.items() if p["common_front"]] == ["a", "b"]
    # On their own rows d (0.25 wrong at 1e-6 s) is dominated by b (0 wrong, as fast).
    assert [m for m, p in pts.items() if p["front"]] == ["a", "b"]


def test_pareto_plot_is_written_with_alt_text(tmp_path):
    alt = plot_pareto(pareto_points(ROWS), tmp_path / "pareto.png")
    assert (tmp_path / "pareto.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "on the Pareto front a, b" in alt and "fewest wrong: b" in alt
    json.dumps(pareto_points(ROWS), allow_nan=False)  # valid JSON: no NaN


def test_a_method_that_hits_nothing_has_no_t_error_not_zero():
    """The flaw fixed: a method that misses every ray reported t error 0 (perfect). Now the t
    metrics are left out where no ray is a hit for both, both_hits says so, and a knob value's
    t error is over the cases that have one."""
    import numpy as np

    from study import metrics, truth
    from study.families import Case
    from study.methods import Method, Traced, _rtlab_trace
    from study.run import _Acc
    from study.shapes import Sphere

    def misses(shape, o, d):
        n = len(o)
        return Traced(np.zeros(n, dtype=bool), np.full(n, np.inf), np.zeros((n, 3)), None,
                      np.zeros((n, 3)))  # fmt: skip

    sphere = Sphere((0.0, 0.0, 0.0), 1.0)
    o = np.array([[0.0, 0.0, 5.0]] * 4)
    d = np.array([[0.0, 0.0, -1.0], [0.1, 0.0, -1.0], [0.0, 0.1, -1.0], [0.0, 0.0, 1.0]])
    case = Case(sphere, o, d)
    tru = truth.truth(sphere, o, d)
    blind = Method("blind", "1", frozenset({"sphere"}), misses, None, None, "double")  # type: ignore[arg-type]
    m, _, _ = metrics.decision(case, blind, tru)
    assert m["both_hits"] == 0 and m["wrong_decisions"] == 0.75
    assert not any(k.startswith("t_error") for k in m)
    seeing = Method("rtlab", "1", frozenset({"sphere"}), _rtlab_trace, None, None, "double")  # type: ignore[arg-type]
    m2, _, _ = metrics.decision(case, seeing, tru)
    assert m2["both_hits"] == 0.75 and m2["t_error_ulps_max"] <= 4
    # Over two cases, one without t: the median is the other's, not halved by a 0.
    acc = _Acc()
    acc.add(m, 4, 0)
    acc.add(m2, 4, 0)
    assert acc.values()["t_error_ulps_median"] == m2["t_error_ulps_median"]
    assert acc.values()["both_hits"] == 0.75 / 2


def test_the_family_plot_says_no_data(tmp_path):
    from study.families import FAMILIES
    from study.report import plot_family

    fam = FAMILIES["grazing"]
    rows = [_row("grazing", k, m, fam.metric, 0.0) for k in (4.0, 20.0) for m in ("a", "b")]
    rows += [_row("grazing", k, "a", t, 2.0) for k in (4.0, 20.0)
             for t in ("t_error_ulps_median", "t_error_ulps_max")]  # fmt: skip
    rows += [_row("grazing", 4.0, "b", t, 1.0) for t in ("t_error_ulps_median", "t_error_ulps_max")]
    alt = plot_family(fam, rows, tmp_path / "g.png")
    assert "a at most 2 ulps" in alt
    assert "b at most 1 ulps (no data at 20)" in alt  # b's 20: no ray a hit for both
    assert (tmp_path / "g.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
