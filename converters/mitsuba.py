"""Scene model -> Mitsuba 3, with the classic model running inside Mitsuba.

Mitsuba has no plugin for the slides' model (no fall-off-free point light, no ambient term, no
untinted Phong highlight), so this module registers two small plugins written in Python on
Dr.Jit, in every variant it can load, as soon as it is imported:

- ``rtlab_classic_material`` BSDF: carries a material's classic terms (``color``, ``ambient``,
  ``diffuse``, ``specular``, ``shininess``, ``reflectivity``). It scatters nothing; it is read
  by the integrator.
- ``rtlab_classic`` integrator: the classic algorithm of tracer/cpp/10_classic.h, step by step,
  using Mitsuba's own ``ray_intersect`` for primary and secondary rays and ``ray_test`` for
  shadow rays. Lights are Mitsuba's own ``point`` (its ``intensity`` read as the classic light
  colour, without fall-off) and ``directional`` (its ``irradiance`` read as the colour)
  emitters.

The scene is emitted both as a dict for ``mi.load_dict`` and as an XML file that
``mi.load_file`` reads in any process that has imported this module.

Variants: ``llvm_ad_rgb`` (vectorised, JIT-compiled) where libLLVM 19 is installed, which the
Makefile does (Debian 12's default libLLVM 15 aborts in it); otherwise ``scalar_rgb``, with a
message saying why.
"""

from __future__ import annotations

import math
import os
import sys
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

import numpy as np

from tracer.image import atomic_path
from tracer.scene import DirectionalLight, Plane, PointLight, Scene, Sphere

LIBLLVM = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
if "DRJIT_LIBLLVM_PATH" not in os.environ and os.path.exists(LIBLLVM):
    os.environ["DRJIT_LIBLLVM_PATH"] = LIBLLVM

import drjit as dr  # noqa: E402  (after DRJIT_LIBLLVM_PATH is set)
import mitsuba as mi  # noqa: E402

VARIANTS = ("scalar_rgb", "llvm_ad_rgb")
PLUGIN = "rtlab_classic"
MATERIAL_PLUGIN = "rtlab_classic_material"
#: Planes become Mitsuba disks of this many scene sizes in radius, centred below the camera: a
#: ray must pass within ~1/PLANE_SCALE radians of the horizon to miss one, far below a pixel's
#: angle. A disk, unlike a rectangle (a triangle mesh in Mitsuba 3.9, whose float32 vertices
#: would lie 1e6 units out), is intersected in its local frame, where the distance along the
#: normal keeps its precision whatever the radius.
PLANE_SCALE = 1.0e6


def llvm_available() -> tuple[bool, str]:
    """Whether llvm_ad_rgb can run here, and if not, why."""
    if "llvm_ad_rgb" not in mi.variants():
        return False, "this Mitsuba build has no llvm_ad_rgb variant"
    path = os.environ.get("DRJIT_LIBLLVM_PATH", "")
    if not path or not os.path.exists(path):
        return False, (
            f"libLLVM 19 not found ({LIBLLVM}); Debian's default libLLVM 15 aborts in "
            "llvm_ad_rgb. Run 'make setup' (it installs libllvm19)"
        )
    return True, ""


_fallback_told = False


def default_variant() -> str:
    """llvm_ad_rgb where it works, else scalar_rgb (saying why, once)."""
    global _fallback_told
    ok, why = llvm_available()
    if ok:
        return "llvm_ad_rgb"
    if not _fallback_told:
        print(f"rtlab: Mitsuba falls back to scalar_rgb: {why}", file=sys.stderr)
        _fallback_told = True
    return "scalar_rgb"


# --------------------------------------------------------------------------- the plugins


