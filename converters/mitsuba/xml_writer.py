"""The scene as Mitsuba 3 XML, which ``mi.load_file`` reads in any process that has imported
converters.mitsuba (importing it registers the plugins the file names)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

import mitsuba as mi
import numpy as np

from converters.mitsuba import classic, classic_material, mixed, phong
from converters.mitsuba.scene_dict import to_mitsuba_dict
from tracer.image import atomic_path
from tracer.scene import Scene

#: The XML element of each plugin type this converter emits.
_TAGS = {
    classic.NAME: "integrator", classic_material.NAME: "bsdf", "perspective": "sensor",
    "stratified": "sampler", "independent": "sampler", "hdrfilm": "film", "box": "rfilter",
    "point": "emitter", "directional": "emitter", "sphere": "shape", "disk": "shape",
    "cube": "shape", "cylinder": "shape", "ply": "shape", "path": "integrator",
    "diffuse": "bsdf", "conductor": "bsdf", "blendbsdf": "bsdf", "twosided": "bsdf",
    phong.NAME: "bsdf", mixed.NAME: "bsdf", "area": "emitter", "constant": "emitter",
}  # fmt: skip


def _xml_value(name: str, value: Any, indent: str, base: Path | None) -> list[str]:
    if isinstance(value, dict):
        ident = f' id="{name}"' if name.startswith(("object_", "light_", "environment")) else ""
        lines = [f'{indent}<{_TAGS[value["type"]]} type="{value["type"]}"{ident}>']
        for key, item in value.items():
            if key != "type":
                lines += _xml_value(key, item, indent + "  ", base)
        return [*lines, f"{indent}</{_TAGS[value['type']]}>"]
    if isinstance(value, bool):
        return [f'{indent}<boolean name="{name}" value="{str(value).lower()}"/>']
    if isinstance(value, int):
        return [f'{indent}<integer name="{name}" value="{value}"/>']
    if isinstance(value, float):
        return [f'{indent}<float name="{name}" value="{_f(value)}"/>']
    if isinstance(value, str):
        if name == "filename" and base is not None:  # relative to the XML file
            value = os.path.relpath(value, base)
        return [f"{indent}<string name={quoteattr(name)} value={quoteattr(value)}/>"]
    if isinstance(value, mi.ScalarColor3f):
        return [f'{indent}<rgb name="{name}" value="{_v(value)}"/>']
    if isinstance(value, mi.ScalarPoint3f):
        return [f'{indent}<point name="{name}" value="{_v(value)}"/>']
    if isinstance(value, mi.ScalarVector3f):
        return [f'{indent}<vector name="{name}" value="{_v(value)}"/>']
    if isinstance(value, mi.ScalarTransform4f):
        matrix = " ".join(_f(x) for x in np.array(value.matrix, dtype=np.float64).ravel())
        return [f'{indent}<transform name="{name}"><matrix value="{matrix}"/></transform>']
    raise TypeError(f"cannot write {name}={value!r} to Mitsuba XML")


def _f(x: float) -> str:
    return repr(float(x))


def _v(v: Any) -> str:
    return ", ".join(_f(x) for x in v)


def write_mitsuba_xml(scene: Scene, path: str | os.PathLike[str]) -> Path:
    """The scene as Mitsuba 3 XML, with its meshes as PLY files in ``<name>-meshes/`` beside it;
    ``mi.load_file`` reads it in any process that has imported converters.mitsuba."""
    path = Path(path)
    d = to_mitsuba_dict(scene, mesh_dir=path.parent / f"{path.stem}-meshes")
    lines = [
        f"<!-- Converted by rtlab from {quoteattr(scene.source)[1:-1]}: the "
        f"{scene.render.integrator} model.",
        "     Load it with mi.load_file in a process that has imported converters.mitsuba,",
        f'     which registers the "{classic.NAME}" integrator and the "{classic_material.NAME}",',
        f'     "{phong.NAME}" and "{mixed.NAME}" BSDFs. -->',
        '<scene version="3.0.0">',
    ]
    for key, value in d.items():
        if key != "type":
            lines += _xml_value(key, value, "  ", path.parent.resolve())
    lines.append("</scene>")
    with atomic_path(path) as tmp:
        tmp.write_text("\n".join(lines) + "\n")
    return path
