"""Image metrics for comparing renderers: RMSE, max abs error, PSNR and SSIM (scikit-image),
FLIP (NVIDIA's flip-evaluator), the share of pixels over a tolerance, and heat maps."""

from __future__ import annotations

import os
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

Image = npt.NDArray[np.floating]

# --------------------------------------------------------------------------- agreement rules
#
# Our images are float32: a value up to 2 carries half an ulp of rounding, 2^-24 * 2 ~ 1.2e-7;
# twice that covers the reference's own double arithmetic before its output rounding.
FLOAT32_SLACK = 2.4e-7
# Mitsuba's visibility runs in float32: ray origins and directions carry relative errors of
# ~2^-24, so hit points move by ~1e-6 on these scenes (coordinates up to ~10). A Phong lobe
# max(R.L, 0)^n turns a normal error e into a relative change of about n e: 200 * 1e-6 = 2e-4
# at the sharpest exponent of the canonical scenes, times a highlight of at most ~0.5 in
# value. 1e-4 absolute holds everywhere but on edges.
MITSUBA_TOLERANCE = 1e-4
# Where a ray grazes a silhouette, seen directly or through a reflection, the renderers decide
# hit or miss in different precision (float32 in Mitsuba, double with other epsilons in
# POV-Ray): such pixels may differ by a whole colour. Their share is bounded, not excused.
MAX_SHARE_OVER = 0.0005
# Mitsuba has no torus; converters.mitsuba tessellates it (512 x 256 quads). Hits and normals are
# moved onto the true torus, but whether a grazing ray meets the facets or the true surface can
# differ. A thin torus whose tube is narrower than a pixel (reference/scenes/torus_cylinder.toml:
# 0.02 units wide, a pixel spans 0.03) is all silhouette, and so is its shadow: measured, 32 of
# 19,200 pixels (0.17%) there. The bound for scenes with tori against Mitsuba is 0.3%.
MAX_SHARE_TESSELLATED = 0.003


@dataclass(frozen=True)
class Comparison:
    rmse: float
    max_abs: float
    psnr: float  # dB, against the reference's peak (at least 1)
    ssim: float
    flip: float  # mean FLIP, HDR mode
    over_tolerance: float  # share of pixels with any channel over the tolerance
    tolerance: float
    pixels_over: int

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def _check(reference: Image, test: Image) -> tuple[np.ndarray, np.ndarray]:
    ref = np.asarray(reference, dtype=np.float64)
    tst = np.asarray(test, dtype=np.float64)
    if ref.shape != tst.shape:
        raise ValueError(f"images differ in shape: {ref.shape} vs {tst.shape}")
    return ref, tst


def rmse(reference: Image, test: Image) -> float:
    ref, tst = _check(reference, test)
    return float(np.sqrt(np.mean((ref - tst) ** 2)))


def max_abs(reference: Image, test: Image) -> float:
    ref, tst = _check(reference, test)
    return float(np.max(np.abs(ref - tst)))


def data_range(reference: Image) -> float:
    """The peak PSNR and SSIM measure against: 1 for displayable images, more for HDR ones."""
    return max(1.0, float(np.max(reference)))


def psnr(reference: Image, test: Image) -> float:
    from skimage.metrics import peak_signal_noise_ratio

    ref, tst = _check(reference, test)
    if np.array_equal(ref, tst):
        return float("inf")
    return float(peak_signal_noise_ratio(ref, tst, data_range=data_range(ref)))


def ssim(reference: Image, test: Image) -> float:
    from skimage.metrics import structural_similarity

    ref, tst = _check(reference, test)
    win = min(7, *ref.shape[:2])
    win -= 1 - win % 2  # an odd window that fits the image
    if win < 3:
        return 1.0 if np.array_equal(ref, tst) else float("nan")
    return float(
        structural_similarity(ref, tst, data_range=data_range(ref), channel_axis=-1, win_size=win)
    )


