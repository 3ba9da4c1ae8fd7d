"""Statistical agreement of Monte Carlo renders with a reference.

- ``mitsuba_reference``: Mitsuba's own path tracer at high spp, rendered as CHUNKS independent
  renders (different seeds) whose spread gives the per-sample variance (Mitsuba's ``moment``
  integrator reports second moments in XYZ in RGB variants, which cannot be turned back into
  RGB variances); cached on disk under the scene's hash, the spp and Mitsuba's version
  (``RTLAB_CACHE``, default ``~/.cache/rtlab``).
- ``pixel_test``: Mitsuba's image test (its ``src/render/tests/test_renders.py``): per pixel and
  channel, z = |mean - ref| sqrt(spp / max(var, 1e-4)), p = 2 (1 - Phi(z)), compared with the
  Sidak-corrected alpha = 1 - (1 - 0.01)^(1 / pixels); it passes when at least 99.75% of the
  pixels pass. Built to catch broken images, it cannot see a small bias: at a few hundred spp
  one pixel's noise dwarfs a 2% shift.
- ``aggregate_test``: the complement. From k independent renders (different seeds) it forms,
  per render, the mean difference to the reference over the whole image and over blocks of
  pixels; across the k renders these have a sample spread, so each gets a t statistic with
  k - 1 degrees of freedom (the reference's own noise added to its variance). A bias shifts
  every pixel the same way, so the whole-image mean sees it with the noise of all pixels
  averaged away; the blocks see a bias confined to one region. The test rejects when the
  whole-image p-value or the Sidak-corrected smallest block p-value is below alpha / 2.
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

from tracer.scene import Scene

#: Independent renders a reference is made of (its variance estimate has CHUNKS - 1 degrees
#: of freedom per pixel).
CHUNKS = 16


@dataclass(frozen=True)
class Reference:
    mean: np.ndarray  # (h, w, 3) the expected pixel values, up to the reference's own noise
    variance: np.ndarray  # (h, w, 3) the variance of one sample
    spp: int


def cache_dir() -> Path:
    return Path(os.environ.get("RTLAB_CACHE", Path.home() / ".cache" / "rtlab")) / "references"


def scene_hash(scene: Scene, spp: int, renderer: str) -> str:
    """The cache key: the scene, the spp, the renderer's version, and the converter's own source
    (a change to how scenes are converted must not reuse references made the old way)."""
    import converters.mitsuba

    converter = converters.mitsuba.source_digest()  # every module of the package
    data = json.dumps(scene.to_dict(), sort_keys=True, default=str) + converter
    # The cache format is part of the key: a change to how references are made changes it.
    return hashlib.sha256(f"{data}|{spp}|{renderer}|chunks{CHUNKS}".encode()).hexdigest()[:24]


def mitsuba_reference(
    scene: Scene, spp: int, *, variant: str | None = None, sampler: str | None = None
) -> Reference:
    """Mitsuba's path tracer at ``spp`` samples per pixel, mean and per-sample variance; from
    the cache when this scene was rendered so before by this Mitsuba. ``sampler``: Mitsuba's
    sampler for every chunk (None: the converter's, independent samples); with "stratified"
    each chunk's spp (a square: per_chunk = 256 of 4096) are a grid of jittered strata, so a
    pixel cut by an edge has a fraction of the independent noise, while the chunks are still
    independent renders and their spread still the variance of the mean."""
    import mitsuba as mi

    import converters.mitsuba as cm

    variant = cm.use_variant(variant)
    renderer = f"mitsuba-{mi.__version__}" + (f"-{sampler}" if sampler else "")
    key = scene_hash(scene.with_overrides(spp=spp), spp, renderer)
    path = cache_dir() / f"{key}.npz"
    if path.exists():
        data = np.load(path)
        return Reference(data["mean"], data["variance"], int(data["spp"]))
    per_chunk = max(1, spp // CHUNKS)
    d = cm.to_mitsuba_dict(scene.with_overrides(spp=per_chunk))
    if sampler is not None:
        d["sensor"]["sampler"] = {"type": sampler, "sample_count": per_chunk}
    mi_scene = mi.load_dict(d)
    chunks = np.stack([np.array(mi.render(mi_scene, seed=1000 + c), dtype=np.float64)[..., :3]
                       for c in range(CHUNKS)])  # fmt: skip
    # What each chunk drew: Mitsuba's stratified sampler rounds a count up to a square.
    per_chunk = int(mi_scene.sensors()[0].sampler().sample_count())
    mean = chunks.mean(axis=0)
    variance = chunks.var(axis=0, ddof=1) * per_chunk  # of one sample
    spp = per_chunk * CHUNKS
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp.npz")
    np.savez_compressed(tmp, mean=mean, variance=variance, spp=spp)
    os.replace(tmp, path)
    return Reference(mean, variance, spp)


@dataclass(frozen=True)
class TestResult:
    passed: bool
    statistic: float
    detail: dict[str, Any]


def pixel_test(image: np.ndarray, spp: int, ref: Reference, alpha: float = 0.01) -> TestResult:
    """Mitsuba's per-pixel z-test (see the module's text)."""
    z = np.abs(np.asarray(image, np.float64) - ref.mean) * np.sqrt(
        spp / np.maximum(ref.variance, 1e-4)
    )
    p = 2 * stats.norm.sf(z)
    alpha_sidak = 1 - (1 - alpha) ** (1 / p.size)
    share = float(np.mean(p >= alpha_sidak))
    return TestResult(share >= 0.9975, share, {"alpha_sidak": alpha_sidak, "max_z": float(z.max())})


def _block_means(x: np.ndarray, block: int) -> np.ndarray:
    h, w = x.shape[:2]
    hb, wb = h // block, w // block
    x = x[: hb * block, : wb * block]
    return x.reshape(hb, block, wb, block, -1).mean(axis=(1, 3)).reshape(-1)


def aggregate_test(
    images: list[np.ndarray], ref: Reference, alpha: float = 0.01, block: int = 16
) -> TestResult:
    """Whole-image and block-mean t-tests over k independent renders (see the module's text)."""
    k = len(images)
    if k < 3:
        raise ValueError("the aggregate test needs at least three independent renders")
    diffs = [np.asarray(im, np.float64) - ref.mean for im in images]
    n = ref.mean.size
    # Whole image: one number per render; the reference's noise is common to all of them.
    whole = np.array([d.mean() for d in diffs])
    ref_var_whole = ref.variance.sum() / ref.spp / n**2
    se = np.sqrt(whole.var(ddof=1) / k + ref_var_whole)
    t_whole = whole.mean() / se
    p_whole = 2 * stats.t.sf(abs(t_whole), df=k - 1)
    # Blocks: per block per channel.
    blocks = np.stack([_block_means(d, block) for d in diffs])  # (k, B)
    ref_var_blocks = _block_means(ref.variance, block) / ref.spp / block**2
    se_b = np.sqrt(blocks.var(axis=0, ddof=1) / k + ref_var_blocks)
    t_b = blocks.mean(axis=0) / np.maximum(se_b, 1e-300)
    p_b = 2 * stats.t.sf(np.abs(t_b), df=k - 1)
    p_block = 1 - (1 - p_b.min()) ** p_b.size  # Sidak over the blocks
    passed = bool(p_whole >= alpha / 2 and p_block >= alpha / 2)
    return TestResult(passed, float(t_whole), {
        "p_whole": float(p_whole), "p_block": float(p_block), "relative_bias":
        float(whole.mean() / ref.mean.mean()), "blocks": int(p_b.size)})  # fmt: skip


def biased(scene: Scene, factor: float) -> Scene:
    """The scene with every material's colour (hence albedo) scaled: a deliberate bias."""
    from tracer.scene import parse_scene

    data = scene.to_dict()
    for m in data["materials"].values():
        m["color"] = [c * factor for c in m["color"]]
    return parse_scene(data, source=f"{scene.source} (colours x {factor})", base_dir=scene.base_dir)


def study(
    scene: Scene,
    ref: Reference,
    *,
    trials: int,
    replicates: int = 6,
    spp: int = 64,
    bias: float = 1.02,
    seed: int = 0,
) -> dict[str, float]:
    """How often each test rejects correct renders (false alarms) and renders whose albedo is
    off by ``bias`` (power), over ``trials`` independent trials."""
    from tracer.render import render

    wrong = biased(scene, bias)
    counts = {"pixel_false_alarm": 0, "pixel_power": 0, "aggregate_false_alarm": 0,
              "aggregate_power": 0}  # fmt: skip
    for trial in range(trials):
        for target, label in ((scene, "false_alarm"), (wrong, "power")):
            base = seed + 1000 * trial + (500 if label == "power" else 0)
            images = [render(target.with_overrides(spp=spp, seed=base + k), progress=False)
                      for k in range(replicates)]  # fmt: skip
            counts[f"pixel_{label}"] += not pixel_test(images[0], spp, ref).passed
            counts[f"aggregate_{label}"] += not aggregate_test(images, ref).passed
    return {k: v / trials for k, v in counts.items()}
