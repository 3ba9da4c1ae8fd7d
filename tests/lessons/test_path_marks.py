"""A path scene's failing pixels (lessons/scene_checks.py judge_path, Verdict.failing): its rule
is statistical, per block of pixels, so the pixels a feedback page marks are the blocks that
fail. Checked on L12's furnace, whose every pixel is known in closed form, with replicates drawn
here: noise of the closed form's size everywhere and a bias in one block only."""

import numpy as np

from lessons.L12_cornell.scenes import FURNACE
from lessons.scene_checks import Rendered, judge_path, lesson_scenes, references


def test_the_failing_blocks_are_the_marked_pixels() -> None:
    check = next(c for c in lesson_scenes("L12") if c.name == "furnace")
    refs = references(check)
    scene = check.load()
    h, w = scene.camera.height, scene.camera.width
    rng = np.random.default_rng(12)
    # Each replicate's pixel noise: one sample's standard deviation in the furnace is of the
    # order of the value itself (paths of random length), over spp samples.
    sd = FURNACE / np.sqrt(scene.render.spp)
    images = [FURNACE + sd * rng.standard_normal((h, w, 3)) for _ in range(check.replicates)]
    unbiased = judge_path(check, Rendered("ok", image=[im.astype(np.float32) for im in images]),
                          refs)  # fmt: skip
    assert unbiased.ok, unbiased.lines  # the drawn noise alone passes (no block is marked)
    assert not unbiased.failing
    b = check.block
    y0, x0 = b, 2 * b  # the second block row, the third block column
    for im in images:
        im[y0 : y0 + b, x0 : x0 + b] *= 1.3  # 30% too bright: tens of standard errors
    biased = judge_path(check, Rendered("ok", image=[im.astype(np.float32) for im in images]),
                        refs)  # fmt: skip
    assert not biased.ok
    expected = np.zeros((h, w), dtype=bool)
    expected[y0 : y0 + b, x0 : x0 + b] = True
    assert set(biased.failing) == set(biased.heat_maps)  # a mask for each image shown
    for name, mask in biased.failing.items():
        assert mask.shape == (h, w)
        assert np.array_equal(mask, expected), name
    # The line names the same pixels.
    assert f"failing pixels in x {x0}..{x0 + b - 1}, y {y0}..{y0 + b - 1}" in "\n".join(
        biased.lines
    )
