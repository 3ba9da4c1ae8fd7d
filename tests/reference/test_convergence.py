"""The convergence protocol (reference/convergence.py): what each renderer's timed render
includes, and the sampler each of Mitsuba's rows draws with."""

from __future__ import annotations

import drjit as dr

from reference.convergence import SCENES, _mitsuba_timer, convergence
from tracer.scene import load_scene


def _jit_kernels() -> list[dict]:
    return [k for k in dr.kernel_history() if k["type"] == dr.KernelType.JIT]


def _in_memory(kernel: dict) -> bool:
    """Found compiled in this process: neither compiled now nor loaded from the disk cache."""
    return bool(kernel["cache_hit"]) and not kernel.get("cache_disk", False)


def test_mitsuba_timings_include_no_compilation():
    """The stratified sampler's kernels depend on the sample count: the first render at a new
    count compiles them (or loads them from Dr.Jit's disk cache). The timer renders each count
    once untimed first, so the timed render (the last kernels launched, as many as a warm
    render launches) finds every kernel compiled in memory."""
    scene = load_scene(SCENES / "cornell_box.toml").with_overrides(width=16, height=16)
    run = _mitsuba_timer(scene, "llvm_ad_rgb", "stratified")
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        dr.kernel_history()  # clear
        image, seconds, rendered = run(40, 17)  # a count no other test renders
        first = _jit_kernels()
        run(40, 18)
        warm = _jit_kernels()
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    assert image.shape == (16, 16, 3) and seconds > 0
    assert rendered == 49  # Mitsuba's stratified sampler rounds 40 up to a square
    assert warm and all(_in_memory(k) for k in warm)  # a warm render compiles nothing
    assert not all(_in_memory(k) for k in first)  # the new count needed its kernels ...
    assert all(_in_memory(k) for k in first[-len(warm) :])  # ... before the timed render


def test_each_mitsuba_row_says_how_many_samples_it_drew():
    rows = convergence(width=16, height=16, sweep=(8,), reference_spp=64, repeats=2,
                       renderers=("rtlab", "mitsuba-llvm", "mitsuba-llvm-stratified"))  # fmt: skip
    rendered = {r["renderer"]: r["spp_rendered"] for r in rows}
    assert rendered == {"rtlab": 8, "mitsuba-llvm": 8, "mitsuba-llvm-stratified": 9}
    assert all(r["spp"] == 8 and r["seconds"] > 0 and r["value"] > 0 for r in rows)
    assert all(r["repeats"] == 2 for r in rows)  # one row per renderer, the faster render's time