def _make_plugins() -> tuple[type, type]:
    """The two plugin classes, derived from the *current* variant's base classes."""

    class ClassicMaterial(mi.BSDF):
        """A material of the classic model; the integrator reads its terms.

        (Properties.get cannot take a colour default, hence the `in` tests below.)
        """

        def __init__(self, props: mi.Properties) -> None:
            mi.BSDF.__init__(self, props)
            color = props["color"] if "color" in props else (1.0, 1.0, 1.0)  # noqa: SIM401
            self.color = tuple(float(c) for c in color)
            self.ambient = float(props.get("ambient", 0.1))
            self.diffuse = float(props.get("diffuse", 0.6))
            self.specular = float(props.get("specular", 0.0))
            self.shininess = float(props.get("shininess", 40.0))
            self.reflectivity = float(props.get("reflectivity", 0.0))
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

    class ClassicIntegrator(mi.SamplingIntegrator):
        """The slides' "Simple Ray Tracing Algorithm" on Mitsuba's ray queries."""

        def __init__(self, props: mi.Properties) -> None:
            mi.SamplingIntegrator.__init__(self, props)
            self.max_depth = int(props.get("max_depth", 5))
            self.min_coefficient = float(props.get("min_coefficient", 0.0))
            bg = props["background"] if "background" in props else (0, 0, 0)  # noqa: SIM401
            amb = props["ambient_light"] if "ambient_light" in props else (1, 1, 1)  # noqa: SIM401
            self.background = tuple(float(c) for c in bg)
            self.ambient_light = tuple(float(c) for c in amb)
            self._prepared: tuple[Any, Any] | None = None

        # -- per scene, once: lights, and the geometry and material of every shape ----------
        def _prepare(self, scene: mi.Scene) -> Any:
            key = id(scene)
            if self._prepared is not None and self._prepared[0] == key:
                return self._prepared[1]
            lights = []
            for emitter in scene.emitters():
                params = mi.traverse(emitter)
                if "position" in params:
                    pos = [float(x) for x in np.ravel(params["position"])]
                    color = [float(x) for x in np.ravel(params["intensity.value"])]
                    lights.append(("point", pos, color))
                elif "irradiance.value" in params:
                    m = np.array(params["to_world"].matrix, dtype=np.float64).reshape(4, 4)
                    d = m[:3, 2] / np.linalg.norm(m[:3, 2])
                    color = [float(x) for x in np.ravel(params["irradiance.value"])]
                    lights.append(("directional", d.tolist(), color))
                else:
                    raise ValueError(f"{PLUGIN} integrator: unsupported emitter {emitter}")
            shapes = scene.shapes()
            rows = [_shape_row(shape) for shape in shapes]
            if dr.is_jit_v(mi.Float):
                # Shapes are pointers in JIT variants: their registry ids index the table.
                ids = [int(dr.reinterpret_array(mi.UInt32, mi.ShapePtr(s))[0]) for s in shapes]
                table = np.zeros((max(ids) + 1, len(ROW)))
                for sid, row in zip(ids, rows, strict=True):
                    table[sid] = row
                columns = {k: mi.Float64(table[:, i]) for i, k in enumerate(ROW)}
            else:  # scalar: one ray at a time; the shape is a Python object with an id
                columns = {
                    s.id(): dict(zip(ROW, row, strict=True))
                    for s, row in zip(shapes, rows, strict=True)
                }
            self._prepared = (key, (lights, columns))
            return self._prepared[1]

        @staticmethod
        def _lookup(columns: Any, si: mi.SurfaceInteraction3f, active: Any) -> dict[str, Any]:
            if dr.is_jit_v(mi.Float):
                idx = dr.reinterpret_array(mi.UInt32, si.shape)
                return {k: dr.gather(mi.Float64, v, idx, active) for k, v in columns.items()}
            return columns[si.shape.id()]

        def sample(self, scene, sampler, ray, medium=None, active=True) -> Any:  # noqa: ANN001
            lights, columns = self._prepare(scene)
            # Mitsuba decides visibility in float32 (ray_intersect, ray_test); the shading, as
            # in the C++ core, is done in double: the hit is recomputed from the shape's own
            # parameters (robust sphere roots, Haines et al.), so that the comparison measures
            # the model and Mitsuba's visibility, not float32 round-off in the shading.
            o = mi.Point3d(ray.o)
            d = mi.Vector3d(ray.d)
            color = mi.Color3d(0.0)
            coef = mi.Float64(1.0)
            active = mi.Bool(active)
            background = mi.Color3d(self.background)
            ambient_light = mi.Color3d(self.ambient_light)
            # The primary ray is level 1; past max_depth the ray returns black. The loop is
            # unrolled: each level is the same straight-line code.
            # (In scalar variants `active` is a plain bool and a finished ray stops at once; in
            # JIT variants all levels are traced as one kernel, finished lanes masked off.)
            scalar = not dr.is_jit_v(mi.Float)
            for _level in range(self.max_depth):
                active &= coef >= self.min_coefficient  # "stop when coef << 1"
                if scalar and not active:
                    break
                si = scene.ray_intersect(mi.Ray3f(mi.Point3f(o), mi.Vector3f(d)), active)
                miss = active & ~si.is_valid()
                color += dr.select(miss, coef * background, 0.0)
                active &= si.is_valid()
                if scalar and not active:
                    break
                g = self._lookup(columns, si, active)
                t, N = _refine_hit(g, o, d, mi.Float64(si.t), mi.Vector3d(si.n))
                p = o + t * d
                N = dr.select(dr.dot(N, d) > 0, -N, N)  # face the incoming ray
                R = d - 2 * dr.dot(d, N) * N
                c = mi.Color3d(g["r"], g["g"], g["b"])
                local = c * g["ambient"] * ambient_light
                # New rays start a little along their own direction, so they stay on the line
                # through p; 2^-16 of the coordinates' size is ~256 float32 ulps, clear of
                # Mitsuba's float32 intersection error.
                eps = (1.0 + dr.max(dr.abs(p))) * 2.0**-16
                for kind, where, light_color in lights:
                    if kind == "point":
                        to = mi.Point3d(where) - p
                        dist = dr.norm(to)
                        L = to / dist
                    else:
                        L = -mi.Vector3d(where)
                        dist = mi.Float64(1e30)
                    NL = dr.dot(N, L)
                    lit = active & (NL > 0)
                    shadow = mi.Ray3f(mi.Point3f(p + eps * L), mi.Vector3f(L))
                    shadow.maxt = mi.Float(dist - eps)
                    lit &= ~scene.ray_test(shadow, lit)
                    RL = dr.maximum(dr.dot(R, L), 0.0)
                    lc = mi.Color3d(light_color)
                    term = (
                        g["diffuse"] * NL * c * lc
                        + g["specular"] * dr.power(RL, g["shininess"]) * lc
                    )
                    local += dr.select(lit, term, 0.0)
                color += dr.select(active, coef * local, 0.0)
                coef *= g["reflectivity"]
                active &= g["reflectivity"] > 0
                o, d = p + eps * R, R
            return mi.Color3f(color), mi.Bool(True), []

        def aov_names(self) -> list[str]:
            return []

        def to_string(self) -> str:
            return f"ClassicIntegrator[max_depth={self.max_depth}]"

    return ClassicMaterial, ClassicIntegrator


