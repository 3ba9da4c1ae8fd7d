"""Samples per pixel > 1 (tracer/cpp/11_render.h, for_each_sample): spp samples in a grid of
rows x cols strata (rows the largest divisor of spp not above its square root), one jittered
sample in each, averaged with equal weights (the box filter).

Set-up: the camera at z = 1 looks at the plane z = 0 with a 90 degree vertical field of view,
so the image spans y in [-1, 1] and x in [-W/H, W/H] there; pixel (i, j) is a known rectangle.
Quads on z = 0 cover chosen parts of chosen pixels. Their material returns
exactly 1 (ambient 1, colour 1, ambient light 1, no lights), the background 0: a pixel's
value is the share of its samples that hit, k / spp, exact in float32.
"""

from __future__ import annotations

import numpy as np
import pytest

import tracer
from tests.helpers import material, scene_dict

GRIDS = {4: (2, 2), 6: (2, 3), 8: (2, 4), 9: (3, 3), 12: (3, 4), 16: (4, 4)}  # spp: rows, cols
W, H = 3, 2


def pixel_rect(i, j):
    """The world rectangle (x0, x1, y_top, y_bottom) of pixel (i, j) on z = 0."""
    half_w = W / H
    x0 = (i / W - 0.5) * 2 * half_w
    x1 = ((i + 1) / W - 0.5) * 2 * half_w
    return x0, x1, 1 - 2 * j / H, 1 - 2 * (j + 1) / H


def rect(x0, x1, y0, y1):
    """A quad on z = 0, facing the camera: flat, so no ray meets it from the side."""
    return {"type": "quad", "corner": [x0, y0, 0.0], "edge1": [x1 - x0, 0.0, 0.0],
            "edge2": [0.0, y1 - y0, 0.0], "material": "m"}  # fmt: skip


def render(objects, spp, seed):
    data = scene_dict(
        camera={"eye": [0, 0, 1], "look_at": [0, 0, 0], "fov_y": 90.0, "width": W, "height": H},
        render={"spp": spp, "seed": seed},
        materials={"m": material(ambient=1.0)},
        objects=objects,
    )
    return tracer.render(tracer.load_scene(data), threads=1)[..., 0]


def covered(k, i, j, n):
    """How many of n columns (or rows) of pixel (i, j) a box covers: 1 to n, differing from
    pixel to pixel, so that a sample put in the wrong pixel would be seen."""
    return 1 + (k + i + 2 * j) % n


@pytest.mark.parametrize("spp", GRIDS)
@pytest.mark.parametrize("seed", [0, 1, 7])
def test_one_sample_in_each_column_of_strata(spp, seed):
    """Each pixel covered from its left edge to a stratum boundary, c of cols columns: every
    column's samples lie inside or outside, whatever the jitter, so the pixel is exactly c/cols."""
    _, cols = GRIDS[spp]
    objects, want = [], np.zeros((H, W))
    for j in range(H):
        for i in range(W):
            x0, x1, top, bottom = pixel_rect(i, j)
            c = covered(spp, i, j, cols)
            objects.append(rect(x0, x0 + (x1 - x0) * c / cols, bottom, top))
            want[j, i] = c / cols
    assert np.array_equal(render(objects, spp, seed), want.astype(np.float32))


@pytest.mark.parametrize("spp", GRIDS)
@pytest.mark.parametrize("seed", [0, 1, 7])
def test_one_sample_in_each_row_of_strata(spp, seed):
    """The same with rows, covered from the top: exactly r/rows. With the columns test this
    pins the grid's shape: 8 spp is 2 rows of 4, not 4 rows of 2."""
    rows, _ = GRIDS[spp]
    objects, want = [], np.zeros((H, W))
    for j in range(H):
        for i in range(W):
            x0, x1, top, bottom = pixel_rect(i, j)
            r = covered(spp, i, j, rows)
            objects.append(rect(x0, x1, top - (top - bottom) * r / rows, top))
            want[j, i] = r / rows
    assert np.array_equal(render(objects, spp, seed), want.astype(np.float32))


