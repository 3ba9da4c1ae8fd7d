"""Rendering a scene model with the C++ core."""

from __future__ import annotations

import dataclasses
import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from tracer import _core
from tracer.scene import (
    Box,
    Cylinder,
    DirectionalLight,
    Mesh,
    Plane,
    PointLight,
    Quad,
    Scene,
    SceneError,
    Sphere,
    Torus,
    Triangle,
    cylinder_height,
    to_world,
    triangles,
)

AOV_CHANNELS = ("depth", "object_id", "N.X", "N.Y", "N.Z")


class ImageTooLargeError(MemoryError):
    """A render refused before it starts: its image would not fit in the memory this process
    may still use. (Not a SceneError: the scene is valid, this machine is too small for it.)"""


def _read(path: str) -> str | None:
    try:
        with open(path) as f:
            return f.read()
    except OSError:
        return None


def _meminfo_available() -> int | None:
    """MemAvailable of /proc/meminfo: what the kernel can give without swapping."""
    text = _read("/proc/meminfo")
    for line in (text or "").splitlines():
        if line.startswith("MemAvailable:"):
            return int(line.split()[1]) * 1024  # the file counts in kiB
    return None


def _cgroup_available() -> int | None:
    """What the memory limit of this process's control group (a container's) leaves: limit -
    usage, in cgroup v2 (memory.max, memory.current) or v1 (memory.limit_in_bytes,
    memory.usage_in_bytes), in the process's own group or, where that is not visible (inside a
    container), the root; None where there is no limit."""
    v2, v1 = [""], [""]
    for line in (_read("/proc/self/cgroup") or "").splitlines():
        number, controllers, path = [*line.split(":", 2), "", ""][:3]
        if number == "0" and not controllers:
            v2.insert(0, path.strip().rstrip("/"))
        elif "memory" in controllers.split(","):
            v1.insert(0, path.strip().rstrip("/"))
    candidates = [(f"/sys/fs/cgroup{g}", "memory.max", "memory.current") for g in v2] + [
        (f"/sys/fs/cgroup/memory{g}", "memory.limit_in_bytes", "memory.usage_in_bytes") for g in v1
    ]
    for base, limit_file, usage_file in candidates:
        limit, usage = _read(f"{base}/{limit_file}"), _read(f"{base}/{usage_file}")
        if limit is None or usage is None:
            continue
        # v2 writes "max" for no limit; v1 a number near 2^63.
        if limit.strip() == "max" or int(limit) >= 2**62:
            return None
        return max(0, int(limit) - int(usage))
    return None


def memory_available() -> tuple[int, str] | None:
    """The bytes this process may still allocate and where the figure comes from: the smaller
    of MemAvailable and what the cgroup limit leaves; None where neither can be read."""
    found = [
        (n, what)
        for n, what in (
            (_meminfo_available(), "MemAvailable in /proc/meminfo"),
            (_cgroup_available(), "the cgroup memory limit"),
        )
        if n is not None
    ]
    return min(found) if found else None


def _gib(n: int) -> str:
    return f"{n / 2**30:.1f} GiB"


def check_memory(scene: Scene, bytes_per_value: int = 4) -> None:
    """Refuse, before anything is allocated, a render whose image (float32 values: 3 per pixel,
    5 for aov) would not fit in the memory left, rather than let the kernel kill the process
    half way through. ``bytes_per_value`` counts every copy a caller keeps of each value. A
    stereo pair's two eyes are kept while they are composed: their pixels count too."""
    c = scene.camera
    channels = len(AOV_CHANNELS) if scene.render.integrator == "aov" else 3
    rows, columns = c.image_shape
    pixels = rows * columns + (c.width * c.height * len(_eyes(scene)) if c.stereo else 0)
    needed = pixels * channels * bytes_per_value
    available = memory_available()
    if available is not None and needed > available[0]:
        raise ImageTooLargeError(
            f"{scene.source}: a {columns}x{rows} image needs {needed} bytes "
            f"({_gib(needed)}), and {available[0]} bytes ({_gib(available[0])}) are available "
            f"({available[1]}); render it smaller"
        )