#: One row per shape: its kind, its geometry and its classic material.
ROW = ("kind", "ax", "ay", "az", "radius", "nx", "ny", "nz", "r", "g", "b", "ambient",
       "diffuse", "specular", "shininess", "reflectivity")  # fmt: skip
SPHERE, PLANE, OTHER = 0.0, 1.0, 2.0


def _shape_row(shape: Any) -> list[float]:
    """Geometry from the shape's own parameters (its to_world), material from its BSDF."""
    m = shape.bsdf()
    material = [*m.color, m.ambient, m.diffuse, m.specular, m.shininess, m.reflectivity]
    to_world = np.array(mi.traverse(shape)["to_world"].matrix, dtype=np.float64).reshape(4, 4)
    if shape.shape_type() == mi.ShapeType.Sphere:  # to_world = translate(c) scale(r)
        return [SPHERE, *to_world[:3, 3], float(np.linalg.norm(to_world[:3, 0])), 0, 0, 0,
                *material]  # fmt: skip
    if shape.shape_type() in (mi.ShapeType.Disk, mi.ShapeType.Rectangle):  # z = 0, normal +z
        n = np.cross(to_world[:3, 0], to_world[:3, 1])
        return [PLANE, *to_world[:3, 3], 0.0, *(n / np.linalg.norm(n)), *material]
    return [OTHER, 0, 0, 0, 0, 0, 0, 0, *material]