def test_a_half_covered_pixel_converges_to_one_half():
    """A triangle covers pixel (0, 0) below its diagonal from the top-right to the bottom-left
    corner. At 64 spp (8 x 8 strata) the diagonal halves the 8 strata it crosses and leaves 28
    wholly covered: the value is (28 + B) / 64 with B ~ Binomial(8, 1/2), mean 1/2, standard
    deviation sqrt(2)/64 = 0.022, always within [28/64, 36/64]. Unstratified, it would be
    Binomial(64, 1/2) / 64, standard deviation 1/16 = 0.0625."""
    x0, x1, top, bottom = pixel_rect(0, 0)
    # The pixel is the square [x0, x1] x [bottom, top]; the part below the line from
    # (x0, bottom) to (x1, top), extended well past the pixel.
    d = np.array([x1 - x0, top - bottom])
    a, b = np.array([x0, bottom]) - 5 * d, np.array([x0, bottom]) + 6 * d
    c = np.array([a[0] + 11 * d[0], a[1]])
    tri = {"type": "triangle", "material": "m",
           "vertices": [[*a, 0.0], [*c, 0.0], [*b, 0.0]]}  # fmt: skip
    values = np.array([render([tri], 64, seed)[0, 0] for seed in range(40)], dtype=np.float64)
    hits = np.round(values * 64)
    assert np.array_equal(hits, values * 64) and hits.min() >= 28 and hits.max() <= 36, hits
    # The mean of 40: standard deviation 0.022 / sqrt(40) = 0.0035; 4 of them is 0.014.
    assert abs(values.mean() - 0.5) < 0.014
    # The spread: 0.022 stratified; 0.04 would be 8 standard errors above (the sample
    # standard deviation of 40 varies by ~11%) and 3 below the unstratified 0.0625.
    assert values.std(ddof=1) < 0.04


# --- the sampler "sobol": Sobol's (0,2)-sequence, Owen-scrambled per pixel -----------------

NETS = (4, 8, 16, 32)  # spp = 2^m: the first 2^m points are a (0,m,2)-net


def render_sobol(objects, spp, seed):
    data = scene_dict(
        camera={"eye": [0, 0, 1], "look_at": [0, 0, 0], "fov_y": 90.0, "width": W, "height": H},
        render={"spp": spp, "seed": seed, "sampler": "sobol"},
        materials={"m": material(ambient=1.0)},
        objects=objects,
    )
    return tracer.render(tracer.load_scene(data), threads=1)[..., 0]


@pytest.mark.parametrize("spp", NETS)
@pytest.mark.parametrize("seed", [0, 5])
def test_sobol_puts_one_sample_in_every_box_of_a_net(spp, seed):
    """A (0,m,2)-net in base 2 has one point in every box 2^-a wide and 2^-b high (a + b = m)
    at multiples of its size, for every shape at once; Owen's scrambling keeps that. Each
    pixel is covered from its top-left corner over c of 2^a columns and r of 2^b rows of such
    boxes, c and r differing from pixel to pixel: exactly c r of its spp samples hit, whatever
    the scramble, so the pixel is exactly c r / spp, for each of the m + 1 shapes."""
    m = spp.bit_length() - 1
    for a in range(m + 1):
        cols, rows = 2**a, 2 ** (m - a)
        objects, want = [], np.zeros((H, W))
        for j in range(H):
            for i in range(W):
                x0, x1, top, bottom = pixel_rect(i, j)
                c, r = covered(spp + a, i, j, cols), covered(spp - a, j, i, rows)
                objects.append(rect(x0, x0 + (x1 - x0) * c / cols,
                                    top - (top - bottom) * r / rows, top))  # fmt: skip
                want[j, i] = c * r / spp
        got = render_sobol(objects, spp, seed)
        assert np.array_equal(got, want.astype(np.float32)), (a, got, want)


def test_an_edge_along_an_axis_crosses_one_box_of_the_net():
    """A horizontal edge at a height that is no stratum boundary: the jittered 8 x 8 grid puts
    8 samples in the row of strata the edge crosses, each a coin toss; the net's 64 rows of
    height 1/64 hold one sample each, so only the one row the edge crosses is in doubt: the
    count of hits is n or n + 1 for every seed, where the strata's ranges over 8 values."""
    x0, x1, top, bottom = pixel_rect(0, 0)
    edge = top - (top - bottom) * 0.3712  # 23.76 of 64 rows, 2.97 of 8 rows covered
    quad = [rect(x0 - 1, x1 + 1, edge, top + 1)]
    sobol = np.array([render_sobol(quad, 64, s)[0, 0] for s in range(40)]) * 64
    strata = np.array([render(quad, 64, s)[0, 0] for s in range(40)]) * 64
    assert set(np.round(sobol).astype(int)) <= {23, 24}, sobol
    # Both unbiased: the mean of 40 near 23.76 (the net's hits are 23 or 24: a standard
    # deviation of at most 0.5, 0.08 for a mean of 40; 4 of them, 0.32).
    assert abs(sobol.mean() - 23.76) < 0.32
    # The strata: 2 whole rows (16 hits) and Binomial(8, 0.97): spread over several values.
    assert strata.min() >= 16 and len(set(np.round(strata).astype(int))) >= 2, strata


