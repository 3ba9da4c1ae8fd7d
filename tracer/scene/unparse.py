"""Unparsing: a ``Scene`` back to a plain dict in the scene language, which
``parse_scene`` reads back to an equal scene (meshes from files keep their file name)."""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any

from tracer.scene.model import Mesh, Transform
from tracer.scene.objects import resolve_file

if TYPE_CHECKING:  # Scene.to_dict calls this: the whole scene is built on it
    from tracer.scene.document import Scene


def unparse(scene: Scene) -> dict[str, Any]:
    def plain(obj: Any, drop: tuple[str, ...] = ()) -> dict[str, Any]:
        return {
            k: list(v) if isinstance(v, tuple) else v
            for k, v in dataclasses.asdict(obj).items()
            if k not in drop
        }

    def unparse_object(obj: Any) -> dict[str, Any]:
        if isinstance(obj, Mesh):
            d: dict[str, Any] = {"type": "mesh", "material": obj.material, "smooth": obj.smooth}
            if obj.file is not None:
                d["file"] = str(resolve_file(None, "", obj.file, scene.base_dir))
                if obj.transform is not None:
                    d["transform"] = obj.transform.to_dict()
            else:  # the vertices as they are now, the transform already applied
                d["vertices"] = obj.vertices.tolist()
                d["faces"] = obj.faces.tolist()
            return d
        d = {k: getattr(obj, k) for k in (f.name for f in dataclasses.fields(obj))}
        for k, v in list(d.items()):
            if isinstance(v, Transform):
                d[k] = v.to_dict()
            elif v is None:
                del d[k]
            elif isinstance(v, tuple):
                d[k] = [list(x) if isinstance(x, tuple) else x for x in v]
        return d

    return {
        "camera": plain(scene.camera, () if scene.camera.stereo is not None else ("stereo",)),
        "render": plain(scene.render),
        "materials": {name: plain(m, ("name",)) for name, m in scene.materials.items()},
        "lights": [plain(light) for light in scene.lights],
        "objects": [unparse_object(obj) for obj in scene.objects],
    }