def _sphere_hit(g: dict[str, Any], o: Any, d: Any, t_mitsuba: Any) -> tuple[Any, Any]:
    """The root of the robust quadratic (tracer/cpp/05_sphere.h) nearest to Mitsuba's t."""
    center = mi.Point3d(g["ax"], g["ay"], g["az"])
    f = o - center
    a = dr.dot(d, d)
    b = dr.dot(f, d)
    r2 = g["radius"] * g["radius"]
    l = f - (b / a) * d  # noqa: E741  (Haines et al.'s name)
    disc = dr.maximum(a * (r2 - dr.dot(l, l)), 0.0)
    q = -(b + dr.copysign(dr.sqrt(disc), b))
    t0, t1 = (dr.dot(f, f) - r2) / q, q / a
    t = dr.select(dr.abs(t0 - t_mitsuba) < dr.abs(t1 - t_mitsuba), t0, t1)
    return t, (o + t * d - center) / g["radius"]


def _plane_hit(g: dict[str, Any], o: Any, d: Any) -> tuple[Any, Any]:
    """(a - o).n / (d.n), the plane's implicit form."""
    n = mi.Vector3d(g["nx"], g["ny"], g["nz"])
    return dr.dot(mi.Point3d(g["ax"], g["ay"], g["az"]) - o, n) / dr.dot(d, n), n


def _refine_hit(g: dict[str, Any], o: Any, d: Any, t_mitsuba: Any, n_mitsuba: Any) -> tuple:
    """The hit's t and outward unit normal in double, from the shape's parameters."""
    if not dr.is_jit_v(mi.Float):  # scalar: one ray, one kind of shape
        if g["kind"] == SPHERE:
            t, n = _sphere_hit(g, o, d, t_mitsuba)
        elif g["kind"] == PLANE:
            t, n = _plane_hit(g, o, d)
        else:
            t, n = t_mitsuba, n_mitsuba
        return t, dr.normalize(n)
    t_sphere, n_sphere = _sphere_hit(g, o, d, t_mitsuba)
    t_plane, n_plane = _plane_hit(g, o, d)
    is_sphere, is_plane = g["kind"] == SPHERE, g["kind"] == PLANE
    t = dr.select(is_sphere, t_sphere, dr.select(is_plane, t_plane, t_mitsuba))
    n = dr.select(is_sphere, n_sphere, dr.select(is_plane, n_plane, n_mitsuba))
    return t, dr.normalize(n)


_registered: set[str] = set()


def use_variant(variant: str | None = None) -> str:
    """Set a Mitsuba variant and make sure the classic plugins are registered in it."""
    variant = variant or default_variant()
    mi.set_variant(variant)
    if variant not in _registered:
        material, integrator = _make_plugins()
        mi.register_bsdf(MATERIAL_PLUGIN, lambda props: material(props))
        mi.register_integrator(PLUGIN, lambda props: integrator(props))
        _registered.add(variant)
    return variant


def _register_all() -> None:
    """On import: register in every variant this machine can run, then pick the default."""
    for variant in VARIANTS:
        if variant == "llvm_ad_rgb" and not llvm_available()[0]:
            continue
        if variant in mi.variants():
            use_variant(variant)
    use_variant(default_variant())


# --------------------------------------------------------------------------- the scene


def plane_matrix(plane: Plane, radius: float, eye: tuple[float, float, float]) -> np.ndarray:
    """to_world of a disk (unit radius at z = 0, normal +z) standing in for a plane, centred on
    the point of the plane nearest the eye."""
    n = np.array(plane.normal, dtype=np.float64)
    centre = np.array(eye) - np.dot(np.array(eye) - plane.point, n) * n
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    s = np.cross(helper, n)
    s /= np.linalg.norm(s)
    t = np.cross(n, s)
    m = np.eye(4)
    m[:3, 0] = s * radius
    m[:3, 1] = t * radius
    m[:3, 2] = n
    m[:3, 3] = centre
    return m


