"""The ``rtlab_mixed_lobes`` BSDF: the path tracer's whole material (tracer/cpp/20_path.h) as
one BSDF, albedo/pi + Phong + a mirror, lobes chosen with the same probabilities.

Used where a material mixes the mirror with another lobe: Mitsuba 3.9.1's blendbsdf of a
conductor and another BSDF was measured to lose energy (a white furnace gave R 0.0997 for 0.125
with a coloured diffuse; see the README).
"""

from __future__ import annotations

from typing import Any

import drjit as dr
import mitsuba as mi

from converters.mitsuba.lobes import (
    mirror_direction,
    phong_f,
    phong_lobe,
    phong_pdf,
    sample_phong_lobe,
)
from tracer.scene import Material

NAME = "rtlab_mixed_lobes"
#: The scene language's defaults (tracer.scene.Material).
DEFAULT = Material(name="default")


def plugin_class() -> type:
    """The plugin's class, derived from the *current* variant's ``mi.BSDF``."""

    class MixedLobes(mi.BSDF):
        def __init__(self, props: mi.Properties) -> None:
            mi.BSDF.__init__(self, props)
            self.albedo = mi.ScalarColor3f(props["albedo"])
            self.specular = float(props.get("specular", DEFAULT.specular))
            self.shininess = float(props.get("shininess", DEFAULT.shininess))
            self.reflectivity = float(props.get("reflectivity", DEFAULT.reflectivity))
            wd = max(self.albedo)
            total = wd + self.specular + self.reflectivity
            self.p_diffuse, self.p_glossy = wd / total, self.specular / total
            self.p_mirror = self.reflectivity / total
            self.m_flags = (mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.GlossyReflection
                            | mi.BSDFFlags.DeltaReflection | mi.BSDFFlags.FrontSide)  # fmt: skip
            self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide,
                                 mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide,
                                 mi.BSDFFlags.DeltaReflection | mi.BSDFFlags.FrontSide]  # fmt: skip

        def _smooth(self, si: Any, wo: Any) -> tuple:
            cos_i, cos_o = mi.Frame3f.cos_theta(si.wi), mi.Frame3f.cos_theta(wo)
            valid = (cos_i > 0) & (cos_o > 0)
            lobe = phong_lobe(mirror_direction(si.wi), wo, self.shininess)
            f = mi.Color3f(self.albedo) / dr.pi + phong_f(self.specular, self.shininess, lobe)
            pdf = self.p_diffuse * cos_o / dr.pi + phong_pdf(self.shininess, lobe, self.p_glossy)
            return dr.select(valid, f * cos_o, 0.0), dr.select(valid, pdf, 0.0)

        def eval(self, ctx, si, wo, active=True) -> Any:  # noqa: ANN001
            return self._smooth(si, wo)[0]

        def pdf(self, ctx, si, wo, active=True) -> Any:  # noqa: ANN001
            return self._smooth(si, wo)[1]

        def eval_pdf(self, ctx, si, wo, active=True) -> Any:  # noqa: ANN001
            return self._smooth(si, wo)

        def sample(self, ctx, si, sample1, sample2, active=True) -> Any:  # noqa: ANN001
            mirror = mirror_direction(si.wi)
            choose_mirror = sample1 < self.p_mirror
            choose_glossy = ~choose_mirror & (sample1 < self.p_mirror + self.p_glossy)
            glossy = sample_phong_lobe(mirror, sample2, self.shininess)
            diffuse = mi.warp.square_to_cosine_hemisphere(sample2)
            wo = dr.select(choose_mirror, mirror, dr.select(choose_glossy, glossy, diffuse))
            value, pdf = self._smooth(si, wo)
            bs = mi.BSDFSample3f()
            bs.wo, bs.eta = wo, 1.0
            bs.pdf = dr.select(choose_mirror, 1.0, pdf)
            delta = mi.UInt32(+mi.BSDFFlags.DeltaReflection)
            smooth = dr.select(choose_glossy, mi.UInt32(+mi.BSDFFlags.GlossyReflection),
                               mi.UInt32(+mi.BSDFFlags.DiffuseReflection))  # fmt: skip
            bs.sampled_type = dr.select(choose_mirror, delta, smooth)
            component = dr.select(choose_glossy, mi.UInt32(1), mi.UInt32(0))
            bs.sampled_component = dr.select(choose_mirror, mi.UInt32(2), component)
            above = mi.Frame3f.cos_theta(si.wi) > 0
            weight = dr.select(choose_mirror, self.reflectivity / self.p_mirror,
                               dr.select(pdf > 0, value / pdf, 0.0))  # fmt: skip
            return bs, mi.Color3f(dr.select(above, weight, 0.0))

        def to_string(self) -> str:
            return f"MixedLobes[reflectivity={self.reflectivity}]"

    MixedLobes.__doc__ = __doc__
    return MixedLobes
