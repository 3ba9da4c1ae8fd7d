"""The agreement rule itself (reference/metrics.agrees): what it lets through and what not."""

from __future__ import annotations

import numpy as np
import pytest

from reference.metrics import MAX_SHARE_OVER, agrees, compare, over_tolerance

SHAPE = (40, 50, 3)  # 2,000 pixels: MAX_SHARE_OVER (0.05%) allows exactly one over tolerance


def images():
    rng = np.random.default_rng(1)
    ref = rng.uniform(0, 1, SHAPE)
    return ref, ref + 1e-5  # every pixel within a tolerance of 1e-4


def test_the_share_rule_itself():
    assert MAX_SHARE_OVER * SHAPE[0] * SHAPE[1] == pytest.approx(1.0)
    ref, test = images()
    assert agrees(ref, test, 1e-4)[0]
    test[3, 4, 1] += 0.5  # one pixel over: still within the share
    assert agrees(ref, test, 1e-4)[0]
    test[5, 6, 2] += 0.5  # two: over it
    ok, text = agrees(ref, test, 1e-4)
    assert not ok and "2 of 2000 pixels" in text


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("where", ["test", "reference"])
def test_a_pixel_that_is_not_a_number_is_a_disagreement(value, where):
    """|nan - x| > tol is false: without its own check a NaN pixel would pass the rule. One
    such pixel fails it, though the share rule alone would excuse one pixel of 2,000."""
    ref, test = images()
    (test if where == "test" else ref)[7, 8, 0] = value
    ok, text = agrees(ref, test, 1e-4)
    assert not ok, text
    n_ref, n_test = (1, 0) if where == "reference" else (0, 1)
    assert f"{n_ref} pixels of the reference and {n_test} of the test image" in text
    assert "NaN or infinite" in text
    assert "max abs error 1e-05" in text  # measured over the pixels that are numbers
    assert over_tolerance(ref, test, 1e-4)[7, 8]
    assert compare(ref, test, 1e-4).pixels_over == 1


def test_nan_in_both_images_is_still_a_disagreement():
    ref, test = images()
    ref[0, 0, :] = test[0, 0, :] = np.nan
    assert not agrees(ref, test, 1e-4)[0]