def scene_size(scene: Scene) -> float:
    pts = [scene.camera.eye, scene.camera.look_at]
    size = 1.0
    for obj in scene.objects:
        if isinstance(obj, Sphere):
            pts.append(obj.center)
            size = max(size, obj.radius)
        else:
            pts.append(obj.point)
    return size + max(max(abs(c) for c in p) for p in pts)


def _sampler(scene: Scene) -> dict[str, Any]:
    if scene.render.spp == 1:  # exactly the pixel centre, as the tracer and POV-Ray -A do
        return {"type": "stratified", "sample_count": 1, "jitter": False}
    return {"type": "independent", "sample_count": scene.render.spp, "seed": scene.render.seed}


def to_mitsuba_dict(scene: Scene) -> dict[str, Any]:
    """The scene as a dict for ``mi.load_dict`` (call ``use_variant`` first)."""
    cam, ren = scene.camera, scene.render
    d: dict[str, Any] = {
        "type": "scene",
        "integrator": {
            "type": PLUGIN,
            "max_depth": ren.max_depth,
            "min_coefficient": ren.min_coefficient,
            "background": mi.ScalarColor3f(ren.background),
            "ambient_light": mi.ScalarColor3f(ren.ambient_light),
        },
        "sensor": {
            "type": "perspective",
            "fov": cam.fov_y,
            "fov_axis": "y",
            "to_world": mi.ScalarTransform4f().look_at(
                origin=cam.eye, target=cam.look_at, up=cam.up
            ),
            "sampler": _sampler(scene),
            "film": {
                "type": "hdrfilm",
                "width": cam.width,
                "height": cam.height,
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
                "component_format": "float32",
            },
        },
    }
    for i, light in enumerate(scene.lights):
        color = {"type": "rgb", "value": list(light.color)}
        if isinstance(light, PointLight):
            d[f"light_{i}"] = {
                "type": "point",
                "position": list(light.position),
                "intensity": color,
            }
        elif isinstance(light, DirectionalLight):
            d[f"light_{i}"] = {
                "type": "directional", "direction": list(light.direction), "irradiance": color,
            }  # fmt: skip
    half = PLANE_SCALE * scene_size(scene)
    for i, obj in enumerate(scene.objects):
        m = scene.materials[obj.material]
        bsdf = {
            "type": MATERIAL_PLUGIN,
            "color": mi.ScalarColor3f(m.color),
            "ambient": m.ambient,
            "diffuse": m.diffuse,
            "specular": m.specular,
            "shininess": m.shininess,
            "reflectivity": m.reflectivity,
        }
        if isinstance(obj, Sphere):
            shape = {"type": "sphere", "center": list(obj.center), "radius": obj.radius}
        else:
            matrix = plane_matrix(obj, half, cam.eye)
            shape = {"type": "disk", "to_world": mi.ScalarTransform4f(matrix.tolist())}
        d[f"object_{i}"] = {**shape, "bsdf": bsdf}
    return d


def _f(x: float) -> str:
    return repr(float(x))


def _v(v: Any) -> str:
    return ", ".join(_f(x) for x in v)


