"""The ``rtlab_phong`` BSDF: the path tracer's glossy lobe (tracer/cpp/20_path.h), the
normalised Phong lobe f = specular (n + 2) / (2 pi) max(cos a, 0)^n about the mirror direction,
sampled as cos^n about it. No built-in Mitsuba BSDF has this lobe."""

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

NAME = "rtlab_phong"
#: A lobe given no ``specular`` reflects all it receives within the lobe; ``shininess``
#: defaults as the scene language's does (tracer.scene.Material).
DEFAULT_SPECULAR = 1.0
DEFAULT_SHININESS = Material(name="default").shininess


def plugin_class() -> type:
    """The plugin's class, derived from the *current* variant's ``mi.BSDF``."""

    class PhongLobe(mi.BSDF):
        def __init__(self, props: mi.Properties) -> None:
            mi.BSDF.__init__(self, props)
            self.specular = float(props.get("specular", DEFAULT_SPECULAR))
            self.shininess = float(props.get("shininess", DEFAULT_SHININESS))
            self.m_flags = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
            self.m_components = [self.m_flags]

        def _lobe(self, si: Any, wo: Any) -> tuple:
            lobe = phong_lobe(mirror_direction(si.wi), wo, self.shininess)
            valid = (mi.Frame3f.cos_theta(si.wi) > 0) & (mi.Frame3f.cos_theta(wo) > 0)
            f = phong_f(self.specular, self.shininess, lobe)
            pdf = phong_pdf(self.shininess, lobe)
            return dr.select(valid, f, 0.0), dr.select(valid, pdf, 0.0)

        def eval(self, ctx, si, wo, active=True) -> Any:  # noqa: ANN001
            f, _ = self._lobe(si, wo)
            return mi.Color3f(f * dr.maximum(mi.Frame3f.cos_theta(wo), 0.0))

        def pdf(self, ctx, si, wo, active=True) -> Any:  # noqa: ANN001
            return self._lobe(si, wo)[1]

        def eval_pdf(self, ctx, si, wo, active=True) -> Any:  # noqa: ANN001
            f, pdf = self._lobe(si, wo)
            return mi.Color3f(f * dr.maximum(mi.Frame3f.cos_theta(wo), 0.0)), pdf

        def sample(self, ctx, si, sample1, sample2, active=True) -> Any:  # noqa: ANN001
            wo = sample_phong_lobe(mirror_direction(si.wi), sample2, self.shininess)
            f, pdf = self._lobe(si, wo)
            bs = mi.BSDFSample3f()
            bs.wo, bs.pdf, bs.eta = wo, pdf, 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.GlossyReflection)
            bs.sampled_component = mi.UInt32(0)
            weight = dr.select(pdf > 0, f * mi.Frame3f.cos_theta(wo) / pdf, 0.0)
            return bs, mi.Color3f(weight)

        def to_string(self) -> str:
            return f"PhongLobe[specular={self.specular}, shininess={self.shininess}]"

    PhongLobe.__doc__ = __doc__
    return PhongLobe
