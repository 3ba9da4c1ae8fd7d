"""Scene model -> POV-Ray 3.7 SDL that reproduces the classic model exactly.

What makes POV-Ray compute the slides' model (each fact checked by
tests/reference/test_against_references.py and tests/converters/test_converter_bugs.py):

- ``#version 3.7`` and ``assumed_gamma 1.0``: linear colours, no gamma games.
- The camera: POV-Ray is left-handed and its ``angle`` is the *horizontal* field of view; a
  right-handed camera with a vertical field of view fy is ``right -x*W/H up y
  angle 2*atan(W/H*tan(fy/2))``. Rendered with ``-A`` its rays go through pixel centres.
- Every finish term is written out (POV-Ray's defaults differ): ``ambient`` times the global
  ``ambient_light``, ``diffuse`` with ``brilliance 1`` (N.L), ``phong``/``phong_size``
  (untinted, max(R.L, 0)^n), ``specular 0``, ``reflection`` a constant.
- ``max_trace_level`` = max_depth (it counts the primary ray as level 1 and returns black past
  it) and ``adc_bailout`` = min_coefficient (the chain's "coef << 1").
- A point light is a plain ``light_source`` (no fade); a directional light is a ``parallel``
  light placed far away, since its shadow rays only reach the plane through its location.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from tracer.image import atomic_path
from tracer.scene import (
    Box,
    Cylinder,
    DirectionalLight,
    Mesh,
    Plane,
    PointLight,
    Quad,
    Scene,
    Sphere,
    Torus,
    Triangle,
    scene_extent,
    to_world,
    triangles,
)
from tracer.scene.placement import one_eye
from tracer.scene.vectors import cross, sub, unit


def _num(x: float) -> str:
    """A float in full (round-trip) precision: POV-Ray parses doubles."""
    return repr(float(x))


def _vec(v: tuple[float, float, float] | list[float]) -> str:
    return f"<{_num(v[0])}, {_num(v[1])}, {_num(v[2])}>"


def horizontal_angle(fov_y: float, width: int, height: int) -> float:
    """POV-Ray's ``angle`` (horizontal, degrees) for a vertical field of view."""
    return math.degrees(2 * math.atan(width / height * math.tan(math.radians(fov_y) / 2)))


def _camera(scene: Scene) -> list[str]:
    cam = scene.camera
    if cam.stereo is None:
        return [
            "camera {",
            "  perspective",
            f"  location {_vec(cam.eye)}",
            f"  right -x*{_num(cam.width / cam.height)}",
            "  up y",
            f"  angle {_num(horizontal_angle(cam.fov_y, cam.width, cam.height))}",
            f"  sky {_vec(cam.up)}",
            f"  look_at {_vec(cam.look_at)}",
            "}",
        ]
    # One eye of a stereo pair (tracer/cpp/03_camera.h stereo_eye()). POV-Ray's perspective
    # ray is direction + x right + y up, x and y from -1/2 to 1/2 (pixel centres with -A): with
    # the vectors given in world space and no look_at or angle to re-aim them, a direction with
    # a component along right is the shifted, off-axis window itself.
    eye, look_at, shift = one_eye(scene, "POV-Ray renders one eye at a time")
    forward = unit(sub(look_at, eye))
    right = unit(cross(forward, cam.up))
    up = cross(right, forward)
    height = 2 * math.tan(math.radians(cam.fov_y) / 2)
    width = height * cam.width / cam.height
    direction = tuple(f + shift * r for f, r in zip(forward, right, strict=True))
    return [
        "camera {",
        "  perspective",
        f"  location {_vec(eye)}",
        f"  direction {_vec(direction)}",
        f"  right {_vec(tuple(width * r for r in right))}",
        f"  up {_vec(tuple(height * u for u in up))}",
        "}",
    ]


