"""The official Cornell box (Cornell Program of Computer Graphics, "Cornell Box Data"): the
measured geometry in millimetres, and RGB reflectances derived here from the measured spectra.

Derivation. A wall's spectral reflectance rho(lambda) (76 samples, 400-700 nm every 4 nm) is
turned into the linear sRGB reflectance that makes an RGB renderer agree with a spectral one
under the box's own light: the light's spectrum L(lambda) reflected by the wall,
L(lambda) rho(lambda), is integrated against the CIE 1931 2-degree colour matching functions
(colour-science) to XYZ, converted to linear sRGB, and divided per channel by the same for the
light alone (rho = 1), so that a perfect white reflector is (1, 1, 1). The light's own RGB
radiance is its XYZ converted to linear sRGB, scaled so that a flat spectrum of the published
unit has luminance 1. (RGB rendering of a product of spectra is an
approximation however it is done; this one is exact for single reflections of this light.)

Run ``python -m reference.cornell_measured`` to print the values; tests/reference/test_path_stats.py
checks that reference/scenes/cornell_measured.toml holds them.
"""

from __future__ import annotations

import numpy as np

WAVELENGTHS = np.arange(400, 701, 4)  # nm

# Measured reflectances (Cornell Box Data).
WHITE = [0.343, 0.445, 0.551, 0.624, 0.665, 0.687, 0.708, 0.723, 0.715, 0.71, 0.745, 0.758,
         0.739, 0.767, 0.777, 0.765, 0.751, 0.745, 0.748, 0.729, 0.745, 0.757, 0.753, 0.75,
         0.746, 0.747, 0.735, 0.732, 0.739, 0.734, 0.725, 0.721, 0.733, 0.725, 0.732, 0.743,
         0.744, 0.748, 0.728, 0.716, 0.733, 0.726, 0.713, 0.74, 0.754, 0.764, 0.752, 0.736,
         0.734, 0.741, 0.74, 0.732, 0.745, 0.755, 0.751, 0.744, 0.731, 0.733, 0.744, 0.731,
         0.712, 0.708, 0.729, 0.73, 0.727, 0.707, 0.703, 0.729, 0.75, 0.76, 0.751, 0.739,
         0.724, 0.73, 0.74, 0.737]  # fmt: skip
GREEN = [0.092, 0.096, 0.098, 0.097, 0.098, 0.095, 0.095, 0.097, 0.095, 0.094, 0.097, 0.098,
         0.096, 0.101, 0.103, 0.104, 0.107, 0.109, 0.112, 0.115, 0.125, 0.14, 0.16, 0.187,
         0.229, 0.285, 0.343, 0.39, 0.435, 0.464, 0.472, 0.476, 0.481, 0.462, 0.447, 0.441,
         0.426, 0.406, 0.373, 0.347, 0.337, 0.314, 0.285, 0.277, 0.266, 0.25, 0.23, 0.207,
         0.186, 0.171, 0.16, 0.148, 0.141, 0.136, 0.13, 0.126, 0.123, 0.121, 0.122, 0.119,
         0.114, 0.115, 0.117, 0.117, 0.118, 0.12, 0.122, 0.128, 0.132, 0.139, 0.144, 0.146,
         0.15, 0.152, 0.157, 0.159]  # fmt: skip
RED = [0.04, 0.046, 0.048, 0.053, 0.049, 0.05, 0.053, 0.055, 0.057, 0.056, 0.059, 0.057,
       0.061, 0.061, 0.06, 0.062, 0.062, 0.062, 0.061, 0.062, 0.06, 0.059, 0.057, 0.058,
       0.058, 0.058, 0.056, 0.055, 0.056, 0.059, 0.057, 0.055, 0.059, 0.059, 0.058, 0.059,
       0.061, 0.061, 0.063, 0.063, 0.067, 0.068, 0.072, 0.08, 0.09, 0.099, 0.124, 0.154,
       0.192, 0.255, 0.287, 0.349, 0.402, 0.443, 0.487, 0.513, 0.558, 0.584, 0.62, 0.606,
       0.609, 0.651, 0.612, 0.61, 0.65, 0.638, 0.627, 0.62, 0.63, 0.628, 0.642, 0.639, 0.657,
       0.639, 0.635, 0.642]  # fmt: skip
# The light's emission spectrum as published (radiance, relative units), linear between.
LIGHT_WAVELENGTHS = [400, 500, 600, 700]
LIGHT = [0.0, 8.0, 15.6, 18.4]


def _xyz(spectrum: np.ndarray) -> np.ndarray:
    import colour

    cmfs = (
        colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
        .copy()
        .align(colour.SpectralShape(400, 700, 4))
    )
    return np.einsum("w,wc->c", spectrum, cmfs.values) * 4.0  # nm step


def _srgb(xyz: np.ndarray) -> np.ndarray:
    m = np.array(
        [
            [3.2404542, -1.5371385, -0.4985314],
            [-0.9692660, 1.8760108, 0.0415560],
            [0.0556434, -0.2040259, 1.0572252],
        ]
    )  # fmt: skip  (XYZ -> linear sRGB, D65)
    return m @ xyz


def light_spectrum() -> np.ndarray:
    return np.interp(WAVELENGTHS, LIGHT_WAVELENGTHS, LIGHT)


def reflectance_rgb(rho: list[float]) -> np.ndarray:
    light = light_spectrum()
    return _srgb(_xyz(light * np.asarray(rho))) / _srgb(_xyz(light))


def light_rgb() -> np.ndarray:
    """The light's radiance in linear sRGB, in units where a flat spectral radiance of 1 (the
    published unit) has luminance Y = 1."""
    flat = _xyz(np.ones(len(WAVELENGTHS)))
    return _srgb(_xyz(light_spectrum())) / flat[1]


def values() -> dict[str, list[float]]:
    return {
        "white": [round(float(v), 6) for v in reflectance_rgb(WHITE)],
        "green": [round(float(v), 6) for v in reflectance_rgb(GREEN)],
        "red": [round(float(v), 6) for v in reflectance_rgb(RED)],
        "light": [round(float(v), 6) for v in light_rgb()],
    }


if __name__ == "__main__":
    for name, rgb in values().items():
        print(f"{name:6s} {rgb}")