def flip(reference: Image, test: Image) -> tuple[float, np.ndarray]:
    """Mean FLIP (HDR: linear inputs, exposure range chosen by FLIP) and its error map."""
    import flip_evaluator

    ref, tst = _check(reference, test)
    error_map, mean, _ = flip_evaluator.evaluate(
        np.ascontiguousarray(np.maximum(ref, 0), dtype=np.float32),
        np.ascontiguousarray(np.maximum(tst, 0), dtype=np.float32),
        "HDR",
        applyMagma=False,
    )
    return float(mean), np.asarray(error_map)


def over_tolerance(reference: Image, test: Image, tolerance: float | Image) -> np.ndarray:
    """A (height, width) mask of pixels where any channel differs by more than ``tolerance``
    (a number, or a per-pixel, per-channel array such as a reference's output precision), or
    is not finite in either image: |nan - x| > tol is false, so NaN must be caught apart."""
    ref, tst = _check(reference, test)
    bad = ~(np.isfinite(ref) & np.isfinite(tst))
    return np.any((np.abs(ref - tst) > tolerance) | bad, axis=-1)


def non_finite(image: Image) -> int:
    """The number of pixels with a NaN or infinite channel."""
    return int(np.sum(~np.all(np.isfinite(np.asarray(image, dtype=np.float64)), axis=-1)))


def agrees(
    reference: Image, test: Image, tolerance: float | Image, max_share: float = MAX_SHARE_OVER
) -> tuple[bool, str]:
    """The regression rule: pixels over ``tolerance`` make up at most ``max_share``, and no
    pixel of either image is NaN or infinite (a colour that is not a number is a bug, never a
    silhouette to excuse, so one such pixel is a disagreement)."""
    mask = over_tolerance(reference, test, tolerance)
    share = float(mask.mean())
    bad_ref, bad_test = non_finite(reference), non_finite(test)
    diff = np.abs(np.asarray(reference, np.float64) - np.asarray(test, np.float64))
    diff = diff[np.isfinite(diff)]  # the largest error among the pixels that are numbers
    err = float(diff.max()) if diff.size else 0.0
    text = (
        f"{int(mask.sum())} of {mask.size} pixels ({100 * share:.3f}%) over tolerance, "
        f"max abs error {err:.3g}"
    )
    if bad_ref or bad_test:
        text = (
            f"not a number: {bad_ref} pixels of the reference and {bad_test} of the test image "
            f"are NaN or infinite; {text} (of the finite pixels)"
        )
        return False, text
    return share <= max_share, text


def compare(reference: Image, test: Image, tolerance: float | Image = 1e-4) -> Comparison:
    mask = over_tolerance(reference, test, tolerance)
    tol = float(np.max(tolerance)) if not np.isscalar(tolerance) else float(tolerance)
    # An image with NaN or inf has NaN metrics, and says so in pixels_over: no warnings too.
    with np.errstate(invalid="ignore", divide="ignore"):
        return _compare(reference, test, mask, tol)


def _compare(reference: Image, test: Image, mask: np.ndarray, tol: float) -> Comparison:
    return Comparison(
        rmse=rmse(reference, test),
        max_abs=max_abs(reference, test),
        psnr=psnr(reference, test),
        ssim=ssim(reference, test),
        flip=flip(reference, test)[0],
        over_tolerance=float(mask.mean()),
        tolerance=tol,
        pixels_over=int(mask.sum()),
    )


def heat_map(
    reference: Image, test: Image, path: str | os.PathLike[str], *, floor: float = 1e-8
) -> None:
    """A PNG of log10 |difference| (max over channels), magma, with a colour bar; atomic."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from tracer.image import atomic_path

    ref, tst = _check(reference, test)
    err = np.max(np.abs(ref - tst), axis=-1)
    h, w = err.shape
    fig, ax = plt.subplots(figsize=(max(4.0, w / 100 + 1.5), max(3.0, h / 100)), dpi=100)
    shown = ax.imshow(np.log10(np.maximum(err, floor)), cmap="magma", vmin=np.log10(floor),
                      vmax=0, interpolation="nearest")  # fmt: skip
    ax.set_axis_off()
    fig.colorbar(shown, ax=ax, label="log10 |difference|")
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", bbox_inches="tight")
    plt.close(fig)
