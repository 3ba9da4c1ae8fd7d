"""Scene model -> Mitsuba 3, with the slides' classic model running inside Mitsuba.

Importing this package registers rtlab's plugins, written in Python on Dr.Jit, in every variant
this machine can run (converters.mitsuba.registry):

- ``rtlab_classic`` integrator (``classic``): the classic algorithm of tracer/cpp/10_classic.h
  on Mitsuba's ray queries, its hits refined in double (``refine``), its rays spawned with the
  core's vocabulary (``rays``);
- ``rtlab_classic_material`` BSDF (``classic_material``): a material's classic terms, which
  the integrator reads;
- ``rtlab_phong`` BSDF (``phong``): the path tracer's normalised Phong lobe;
- ``rtlab_mixed_lobes`` BSDF (``mixed``): the path tracer's whole material where it mixes the
  mirror with other lobes.

A scene is emitted as a dict for ``mi.load_dict`` (``scene_dict``) and as an XML file
(``xml_writer``) that ``mi.load_file`` reads in any process that has imported this package.
The variant is ``llvm_ad_rgb`` where libLLVM 19 is installed, else ``scalar_rgb`` (``variants``).
"""

# First: it sets DRJIT_LIBLLVM_PATH before Dr.Jit is loaded.
from converters.mitsuba.variants import (
    LIBLLVM,
    VARIANTS,
    MitsubaVariantError,
    default_variant,
    llvm_available,
)

# isort: split

import hashlib
from pathlib import Path

from converters.mitsuba import classic, classic_material, mixed, phong
from converters.mitsuba.classic import ROW
from converters.mitsuba.refine import OTHER, PLANE, SPHERE, TORUS
from converters.mitsuba.registry import register_all, use_variant
from converters.mitsuba.scene_dict import PLANE_SCALE, path_bsdf, plane_matrix, to_mitsuba_dict
from converters.mitsuba.xml_writer import write_mitsuba_xml

#: The plugins' names, as scene dicts and XML files write them.
PLUGIN = classic.NAME
MATERIAL_PLUGIN = classic_material.NAME
PHONG_PLUGIN = phong.NAME
MIXED_PLUGIN = mixed.NAME


def source_digest() -> str:
    """A digest of this package's source: a change to how scenes are converted or rendered in
    Mitsuba changes it (reference.stats keys its cached references with it)."""
    h = hashlib.sha256()
    for path in sorted(Path(__file__).parent.glob("*.py")):
        h.update(path.name.encode() + b"\0" + path.read_bytes())
    return h.hexdigest()


__all__ = [
    "LIBLLVM",
    "MATERIAL_PLUGIN",
    "MIXED_PLUGIN",
    "OTHER",
    "PHONG_PLUGIN",
    "PLANE",
    "PLANE_SCALE",
    "PLUGIN",
    "ROW",
    "SPHERE",
    "TORUS",
    "VARIANTS",
    "MitsubaVariantError",
    "default_variant",
    "llvm_available",
    "path_bsdf",
    "plane_matrix",
    "source_digest",
    "to_mitsuba_dict",
    "use_variant",
    "write_mitsuba_xml",
]

register_all()