def to_mitsuba_xml(scene: Scene) -> str:
    """The scene as Mitsuba 3 XML; loads with ``mi.load_file`` once this module is imported."""
    cam, ren = scene.camera, scene.render
    sampler = _sampler(scene)
    sampler_xml = f'    <sampler type="{sampler["type"]}">\n'
    sampler_xml += f'      <integer name="sample_count" value="{sampler["sample_count"]}"/>\n'
    if "jitter" in sampler:
        sampler_xml += '      <boolean name="jitter" value="false"/>\n'
    if "seed" in sampler:
        sampler_xml += f'      <integer name="seed" value="{sampler["seed"]}"/>\n'
    sampler_xml += "    </sampler>\n"
    out = [
        f"<!-- Converted by rtlab from {quoteattr(scene.source)[1:-1]}: the classic model.",
        "     Load it with mi.load_file in a process that has imported converters.mitsuba,",
        f'     which registers the "{PLUGIN}" integrator and "{MATERIAL_PLUGIN}" BSDF. -->',
        '<scene version="3.0.0">',
        f'  <integrator type="{PLUGIN}">',
        f'    <integer name="max_depth" value="{ren.max_depth}"/>',
        f'    <float name="min_coefficient" value="{_f(ren.min_coefficient)}"/>',
        f'    <rgb name="background" value="{_v(ren.background)}"/>',
        f'    <rgb name="ambient_light" value="{_v(ren.ambient_light)}"/>',
        "  </integrator>",
        '  <sensor type="perspective">',
        f'    <float name="fov" value="{_f(cam.fov_y)}"/>',
        '    <string name="fov_axis" value="y"/>',
        '    <transform name="to_world">',
        f'      <lookat origin="{_v(cam.eye)}" target="{_v(cam.look_at)}" up="{_v(cam.up)}"/>',
        "    </transform>",
        sampler_xml.rstrip("\n"),
        '    <film type="hdrfilm">',
        f'      <integer name="width" value="{cam.width}"/>',
        f'      <integer name="height" value="{cam.height}"/>',
        '      <rfilter type="box"/>',
        '      <string name="pixel_format" value="rgb"/>',
        '      <string name="component_format" value="float32"/>',
        "    </film>",
        "  </sensor>",
    ]
    for i, light in enumerate(scene.lights):
        if isinstance(light, PointLight):
            out += [
                f'  <emitter type="point" id="light_{i}">',
                f'    <point name="position" value="{_v(light.position)}"/>',
                f'    <rgb name="intensity" value="{_v(light.color)}"/>',
                "  </emitter>",
            ]
        elif isinstance(light, DirectionalLight):
            out += [
                f'  <emitter type="directional" id="light_{i}">',
                f'    <vector name="direction" value="{_v(light.direction)}"/>',
                f'    <rgb name="irradiance" value="{_v(light.color)}"/>',
                "  </emitter>",
            ]
    half = PLANE_SCALE * scene_size(scene)
    for i, obj in enumerate(scene.objects):
        m = scene.materials[obj.material]
        if isinstance(obj, Sphere):
            out += [
                f'  <shape type="sphere" id="object_{i}">',
                f'    <point name="center" value="{_v(obj.center)}"/>',
                f'    <float name="radius" value="{_f(obj.radius)}"/>',
            ]
        else:
            matrix = " ".join(_f(x) for x in plane_matrix(obj, half, cam.eye).ravel())
            out += [
                f'  <shape type="disk" id="object_{i}">  <!-- a plane -->',
                f'    <transform name="to_world"><matrix value="{matrix}"/></transform>',
            ]
        out += [
            f'    <bsdf type="{MATERIAL_PLUGIN}">  <!-- material {quoteattr(obj.material)} -->',
            f'      <rgb name="color" value="{_v(m.color)}"/>',
            f'      <float name="ambient" value="{_f(m.ambient)}"/>',
            f'      <float name="diffuse" value="{_f(m.diffuse)}"/>',
            f'      <float name="specular" value="{_f(m.specular)}"/>',
            f'      <float name="shininess" value="{_f(m.shininess)}"/>',
            f'      <float name="reflectivity" value="{_f(m.reflectivity)}"/>',
            "    </bsdf>",
            "  </shape>",
        ]
    out.append("</scene>")
    return "\n".join(out) + "\n"


def write_mitsuba_xml(scene: Scene, path: str | os.PathLike[str]) -> Path:
    with atomic_path(path) as tmp:
        tmp.write_text(to_mitsuba_xml(scene))
    return Path(path)


def horizontal_fov(fov_y: float, width: int, height: int) -> float:
    return math.degrees(2 * math.atan(width / height * math.tan(math.radians(fov_y) / 2)))


_register_all()
