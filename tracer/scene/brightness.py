"""Refusing scenes whose image could overflow float32.

Images are float32 (the core's, the references', the files'), whose largest value is 3.4e38; the
reader accepts any finite double, so a material or light of 1e299 would render as inf pixels.
Rather than a cap on each value (a reflectivity of 2 is harmless at max_depth 5 and overflows at
max_depth 10000), the scene's brightest possible pixel is bounded from its values, and a scene
whose bound passes ``MAX_PIXEL_BOUND`` is refused, naming the value that makes it so.

- Classic (tracer/cpp/10_classic.h): a level adds at most G = ambient max(color) max(ambient
  light) + sum over lights of (diffuse max(color) + specular) max(light colour), since N.L <= 1
  and (R.L)^n <= 1 and point lights have no fall-off; the chain weights level k by at most
  rho^(k-1), rho the largest reflectivity; a miss adds the background once. So a pixel is at
  most (1 + rho + ... + rho^(D-1)) (G + background), D = max_depth.
- Path (tracer/cpp/20_path.h): what reaches the camera starts at an emitter (emission, the
  background, a light's colour) and is multiplied at each bounce by what the material returns,
  at most a = max(color) diffuse + specular + reflectivity; the bound is
  (1 + a + ... + a^(D-1)) times the sum of the emitters' largest components. This bounds the
  expected pixel, not every sample: Russian roulette's 1/q and a point light's 1/r^2 can make a
  single sample larger, which is what the headroom below is for.
- Aov renders carry depth, object id and normal: nothing to bound.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import TYPE_CHECKING

import numpy as np

from tracer.scene.errors import SceneError
from tracer.scene.values import join_key

if TYPE_CHECKING:  # the whole scene is built on this check, not the other way round
    from tracer.scene.document import Scene

#: float32's largest finite value: every image is float32.
FLOAT32_MAX = float(np.finfo(np.float32).max)
#: A scene is refused when its brightest pixel could pass sqrt(FLOAT32_MAX) ~ 1.8e19: the other
#: half of float32's exponent range is headroom for what the bound does not see (a path's
#: sampling weights, a point light's 1/r^2 up close), and a pixel's square (a variance in the
#: statistical tests) stays finite in float32 too.
MAX_PIXEL_BOUND = math.sqrt(FLOAT32_MAX)


def _chain(ratio: float, levels: int) -> float:
    """1 + ratio + ... + ratio^(levels - 1), inf where it overflows a double."""
    if ratio == 1.0:
        return float(levels)
    try:
        return (ratio**levels - 1.0) / (ratio - 1.0)
    except OverflowError:
        return math.inf


def _largest(values: Iterable[tuple[str, float]]) -> tuple[str, float]:
    return max(values, key=lambda kv: kv[1], default=("", 0.0))


def check_brightness(scene: Scene) -> None:
    """Raise a SceneError when the scene's brightest possible pixel passes MAX_PIXEL_BOUND."""
    ren = scene.render
    if ren.integrator == "aov":
        return
    lights = [max(light.color) for light in scene.lights]
    light_keys = [(f"lights[{i}].color", c) for i, c in enumerate(lights)]
    mats = {join_key("materials", n): m for n, m in scene.materials.items()}
    values = [*light_keys, ("render.background", max(ren.background))]
    for key, m in mats.items():
        values += [(f"{key}.color", max(m.color)), (f"{key}.ambient", m.ambient),
                   (f"{key}.diffuse", m.diffuse), (f"{key}.specular", m.specular),
                   (f"{key}.reflectivity", m.reflectivity)]  # fmt: skip
    if ren.integrator == "classic":
        values.append(("render.ambient_light", max(ren.ambient_light)))
        amb = max(ren.ambient_light)
        per_level = max(
            (m.ambient * max(m.color) * amb + sum(lights) * (m.diffuse * max(m.color) + m.specular)
             for m in mats.values()),
            default=0.0,
        )  # fmt: skip
        chain_key, ratio = _largest((f"{k}.reflectivity", m.reflectivity) for k, m in mats.items())
        base = per_level + max(ren.background)
        bound = _chain(ratio, ren.max_depth) * base if base > 0 else 0.0
    else:
        values += [(f"{k}.emission", max(m.emission)) for k, m in mats.items()]
        emitters = max(ren.background) + sum(lights)
        emitters += max((max(m.emission) for m in mats.values()), default=0.0)
        gains = {k: max(m.color) * m.diffuse + m.specular + m.reflectivity for k, m in mats.items()}
        table, ratio = _largest(gains.items())
        chain_key = table
        if table:  # the material's own largest term names the key
            m = mats[table]
            terms = {"color": max(m.color) * m.diffuse, "specular": m.specular,
                     "reflectivity": m.reflectivity}  # fmt: skip
            chain_key = f"{table}.{max(terms, key=lambda t: terms[t])}"
        bound = _chain(ratio, ren.max_depth) * emitters if emitters > 0 else 0.0
    if bound <= MAX_PIXEL_BOUND:
        return
    key, value = _largest(values)
    if _chain(ratio, ren.max_depth) > MAX_PIXEL_BOUND or value <= ratio:
        # the chain of reflections alone is the cause: a material returning more than it gets
        key, value = chain_key, ratio
        why = (f"a material returning {ratio:g} times what it receives, over render.max_depth = "
               f"{ren.max_depth} levels")  # fmt: skip
    else:
        why = f"a value of {value:g}"
    raise SceneError(
        scene.source,
        key,
        f"{why} could make the image overflow float32: a pixel could reach {bound:.3g}, and "
        f"rtlab refuses more than {MAX_PIXEL_BOUND:.3g} (float32 holds up to {FLOAT32_MAX:.3g}; "
        "the rest is headroom for sampling weights)",
    )
