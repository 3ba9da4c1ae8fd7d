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
