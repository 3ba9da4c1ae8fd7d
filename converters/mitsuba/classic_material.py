"""The ``rtlab_classic_material`` BSDF: a material of the classic model.

It carries a material's classic terms (``color``, ``ambient``, ``diffuse``, ``specular``,
``shininess``, ``reflectivity``) and, for a tessellated torus, the true torus; it scatters
nothing: the classic integrator (converters.mitsuba.classic) reads it.
"""

from __future__ import annotations

from typing import Any

import mitsuba as mi

from tracer.scene import Material

NAME = "rtlab_classic_material"
#: The scene language's defaults (tracer.scene.Material): an XML file that omits a term means
#: what the scene file means.
DEFAULT = Material(name="default")


def plugin_class() -> type:
    """The plugin's class, derived from the *current* variant's ``mi.BSDF``."""

    class ClassicMaterial(mi.BSDF):
        """A material of the classic model; the integrator reads its terms.

        (Properties.get cannot take a colour default, hence the `in` tests below.)
        """

        def __init__(self, props: mi.Properties) -> None:
            mi.BSDF.__init__(self, props)
            color = props["color"] if "color" in props else DEFAULT.color  # noqa: SIM401
            self.color = tuple(float(c) for c in color)
            self.ambient = float(props.get("ambient", DEFAULT.ambient))
            self.diffuse = float(props.get("diffuse", DEFAULT.diffuse))
            self.specular = float(props.get("specular", DEFAULT.specular))
            self.shininess = float(props.get("shininess", DEFAULT.shininess))
            self.reflectivity = float(props.get("reflectivity", DEFAULT.reflectivity))
            # A tessellated torus carries its true shape, so the integrator can use the exact
            # normal: centre, unit axis, major and minor radius (world space).
            self.torus = None
            if "torus_center" in props:
                self.torus = (
                    tuple(float(c) for c in props["torus_center"]),
                    tuple(float(c) for c in props["torus_axis"]),
                    float(props["torus_major_radius"]),
                    float(props["torus_minor_radius"]),
                )
            self.m_flags = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
            self.m_components = [self.m_flags]

        def sample(self, ctx, si, sample1, sample2, active=True) -> Any:  # noqa: ANN001
            return mi.BSDFSample3f(), mi.Color3f(0.0)

        def eval(self, ctx, si, wo, active=True) -> Any:  # noqa: ANN001
            return mi.Color3f(0.0)

        def pdf(self, ctx, si, wo, active=True) -> Any:  # noqa: ANN001
            return mi.Float(0.0)

        def eval_pdf(self, ctx, si, wo, active=True) -> Any:  # noqa: ANN001
            return mi.Color3f(0.0), mi.Float(0.0)

        def to_string(self) -> str:
            return f"ClassicMaterial[color={self.color}, reflectivity={self.reflectivity}]"

    return ClassicMaterial