def to_povray(scene: Scene) -> str:
    """The scene as POV-Ray 3.7 SDL text; render with ``povray -D -A``. A stereo pair converts
    one eye at a time (layout ``left`` or ``right``: tracer.render.eye_scene)."""
    ren = scene.render
    out = [
        f"// Converted by rtlab from {scene.source}: the classic model, every term explicit.",
        "#version 3.7;",
        "global_settings {",
        "  assumed_gamma 1.0",
        f"  max_trace_level {ren.max_depth}",
        f"  adc_bailout {_num(ren.min_coefficient)}",
        f"  ambient_light rgb {_vec(ren.ambient_light)}",
        "}",
        f"background {{ rgb {_vec(ren.background)} }}",
        *_camera(scene),
    ]
    far = 1.0e4 * scene_extent(scene)
    for light in scene.lights:
        if isinstance(light, PointLight):
            out.append(f"light_source {{ {_vec(light.position)} color rgb {_vec(light.color)} }}")
        elif isinstance(light, DirectionalLight):
            d = light.direction
            src = (-d[0] * far, -d[1] * far, -d[2] * far)
            out.append(
                f"light_source {{ {_vec(src)} color rgb {_vec(light.color)} "
                f"parallel point_at <0, 0, 0> }}"
            )
    ident = {name: f"M{k}_{_safe(name)}" for k, name in enumerate(scene.materials)}
    for name, m in scene.materials.items():
        out += [
            f"#declare {ident[name]} = texture {{",
            f"  pigment {{ rgb {_vec(m.color)} }}",
            "  finish {",
            f"    ambient {_num(m.ambient)} emission 0",
            f"    diffuse {_num(m.diffuse)} brilliance 1",
            f"    phong {_num(m.specular)} phong_size {_num(m.shininess)}",
            "    specular 0",
            f"    reflection {{ {_num(m.reflectivity)} }}",
            "  }",
            "}",
        ]
    for i, obj in enumerate(scene.objects):
        tex = f"texture {{ {ident[obj.material]} }}"
        if isinstance(obj, Sphere):
            out.append(
                f"sphere {{ {_vec(obj.center)}, {_num(obj.radius)} {tex} }}  // objects[{i}]"
            )
        elif isinstance(obj, Plane):
            n = obj.normal
            dist = sum(a * b for a, b in zip(n, obj.point, strict=True))
            out.append(f"plane {{ {_vec(n)}, {_num(dist)} {tex} }}  // objects[{i}]")
        elif isinstance(obj, Box):
            placed = f" {_matrix(to_world(obj))}" if obj.transform is not None else ""
            out.append(f"box {{ {_vec(obj.min)}, {_vec(obj.max)} {tex}{placed} }}  // objects[{i}]")
        elif isinstance(obj, Cylinder):
            # POV-Ray's cylinder is given by base and top like ours; only the user transform
            # remains to apply.
            placed = f" {_matrix(obj.transform.matrix)}" if obj.transform is not None else ""
            cap = "" if obj.capped else " open"
            out.append(
                f"cylinder {{ {_vec(obj.base)}, {_vec(obj.top)}, {_num(obj.radius)}{cap} {tex}"
                f"{placed} }}  // objects[{i}]"
            )
        elif isinstance(obj, Torus):
            # POV-Ray's torus lies around its y axis; a quarter turn about x takes y to our z.
            y_to_z = np.array([[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]], float)
            out.append(
                f"torus {{ {_num(obj.major_radius)}, {_num(obj.minor_radius)} sturm {tex} "
                f"{_matrix(to_world(obj) @ y_to_z)} }}  // objects[{i}]"
            )
        elif isinstance(obj, Triangle | Quad | Mesh):
            out.append(_mesh2(*triangles(obj), tex, i))
    return "\n".join(out) + "\n"


def _matrix(m: np.ndarray) -> str:
    """A 4x4 object-to-world matrix (column vectors, p' = A p + t) as POV-Ray's ``matrix``,
    which multiplies row vectors: its rows are A's columns, then t."""
    a = m[:3, :3]
    values = [*a[:, 0], *a[:, 1], *a[:, 2], *m[:3, 3]]
    return "matrix <" + ", ".join(_num(v) for v in values) + ">"


def _mesh2(vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray | None, tex: str,
           index: int) -> str:  # fmt: skip
    """A triangle mesh as POV-Ray's mesh2; with vertex normals where the mesh is smooth."""
    lines = [f"mesh2 {{  // objects[{index}]", f"  vertex_vectors {{ {len(vertices)},"]
    lines.append(",\n".join(f"    {_vec(v)}" for v in vertices))
    lines.append("  }")
    if normals is not None:
        lines.append(f"  normal_vectors {{ {len(normals)},")
        lines.append(",\n".join(f"    {_vec(n)}" for n in normals))
        lines.append("  }")
    lines.append(f"  face_indices {{ {len(faces)},")
    lines.append(",\n".join(f"    <{a}, {b}, {c}>" for a, b, c in faces))
    lines.append("  }")
    lines.append(f"  {tex}")
    lines.append("}")
    return "\n".join(lines)


def _safe(name: str) -> str:
    """A material name cut down to what a POV-Ray identifier may hold."""
    return "".join(c if c.isascii() and c.isalnum() else "_" for c in name)


def write_povray(scene: Scene, path: str | os.PathLike[str]) -> Path:
    with atomic_path(path) as tmp:
        tmp.write_text(to_povray(scene))
    return Path(path)
