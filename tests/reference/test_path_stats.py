"""rtlab's path tracer against Mitsuba's, in the statistical sense (reference/stats.py):
Mitsuba's per-pixel z-test and the aggregate test over independent renders, on the Cornell
box and on a scene of glossy, mirror and mixed materials lit by every kind of emitter."""

from __future__ import annotations

import pytest

import tracer
from reference.stats import aggregate_test, biased, mitsuba_reference, pixel_test, study
from tests.helpers import SCENES

SPP, REPLICATES, REFERENCE_SPP = 64, 6, 4096


def small(name, width=64, height=64):
    return tracer.load_scene(SCENES / f"{name}.toml").with_overrides(width=width, height=height)


def renders(scene, seed=100):
    return [tracer.render(scene.with_overrides(spp=SPP, seed=seed + k), threads=2)
            for k in range(REPLICATES)]  # fmt: skip


@pytest.mark.parametrize(
    ("name", "size"),
    [("cornell_box", (64, 64)), ("cornell_measured", (64, 64)), ("path_glossy_mirror", (64, 48))],
)
def test_path_tracer_agrees_with_mitsuba(name, size):
    scene = small(name, *size)
    ref = mitsuba_reference(scene, REFERENCE_SPP)
    images = renders(scene)
    assert pixel_test(images[0], SPP, ref).passed
    result = aggregate_test(images, ref)
    assert result.passed, result.detail


def test_a_two_percent_albedo_bias_escapes_the_pixel_test_but_not_the_aggregate_one():
    scene = small("cornell_box")
    ref = mitsuba_reference(scene, REFERENCE_SPP)
    images = renders(biased(scene, 1.02), seed=900)
    assert pixel_test(images[0], SPP, ref).passed  # a few hundred spp: the noise hides 2%
    result = aggregate_test(images, ref)
    assert not result.passed, result.detail


def test_false_alarms_and_power_of_the_aggregate_test():
    """Ten trials each, at 32x32: the aggregate test should not reject a correct render (alpha
    is 1%: one false alarm in ten is already unlikely, p = 0.096), and should catch the 2% bias
    every time, which the per-pixel test does not (measured here: it caught it 3 times in 10,
    and raised one false alarm)."""
    scene = small("cornell_box", 32, 32)
    ref = mitsuba_reference(scene, REFERENCE_SPP)
    rates = study(scene, ref, trials=10, seed=7)
    assert rates["aggregate_false_alarm"] <= 0.1
    assert rates["aggregate_power"] == 1.0
    assert rates["pixel_power"] < rates["aggregate_power"]


def test_the_measured_cornell_box_holds_the_derived_colours():
    """reference/scenes/cornell_measured.toml must hold what reference/cornell_measured.py
    derives from the measured spectra (rounded to six places, as written)."""
    from reference.cornell_measured import values

    scene = tracer.load_scene(SCENES / "cornell_measured.toml")
    derived = values()
    for name in ("white", "green", "red"):
        assert list(scene.materials[name].color) == pytest.approx(derived[name], abs=1e-6)
    assert list(scene.materials["light"].emission) == pytest.approx(derived["light"], abs=1e-6)
    # The derivation makes a perfect reflector white: the measured white wall is near-grey.
    assert max(derived["white"]) - min(derived["white"]) < 0.02