@dataclass(frozen=True)
class RenderResult:
    #: classic: linear RGB, shape (height, width, 3) (a stereo pair: Camera.image_shape, its
    #: eyes composed); aov: (height, width, 5), the channels of
    #: AOV_CHANNELS (depth: distance along the primary ray, inf on a miss; object_id: index in
    #: [[objects]], -1 on a miss; N: the shading normal, front side, 0 on a miss).
    image: npt.NDArray[np.float32]
    rays: dict[str, int]  # counts of primary, secondary (reflected) and shadow rays
    seconds: float  # wall time of the render itself
    threads: int
    #: what traced the image: "classic" (one ray at a time), "classic_packets" (a packet of rays
    #: at a time: scenes of spheres and planes only, so packets=True falls back to "classic"
    #: elsewhere), "aov", "aov_packets" (packets of primary rays: scenes of meshes only, with
    #: packets=True), "path" (the lecture's scene queries, packets=False) or "path_culled"
    #: (objects culled by their world bounds, packets=True).
    integrator: str = "classic"

    def _repr_png_(self) -> bytes:
        """Jupyter shows a result as its image (tracer/display.py: clipped sRGB; an aov
        render's normals)."""
        from tracer.display import picture

        return picture(self).png()


def default_threads() -> int:
    """All the cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def _set_render(core: _core.Scene, scene: Scene) -> None:
    r = scene.render
    core.set_render(r.max_depth, r.min_coefficient, r.spp, r.seed, r.background, r.ambient_light,
                    r.sampler)  # fmt: skip


# --------------------------------------------------------------------------- stereo pairs
# Slide "Stereoscopy": an eye of a stereo pair is a camera (tracer/cpp/03_camera.h
# stereo_eye()); each eye is rendered like any single camera, then the two are composed.

#: The eyes a stereo layout renders, left first.
_LAYOUT_EYES = {
    "side_by_side": ("left", "right"),
    "over_under": ("left", "right"),
    "anaglyph": ("left", "right"),
    "left": ("left",),
    "right": ("right",),
}
_SIDE = {"left": -1, "right": +1}

#: Eric Dubois, "A projection method to generate anaglyph stereo images", ICASSP 2001, and his
#: "Least squares how to" for Photoshop (www.site.uottawa.ca/~edubois/anaglyph/): the red-cyan
#: matrices (rows: the anaglyph's R, G, B; columns: the eye's R, G, B), the least-squares
#: projection of the stereo pair, seen through the red and cyan filters of the glasses, onto
#: what one display colour can show both eyes. They are derived from the spectra of a CRT's
#: phosphors (Rec. 709 / sRGB primaries) and the filters, and act on linear RGB (before any
#: gamma encoding): rtlab's images are linear RGB in those primaries. Each row of [L R] sums to
#: 1 to the published three decimals, so a white seen by both eyes stays white.
DUBOIS_LEFT = np.array([[0.456, 0.500, 0.176], [-0.040, -0.038, -0.016], [-0.015, -0.021, -0.005]])
DUBOIS_RIGHT = np.array([[-0.043, -0.088, -0.002], [0.378, 0.734, -0.018], [-0.072, -0.113, 1.226]])


def anaglyph(
    left: npt.NDArray[np.floating], right: npt.NDArray[np.floating]
) -> npt.NDArray[np.float32]:
    """Dubois' least-squares red-cyan anaglyph of two linear RGB images (height, width, 3).
    A display cannot show negative light: negative values are clipped to 0 (values above 1
    stay, as in any linear image, until it is written)."""
    mixed = left.astype(np.float64) @ DUBOIS_LEFT.T + right.astype(np.float64) @ DUBOIS_RIGHT.T
    return np.maximum(mixed, 0.0).astype(np.float32)


def compose_stereo(
    layout: str, left: npt.NDArray[np.float32] | None, right: npt.NDArray[np.float32] | None
) -> npt.NDArray[np.float32]:
    """The image of a stereo ``layout`` from its eyes' images: side_by_side (the left eye on the
    left, for a viewer looking parallel), over_under (the left eye on top), anaglyph, or one
    eye alone (``left``, ``right``)."""
    if layout == "left" and left is not None:
        return left
    if layout == "right" and right is not None:
        return right
    if left is None or right is None:
        raise ValueError(f"the stereo layout {layout!r} needs both eyes' images")
    if layout == "side_by_side":
        return np.ascontiguousarray(np.concatenate([left, right], axis=1))
    if layout == "over_under":
        return np.ascontiguousarray(np.concatenate([left, right], axis=0))
    if layout == "anaglyph":
        return anaglyph(left, right)
    raise ValueError(f"unknown stereo layout {layout!r}")


def _eyes(scene: Scene) -> tuple[str, ...]:
    st = scene.camera.stereo
    return _LAYOUT_EYES[st.layout] if st is not None else ()


def eye_scene(scene: Scene, eye: str) -> Scene:
    """The scene as one eye of its stereo pair sees it (layout ``left`` or ``right``): what the
    converters take, one render per eye."""
    st = scene.camera.stereo
    if st is None:
        raise ValueError(f"{scene.source}: the camera is not a stereo pair")
    if eye not in _SIDE:
        raise ValueError(f"eye must be 'left' or 'right', got {eye!r}")
    camera = dataclasses.replace(scene.camera, stereo=dataclasses.replace(st, layout=eye))
    return dataclasses.replace(scene, camera=camera)


def _set_camera(core: _core.Scene, scene: Scene, eye: str | None = None) -> None:
    """The core's camera: the scene's single camera, or one eye of its stereo pair."""
    c, st = scene.camera, scene.camera.stereo
    if st is None or eye is None:
        core.set_camera(c.eye, c.look_at, c.up, c.fov_y, c.width, c.height)
    else:
        core.set_camera(c.eye, c.look_at, c.up, c.fov_y, c.width, c.height,
                        _SIDE[eye], st.eye_separation, st.convergence)  # fmt: skip


def to_core(scene: Scene) -> _core.Scene:
    """Fill a C++ core scene from the validated model (a stereo pair's camera: its first eye)."""
    core = _core.Scene()
    eyes = _eyes(scene)
    _set_camera(core, scene, eyes[0] if eyes else None)
    _set_render(core, scene)
    index = {}
    for name, m in scene.materials.items():
        index[name] = core.add_material(
            m.color, m.ambient, m.diffuse, m.specular, m.shininess, m.reflectivity, m.emission
        )
    for light in scene.lights:
        if isinstance(light, PointLight):
            core.add_point_light(light.position, light.color)
        elif isinstance(light, DirectionalLight):
            core.add_directional_light(light.direction, light.color)
    flat: list = []
    for i, obj in enumerate(scene.objects):
        m = index[obj.material]
        if isinstance(obj, Sphere):
            core.add_sphere(obj.center, obj.radius, i, m)
        elif isinstance(obj, Plane):
            core.add_plane(obj.point, obj.normal, i, m)
        elif isinstance(obj, Box):
            matrix = to_world(obj)[:3].tolist() if obj.transform is not None else None
            core.add_box(obj.min, obj.max, matrix, i, m)
        elif isinstance(obj, Cylinder):
            core.add_cylinder(obj.radius, cylinder_height(obj), obj.capped,
                              to_world(obj)[:3].tolist(), i, m)  # fmt: skip
        elif isinstance(obj, Torus):
            core.add_torus(obj.major_radius, obj.minor_radius, to_world(obj)[:3].tolist(), i, m)
        elif isinstance(obj, Triangle | Quad | Mesh):
            vertices, faces, normals = triangles(obj)
            if normals is None and max(scene.materials[obj.material].emission) == 0:
                flat.append((vertices, faces, i, m))  # joins the scene's one flat mesh
                continue
            core.add_mesh(
                np.ascontiguousarray(vertices, dtype=np.float64),
                np.ascontiguousarray(faces, dtype=np.int32),
                None if normals is None else np.ascontiguousarray(normals, dtype=np.float64),
                scene.render.acceleration, i, m,
            )  # fmt: skip
    if flat:
        _add_flat_triangles(core, flat, scene.render.acceleration)
    return core


def _add_flat_triangles(core: _core.Scene, parts: list, acceleration: str) -> None:
    """Every flat-shaded, non-emitting triangle object (triangles, quads, flat meshes) in one
    mesh with one hierarchy, each triangle remembering its object and material: a room of six
    quads then costs a ray one hierarchy, not six objects tested one after another. (Emitting
    meshes stay apart: the path tracer samples points on each area light by its own area.)"""
    offset, vertices, faces, objects, materials = 0, [], [], [], []
    for v, f, obj, mat in parts:
        vertices.append(v)
        faces.append(np.asarray(f) + offset)
        objects.append(np.full(len(f), obj, dtype=np.int32))
        materials.append(np.full(len(f), mat, dtype=np.int32))
        offset += len(v)
    core.add_mesh(
        np.ascontiguousarray(np.concatenate(vertices), dtype=np.float64),
        np.ascontiguousarray(np.concatenate(faces), dtype=np.int32),
        None, acceleration, int(objects[0][0]), int(materials[0][0]),
        np.ascontiguousarray(np.concatenate(objects)),
        np.ascontiguousarray(np.concatenate(materials)),
    )  # fmt: skip


ProgressCallback = Callable[[int, int], None]


def _progress_bar() -> tuple[ProgressCallback, Callable[[], None]]:
    from tqdm import tqdm

    bar = tqdm(total=100, unit="%", desc="render", leave=False, file=sys.stderr, delay=0.5)

    def update(done: int, total: int) -> None:
        bar.n = round(100 * done / max(total, 1))
        bar.refresh()

    return update, bar.close


def _check_threads(threads: int | None) -> int:
    if threads is None:
        threads = default_threads()
    if threads < 1:
        raise ValueError(f"threads must be at least 1, got {threads}")
    return threads


def core_integrator(scene: Scene, packets: bool = True) -> _core.Integrator:
    """The core's integrator for the scene's ``render.integrator``; ``packets`` chooses between
    the classic model's two tracers (packets serve scenes of spheres and planes only; the core
    falls back to one ray at a time elsewhere and reports it), and between the path tracer's
    scene queries (the lecture's, or objects culled by their world bounds: the same image)."""
    if scene.render.integrator == "aov":
        return _core.Integrator.aov
    if scene.render.integrator == "path":  # the same image either way (tests/tracer/test_path.py)
        return _core.Integrator.path_culled if packets else _core.Integrator.path
    return _core.Integrator.classic_packets if packets else _core.Integrator.classic


def _render_core(
    scene: Scene,
    core: _core.Scene,
    threads: int,
    progress: bool | ProgressCallback | None,
    packets: bool,
) -> RenderResult:
    """Render a core scene already built from ``scene`` (its hierarchies included): a stereo
    pair eye by eye, the core's camera set to each in turn, then composed."""
    eyes = _eyes(scene)
    if not eyes:
        return _render_camera(scene, core, threads, progress, packets)
    st = scene.camera.stereo
    assert st is not None
    if st.layout == "anaglyph" and scene.render.integrator == "aov":
        raise SceneError(
            scene.source,
            "camera.stereo.layout",
            "expected side_by_side, over_under, left or right with the aov integrator, got "
            "'anaglyph' (it mixes colours; depth, object ids and normals are no colours)",
        )
    check_memory(scene)
    images: dict[str, npt.NDArray[np.float32]] = {}
    rays: dict[str, int] = {}
    seconds, ran = 0.0, ""
    for eye in eyes:
        _set_camera(core, scene, eye)
        result = _render_camera(scene, core, threads, progress, packets)
        images[eye] = result.image
        for key, value in result.rays.items():
            rays[key] = rays.get(key, 0) + value
        seconds += result.seconds
        ran = result.integrator
    image = compose_stereo(st.layout, images.get("left"), images.get("right"))
    return RenderResult(image, rays, seconds, threads, ran)


def _render_camera(
    scene: Scene,
    core: _core.Scene,
    threads: int,
    progress: bool | ProgressCallback | None,
    packets: bool,
) -> RenderResult:
    """Render the core scene through the camera it has now. ``progress``: a bar (True; None:
    on a terminal), none (False), or a callback of (done, total) whose exception cancels the
    render and is raised here (``rtlab view`` drops a refinement pass a move has made stale)."""
    if scene.camera.stereo is None:  # a stereo pair's eyes were counted together
        check_memory(scene)
    if progress is None:
        progress = sys.stderr.isatty()
    callback: ProgressCallback | None
    if callable(progress):
        callback, close = progress, lambda: None
    else:
        callback, close = _progress_bar() if progress else (None, lambda: None)
    start = time.perf_counter()
    try:
        image, rays, ran = _core.render(
            core, threads, callback, core_integrator(scene, packets), packets
        )
    finally:
        close()
    return RenderResult(image, dict(rays), time.perf_counter() - start, threads, ran.name)


def render_with_stats(
    scene: Scene,
    *,
    threads: int | None = None,
    progress: bool | None = None,
    packets: bool = True,
) -> RenderResult:
    """Render and report ray counts and time. ``progress=None`` shows a bar on a terminal.

    ``packets=False`` traces one ray at a time, the lecture's code as written; the default
    traces packets of rays with SIMD instructions. Both give the same image, bit for bit.
    """
    threads = _check_threads(threads)
    check_memory(scene)  # before to_core(), which builds the meshes' hierarchies
    return _render_core(scene, to_core(scene), threads, progress, packets)


def render(
    scene: Scene, *, threads: int | None = None, progress: bool | None = None
) -> npt.NDArray[np.float32]:
    """Render to a float32 linear RGB array of shape (height, width, 3); with the ``aov``
    integrator, (height, width, 5): the channels of AOV_CHANNELS. A stereo pair's width and
    height are one eye's: side_by_side gives (height, 2 width, 3), over_under (2 height, width,
    3), anaglyph, left and right (height, width, 3)."""
    return render_with_stats(scene, threads=threads, progress=progress).image


def aov_channels(image: npt.NDArray[np.float32]) -> dict[str, npt.NDArray[np.float32]]:
    """An aov render as named (height, width) channels, as they go into an EXR file."""
    return {name: np.ascontiguousarray(image[..., k]) for k, name in enumerate(AOV_CHANNELS)}


def pass_seed(seed: int, k: int) -> int:
    """The seed of pass k of a progressive render of a scene seeded ``seed``: a given number of
    passes gives the same image on any machine (render_progressive, rtlab view)."""
    return (seed * 1_000_003 + k) % 2**64


def render_progressive(
    scene: Scene,
    seconds: float,
    *,
    threads: int | None = None,
    progress: bool | None = None,
) -> RenderResult:
    """Render passes of ``scene.render.spp`` samples until ``seconds`` are spent, and average
    them: the longer the budget, the less noise. Pass k uses the seed (seed, k), so a given
    number of passes gives the same image on any machine; at least one pass is made, and no
    pass is started that the time left would not cover at the pace so far."""
    import time

    if scene.render.integrator == "aov":
        raise ValueError("an aov render has nothing to refine: render it once")
    threads = _check_threads(threads)
    # Per value: the float64 sum, a pass's float32 image and the float64 temporary of adding them.
    check_memory(scene, bytes_per_value=8 + 4 + 8)
    start = time.perf_counter()
    core = to_core(scene)  # once: the passes differ only in their seed
    total: npt.NDArray[np.float64] | None = None
    rays: dict[str, int] = {}
    passes = 0
    while True:
        seed = pass_seed(scene.render.seed, passes)
        _set_render(core, scene.with_overrides(seed=seed))
        result = _render_core(scene, core, threads, progress, True)
        total = result.image.astype(np.float64) if total is None else total + result.image
        for key, value in result.rays.items():
            rays[key] = rays.get(key, 0) + value
        passes += 1
        elapsed = time.perf_counter() - start
        if elapsed + elapsed / passes > seconds:
            break
    image = (total / passes).astype(np.float32)
    return RenderResult(image, rays, time.perf_counter() - start, result.threads, result.integrator)
