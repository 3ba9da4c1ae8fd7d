"""Registering rtlab's plugins with Mitsuba, in each variant before it is used.

A Python plugin's class derives from the *current* variant's base classes (``mi.BSDF``,
``mi.SamplingIntegrator``), so each variant gets its own classes, made by each plugin module's
``plugin_class()`` once that variant is set.
"""

from __future__ import annotations

import mitsuba as mi

from converters.mitsuba import classic, classic_material, mixed, phong
from converters.mitsuba.variants import VARIANTS, check_variant, default_variant, llvm_available

#: Each plugin's module (its NAME and plugin_class()) and its kind, which says how Mitsuba
#: registers it (mi.register_bsdf, mi.register_integrator: these exist once a variant is set).
_PLUGINS = (
    (classic_material, "bsdf"),
    (classic, "integrator"),
    (phong, "bsdf"),
    (mixed, "bsdf"),
)

_registered: set[str] = set()


def use_variant(variant: str | None = None) -> str:
    """Set a Mitsuba variant and make sure rtlab's plugins are registered in it; raises
    ``MitsubaVariantError`` for a variant this build or this machine cannot run."""
    variant = variant or default_variant()
    check_variant(variant)
    mi.set_variant(variant)
    if variant not in _registered:
        for module, kind in _PLUGINS:
            cls = module.plugin_class()
            register = mi.register_bsdf if kind == "bsdf" else mi.register_integrator
            register(module.NAME, lambda props, cls=cls: cls(props))
        _registered.add(variant)
    return variant


def register_all() -> None:
    """On import: register in every variant this machine can run, then pick the default."""
    for variant in VARIANTS:
        if variant == "llvm_ad_rgb" and not llvm_available()[0]:
            continue
        if variant in mi.variants():
            use_variant(variant)
    use_variant(default_variant())