def test_the_sampler_key_is_checked():
    data = scene_dict(render={"spp": 4, "sampler": "sobl"})
    with pytest.raises(tracer.SceneError, match=r"render\.sampler.*'sobol'"):
        tracer.load_scene(data)
    assert tracer.load_scene(scene_dict()).render.sampler == "stratified"  # the default


def lit_plane(sampler, seed, spp=64):
    """A diffuse floor under a square area light, seen in one pixel: direct light only
    (max_depth 2), so the pixel's noise is the light sample's and the scattered ray's, both of
    the first vertex, whose numbers SobolStream (11_render.h) stratifies across the pixel."""
    data = scene_dict(
        camera={"eye": [0, 1, 2], "look_at": [0, 0, 0], "fov_y": 1.0, "width": 1, "height": 1},
        render={"integrator": "path", "spp": spp, "seed": seed, "max_depth": 2,
                "sampler": sampler},
        materials={"m": material(diffuse=0.8),
                   "lamp": material(diffuse=0.0, emission=[5.0, 5.0, 5.0])},
        objects=[{"type": "quad", "corner": [-5, 0, 5], "edge1": [10, 0, 0],
                  "edge2": [0, 0, -10], "material": "m"},
                 {"type": "quad", "corner": [-0.5, 1.5, -0.5], "edge1": [1, 0, 0],
                  "edge2": [0, 0, 1], "material": "lamp"}],  # facing down
    )  # fmt: skip
    return float(tracer.render(tracer.load_scene(data), threads=1)[0, 0, 0])


def test_sobol_stratifies_the_path_s_first_numbers():
    """The same pixel estimated 30 times (seeds) with each sampler: both unbiased (the means
    agree within 4 standard errors of their difference), and the padded Sobol numbers give a
    far smaller spread than the strata's independent light and scattering samples (measured:
    the variance about 1/30 of the strata's; a smooth integrand in two dimensions, where a
    scrambled net's variance falls as N^-3 against Monte Carlo's N^-1). Asserted: below 1/4.
    With 29 degrees of freedom each, the ratio of two sample variances exceeds its true value
    by 3.2 times or more with probability 0.001 (the F distribution), so a true 1/30 cannot
    pass for 1/4 by chance, and a sampler that failed to stratify (true ratio 1) cannot pass."""
    sobol = np.array([lit_plane("sobol", s) for s in range(30)])
    strata = np.array([lit_plane("stratified", s) for s in range(30)])
    error = np.sqrt(sobol.var(ddof=1) / 30 + strata.var(ddof=1) / 30)
    assert abs(sobol.mean() - strata.mean()) < 4 * error
    assert sobol.var(ddof=1) < strata.var(ddof=1) / 4, (sobol.var(), strata.var())


@pytest.mark.parametrize("spp", [3, 6, 12])
def test_sobol_with_a_count_that_is_no_power_of_two_is_unbiased(spp):
    """The first spp points of the net (spp not a power of two) are no net, but each point is
    uniform on the pixel (Owen's scrambling), so the estimate is still unbiased: a quad over
    37% of the pixel's width averages to 0.37 over 80 seeds, within 4 standard errors (each
    render's hits are a count out of spp, 1 or 2 of 3 at spp = 3: their spread is measured)."""
    x0, x1, top, bottom = pixel_rect(0, 0)
    quad = [rect(x0 - 1, x0 + (x1 - x0) * 0.37, bottom - 1, top + 1)]
    values = np.array([render_sobol(quad, spp, s)[0, 0] for s in range(80)], dtype=np.float64)
    error = values.std(ddof=1) / np.sqrt(values.size)
    assert abs(values.mean() - 0.37) < 4 * error, (values.mean(), error)
