"""The lesson pages' plots (reports/plots.py): each computed once here by the real renderers,
its figures checked against what the theory or an independent computation says they must be,
and all four shown on a page opened in Chromium."""

import dataclasses
import itertools
import math
from decimal import Decimal, localcontext

import numpy as np
import pytest

from reports import plots
from reports.lesson import build_lesson_page
from reports.site import write_lesson_site
from tests.reports.test_pages import assert_offline_and_whole, browser, images_of, open_page

__all__ = ["browser"]  # the fixture, imported for the page test


@pytest.fixture(scope="module")
def made():
    """Each plot once, as the pages make them (defaults)."""
    return {
        "antialiasing": plots.antialiasing(),
        "global-illumination": plots.global_illumination(),
        "precision": plots.precision(),
        "bounding-volumes": plots.bounding_volumes(),
    }


def by(plot, renderer):
    return sorted((r for r in plot.rows if r["renderer"] == renderer), key=lambda r: r["spp"])


# Slope bands. A point's RMSE is measured over thousands of pixel values whose noise is
# independent from pixel to pixel: its relative standard error is a few per cent (say 5%, for
# the path tracer's heavy tails), and over 3 points spanning a factor 16 in samples the fitted
# slope's standard error is 0.05 / (ln 4 sqrt 2) ~ 0.026. The reference's own noise (checked
# below: at least 3 times below every error) inflates the smallest error by at most 5% and so
# flattens a slope by at most 0.05 / ln 16 ~ 0.02. 0.1 is then about three standard errors
# plus that bias; the seeds are fixed, so the run is the same every time.
SLOPE_BAND = 0.1


def test_antialiasing_points(made):
    p = made["antialiasing"]
    assert {r["renderer"] for r in p.rows} == {"rtlab", "povray", "mitsuba"}
    # n = 1: the same ray through each pixel centre for all three, so the same aliased image:
    # the renderers agree per pixel to their scene-check tolerances (~1e-4, POV-Ray's output
    # precision), which moves an RMSE of ~0.015 by less than 1%.
    centre = [r["rmse"] for r in p.rows if r["n"] == 1]
    assert max(centre) - min(centre) <= 0.01 * min(centre), centre
    for name in ("rtlab", "povray", "mitsuba"):
        errors = [r["rmse"] for r in by(p, name)]
        # Jittered samples converge: every step in n lowers the error, all below the centre's.
        assert all(b < a for a, b in itertools.pairwise(errors)), (name, errors)
        assert all(r["seconds"] > 0 for r in by(p, name))
    # Mitsuba's independent samples: the Monte Carlo slope -1/2 against samples per pixel.
    jittered = [r for r in by(p, "mitsuba") if r["n"] > 1]
    assert plots.slope(jittered, "spp") == pytest.approx(p.fit["slope_mitsuba"])
    assert abs(p.fit["slope_mitsuba"] + 0.5) < SLOPE_BAND
    # Stratified jitter (rtlab's strata, POV-Ray's n x n grid) converges faster than
    # independent samples: between the edge pixels' -3/4 and smooth shading's -1, and beyond
    # the band around -1/2 that independent samples stay in.
    for name in ("rtlab", "povray"):
        assert -1 - SLOPE_BAND < p.fit[f"slope_{name}"] < -0.5 - SLOPE_BAND, name
    # The reference's noise is small enough for the band's argument (at least 3 times below).
    assert p.fit["reference_noise"] * 3 < p.fit["smallest"]
    assert f"{p.fit['slope_rtlab']:.2f}" in p.alt and "-1/2" in p.alt


def test_global_illumination_points(made):
    from reference.convergence import efficiency as convergence_efficiency

    p = made["global-illumination"]
    for name in ("rtlab", "mitsuba"):
        assert abs(p.fit[f"slope_{name}"] + 0.5) < SLOPE_BAND, name
        errors = [r["rmse"] for r in by(p, name)]
        assert all(b < a for a, b in itertools.pairwise(errors)), (name, errors)
    assert p.fit["reference_noise"] * 3 < p.fit["smallest"]
    # The efficiency ratio, again by reference/convergence.py's own fit (c = the geometric
    # mean of rmse sqrt(seconds), as `rtlab bench convergence` reports it).
    rows = [{"renderer": r["renderer"], "value": r["rmse"], "seconds": r["seconds"]}
            for r in p.rows]  # fmt: skip
    c = convergence_efficiency(rows)
    assert p.fit["ratio"] == pytest.approx((c["rtlab"] / c["mitsuba"]) ** 2, rel=1e-12)
    assert f"{p.fit['ratio']:.3g}" in " ".join(p.findings)


def test_exact_t_is_exact():
    """The precision plot's truth, on rays whose t has a closed form."""
    # Head on: t = D - 1 exactly.
    for k in (1, 5, 10):
        d = 10.0**k
        assert plots.exact_t([0.0, 0.0, -d], 1.0, [0.0, 0.0, 0.0], [0.0, 0.0, -1.0]) == d - 1
    # 0.5 to the side: t = D - sqrt(3/4), to 60 digits.
    with localcontext() as ctx:
        ctx.prec = 60
        want = Decimal(10) ** 8 - Decimal("0.75").sqrt()
    got = plots.exact_t([0.0, 0.5, -1e8], 1.0, [0.0, 0.0, 0.0], [0.0, 0.0, -1.0])
    assert abs(got - want) < Decimal(10) ** -45


def test_precision_points(made):
    p = made["precision"]
    assert [r["distance"] for r in p.rows] == [10.0**k for k in range(1, 11)]
    # rtlab's robust quadratic: the roundings on the way from the inputs to t (f, b, l, |l|^2,
    # D, its square root, q, the division: about a dozen), each at most u = 2^-53 relative, and
    # these rays are well conditioned (the centre 0.2 to 0.8 from the ray, so sqrt(D) >= 0.6
    # and the roots are far apart): a relative error of at most ~12 u, 6 ulps of t. Measured
    # under 3.
    assert all(r["rtlab_misses"] == 0 for r in p.rows)
    assert p.fit["worst_ulps"] <= 6
    assert p.fit["worst_ulps"] == max(r["rtlab_ulps"] for r in p.rows)
    # The textbook's error grows as D (its cancellation costs 2^-51 D^2 of a discriminant of
    # ~4): slope 1 in log-log up to 10^7, where the largest of 16 rays' errors fluctuates by
    # at most a factor ~2 from decade to decade, 0.05 in slope over six decades.
    assert p.fit["textbook_slope"] == pytest.approx(1.0, abs=0.15)
    at = {round(math.log10(r["distance"])): r for r in p.rows}
    assert at[7]["textbook"] > 1e4 * max(at[7]["rtlab"], 2.0**-53)
    # Beyond 10^8 the rounding error of 4 D^2 (2^-51 D^2 ~ 4.4 at 10^8) exceeds the true
    # discriminant (4 (1 - 0.8^2) to 4 (1 - 0.2^2)): some of the 16 rays there miss.
    assert sum(at[k]["textbook_misses"] for k in (8, 9, 10)) > 0
    assert all(at[k]["textbook_misses"] == 0 for k in range(1, 8))
    assert "miss" in p.alt and f"{p.fit['worst_ulps']:.2g} ulp" in p.alt


def test_bounding_volume_counts(made):
    """'bounding_box' tests every triangle for each ray that enters the mesh's box (counted by
    a slab test here), 'none' every triangle for every ray (its one root box is all of space:
    tracer/cpp/16_mesh.h Mesh::build), the hierarchy a handful."""
    import dataclasses as dc

    from tracer.render import to_core
    from tracer.scene import load_scene
    from tracer.scene.objects import Mesh

    p = made["bounding-volumes"]
    rows = {r["mode"]: r for r in p.rows}
    assert set(rows) == {"bvh", "bounding_box", "none"}
    triangles = p.fit["triangles"]
    assert triangles == 99785  # the Stanford bunny's, as its scene file says
    # The primary rays that enter the mesh's box, by a slab test here on the core's own rays.
    full = load_scene(plots.SCENES / "bunny.toml")
    mesh = next(o for o in full.objects if isinstance(o, Mesh))
    lo, hi = np.min(mesh.vertices, axis=0), np.max(mesh.vertices, axis=0)
    scene = dc.replace(full, objects=[mesh], lights=[]).with_overrides(width=24, height=18)
    core = to_core(scene)
    entering = 0
    for j in range(18):
        for i in range(24):
            o, d = (np.array(v) for v in core.primary_ray(i + 0.5, j + 0.5))
            with np.errstate(divide="ignore"):
                t0, t1 = (lo - o) / d, (hi - o) / d
            near, far = np.max(np.minimum(t0, t1)), np.min(np.maximum(t0, t1))
            entering += bool(near <= far and far > 0)
    assert 0 < entering < 24 * 18  # the box is in the picture, and not all of it
    for mode in ("none", "bounding_box"):
        assert rows[mode]["rays"] == 24 * 18
        assert rows[mode]["box_tests"] == rows[mode]["rays"]  # the one box, once per ray
    assert rows["bounding_box"]["primitive_tests"] == entering * triangles
    assert rows["none"]["primitive_tests"] == 24 * 18 * triangles
    bvh = rows["bvh"]
    assert bvh["triangles_per_ray"] < 1e-3 * rows["none"]["triangles_per_ray"]
    assert bvh["boxes_per_ray"] > rows["none"]["boxes_per_ray"]
    assert all(r["seconds"] > 0 for r in p.rows)
    assert f"{bvh['triangles_per_ray']:.3g} triangle tests" in p.alt


def test_plots_on_a_page_in_a_browser(made, browser, tmp_path):
    """L13's page as the report builds it (its precision plot), with the other three plots
    added: every plot an image that loads, its alt text the finding, its table its rows."""
    page = build_lesson_page("L13", mistake_cap=0, command="tests/reports/test_plots")
    assert [p.name for p in page.plots] == ["precision"]
    every = [*page.plots, *(p for name, p in made.items() if name != "precision")]
    page = dataclasses.replace(page, plots=every)
    for inline in (False, True):
        out = tmp_path / ("inline" if inline else "files")
        path = write_lesson_site(out, page, inline=inline)
        if not inline:
            assert sorted(q.name for q in path.parent.glob("plot-*.png")) == sorted(
                f"plot-{p.name}.png" for p in every
            )
        browser_page, requests, errors = open_page(browser, path)
        assert_offline_and_whole(browser_page, requests, errors, out)
        for p in every:
            src, width, alt = browser_page.eval_on_selector(
                f"#plot-{p.name} img", "e => [e.getAttribute('src'), e.naturalWidth, e.alt]"
            )
            assert width == p.size[0] > 0
            assert alt == p.alt and len(alt) > 80
            assert src.startswith("data:image/png;base64,") == inline
            cells = browser_page.eval_on_selector_all(
                f"#plot-data-{p.name} tbody tr",
                "rows => rows.map(r => [...r.cells].map(c => c.dataset.value))",
            )
            assert len(cells) == len(p.rows)
            for row, values in zip(p.rows, cells, strict=True):
                for (key, _), value in zip(p.columns, values, strict=True):
                    want = row[key]
                    assert (float(value) == want) if isinstance(want, float) else (
                        value == str(want))  # fmt: skip
        if inline:
            srcs = [src for src, _, _ in images_of(browser_page)]
            assert all(s.startswith("data:") for s in srcs)
            assert not list(path.parent.glob("plot-*.png"))
