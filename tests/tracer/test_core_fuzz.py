"""The core survives what a valid scene can ask of it (issue 8, part 6): random scenes of any mix
of objects, with degenerate but legal values (a radius of 1e-300, coincident planes, a light
inside a sphere, a camera inside a closed mesh, max_depth 1000), render tiny images with every
integrator without a crash and without NaN or inf; and a render too big for the memory left is
refused before it starts.

The scenes are dicts in the scene language, read by tracer.load_scene: a scene the reader
refuses is no concern of the core's and is skipped (hypothesis.assume). The suite runs a short,
derandomised session (the same examples every run); RTLAB_FUZZ_EXAMPLES=5000 runs a long random
one."""

from __future__ import annotations

import dataclasses
import importlib
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import tracer
from tests.helpers import SCENES, scene_dict
from tracer import _core

# The module, not the function tracer.render that the package exports under the same name.
render_module = importlib.import_module("tracer.render")

LONG = "RTLAB_FUZZ_EXAMPLES" in os.environ
FUZZ = settings(
    max_examples=int(os.environ.get("RTLAB_FUZZ_EXAMPLES", "50")),
    deadline=None,  # a render's time depends on the machine; no example is too slow to matter
    derandomize=not LONG,
    database=None,  # nothing written into the work tree
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
)

# Numbers that stress the arithmetic, mixed with ordinary ones. Magnitudes stay where a
# scene's light still fits float32 (a radiance near 1e299 overflows the image: the reader's
# concern, issue 8 part 6's first bullet, not the core's).
TINY = [1e-300, -1e-300, 1e-12, 0.0]
HUGE = [1e6, -1e6, 1e12]
coordinate = st.one_of(st.floats(-4, 4), st.sampled_from([*TINY, *HUGE]))
vec3 = st.lists(coordinate, min_size=3, max_size=3)
# Directions (normals, axes, light directions) with one component of some size: the reader
# today crashes (ZeroDivisionError in its normalisation) on a direction whose squared length
# underflows, such as [1e-300, 0, 0], which its non-zero check lets through; reported, and kept
# out of the core's fuzz, whose subject is the core.
unit_ish = st.lists(
    st.one_of(st.floats(-1, 1, allow_subnormal=False), st.sampled_from([0.0, 1e-300])),
    min_size=3,
    max_size=3,
).filter(lambda v: max(abs(x) for x in v) >= 1e-3)
radius = st.one_of(st.floats(1e-3, 4), st.sampled_from([1e-300, 1e-12, 1e6, 1e12]))
amount = st.one_of(st.floats(0, 1.5), st.sampled_from([0.0, 1.0, 1e-300, 1e3]))
color = st.lists(
    st.one_of(st.floats(0, 1), st.sampled_from([0.0, 1.0, 1e3])), min_size=3, max_size=3
)

transform = st.fixed_dictionaries(
    {},
    optional={
        "scale": st.lists(
            st.sampled_from([1.0, 2.0, 0.5, 1e-6, -1.0, 1e6]), min_size=3, max_size=3
        ),
        "rotate": st.fixed_dictionaries({"axis": unit_ish, "degrees": st.floats(-720, 720)}),
        "translate": vec3,
    },
)


def with_transform(strategy: st.SearchStrategy) -> st.SearchStrategy:
    return st.tuples(strategy, st.one_of(st.none(), transform)).map(
        lambda pair: pair[0] if pair[1] is None else {**pair[0], "transform": pair[1]}
    )


CUBE_VERTICES = [[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)]
CUBE_FACES = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]


def closed_cube(center: list[float], half: float) -> dict:
    """A closed mesh (six quads, outward), for a camera inside a mesh."""
    vertices = [[c + half * v for c, v in zip(center, p, strict=True)] for p in CUBE_VERTICES]
    return {"type": "mesh", "vertices": vertices, "faces": CUBE_FACES}


def objects(materials: list[str]) -> st.SearchStrategy:
    m = st.sampled_from(materials)
    sphere = st.fixed_dictionaries(
        {"type": st.just("sphere"), "center": vec3, "radius": radius, "material": m}
    )
    plane = st.fixed_dictionaries(
        {"type": st.just("plane"), "point": vec3, "normal": unit_ish, "material": m}
    )
    box = with_transform(
        st.tuples(vec3, st.lists(radius, min_size=3, max_size=3), m).map(
            lambda t: {
                "type": "box",
                "min": t[0],
                "max": [a + 2 * b for a, b in zip(t[0], t[1], strict=True)],
                "material": t[2],
            }
        )
    )
    triangle = st.fixed_dictionaries(
        {
            "type": st.just("triangle"),
            "vertices": st.lists(vec3, min_size=3, max_size=3),
            "material": m,
        }
    )
    quad = with_transform(
        st.fixed_dictionaries(
            {"type": st.just("quad"), "corner": vec3, "edge1": vec3, "edge2": vec3, "material": m}
        )
    )
    mesh = with_transform(
        st.tuples(st.lists(vec3, min_size=3, max_size=6), st.booleans(), m).map(
            lambda t: {
                "type": "mesh",
                "vertices": t[0],
                "smooth": t[1],
                "material": t[2],
                "faces": [[0, 1, 2], *([[0, 2, len(t[0]) - 1]] if len(t[0]) > 3 else [])],
            }
        )
    )
    cylinder = with_transform(
        st.fixed_dictionaries(
            {
                "type": st.just("cylinder"),
                "base": vec3,
                "top": vec3,
                "radius": radius,
                "capped": st.booleans(),
                "material": m,
            }
        )
    )
    torus = with_transform(
        st.fixed_dictionaries(
            {
                "type": st.just("torus"),
                "center": vec3,
                "axis": unit_ish,
                "major_radius": radius,
                "minor_radius": radius,
                "material": m,
            }
        )
    )
    return st.one_of(sphere, plane, box, triangle, quad, mesh, cylinder, torus)


material = st.fixed_dictionaries(
    {},
    optional={
        "color": color,
        "ambient": amount,
        "diffuse": amount,
        "specular": amount,
        "shininess": st.sampled_from([1e-300, 0.5, 1.0, 10.0, 1e3, 1e6]),
        "reflectivity": st.one_of(st.floats(0, 1), st.sampled_from([0.0, 1.0, 1e-300])),
        "emission": color,
    },
)
light = st.one_of(
    st.fixed_dictionaries({"type": st.just("point"), "position": vec3}, optional={"color": color}),
    st.fixed_dictionaries(
        {"type": st.just("directional"), "direction": unit_ish}, optional={"color": color}
    ),
)


def energy_conserving(m: dict) -> dict:
    """The material scaled so it returns at most the light it receives: albedo (diffuse times
    the brightest colour) + specular + reflectivity <= 1. A material that returns more (legal in
    the classic model, where light does not bounce diffusely) makes a path tracer's sum diverge
    in a closed room, 1000^k at bounce k: its inf is the right answer to that scene, not a
    fault of the core (reported to the reader's side as a value to refuse for path scenes)."""
    albedo = m.get("diffuse", 0.6) * max(m.get("color", [1.0, 1.0, 1.0]))
    total = albedo + m.get("specular", 0.0) + m.get("reflectivity", 0.0)
    if total <= 1:
        return m
    return {
        **m,
        "diffuse": m.get("diffuse", 0.6) / total,
        "specular": m.get("specular", 0.0) / total,
        "reflectivity": m.get("reflectivity", 0.0) / total,
    }


def axis_length_is_representable(objects: list[dict]) -> bool:
    """The reader today accepts a cylinder whose top differs from its base by 1e-300 and then
    fails (ZeroDivisionError) normalising the axis, whose squared length underflows; reported,
    and kept out of the core's fuzz."""
    for o in objects:
        if o["type"] == "cylinder":
            axis = [t - b for t, b in zip(o["top"], o["base"], strict=True)]
            if not sum(x * x for x in axis) > 0:
                return False
    return True


@st.composite
def scenes(draw: st.DrawFn) -> dict:
    names = ["a", "b"]
    eye = draw(vec3)
    data = scene_dict(
        camera={
            "eye": eye,
            "look_at": draw(vec3),
            "up": draw(st.sampled_from([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1e-300, 1.0, 0.0]])),
            "fov_y": draw(st.sampled_from([1e-6, 1.0, 45.0, 179.999])),
            "width": 4,
            "height": 3,
        },
        render={
            "integrator": draw(st.sampled_from(["classic", "path", "aov"])),
            "max_depth": draw(st.sampled_from([1, 2, 5, 1000])),
            "spp": draw(st.sampled_from([1, 2, 3])),
            "seed": draw(st.integers(0, 2**64 - 1)),
            "min_coefficient": draw(st.sampled_from([0.0, 0.0, 1e-3, 2.0])),
            "background": draw(color),
            "ambient_light": draw(color),
        },
        materials={n: draw(material) for n in names},
        lights=draw(st.lists(light, max_size=3)),
        objects=draw(st.lists(objects(names), min_size=1, max_size=5)),
    )
    if data["render"]["integrator"] == "path":
        data["materials"] = {n: energy_conserving(m) for n, m in data["materials"].items()}
    assume(axis_length_is_representable(data["objects"]))
    # The cases the issue names, each drawn now and then.
    extra = data["objects"]
    if draw(st.booleans()) and data["lights"]:  # a light inside a sphere
        inside = data["lights"][0].get("position", eye)
        extra.append({"type": "sphere", "center": inside, "radius": 0.5, "material": "a"})
    if draw(st.booleans()):  # coincident planes
        p = {"type": "plane", "point": draw(vec3), "normal": draw(unit_ish), "material": "a"}
        extra += [p, {**p, "material": "b"}]
    if draw(st.booleans()):  # the camera inside a closed mesh
        extra.append({**closed_cube(eye, draw(radius)), "material": "b"})
    return data


def load_or_skip(data: dict) -> tracer.Scene:
    try:
        return tracer.load_scene(data)
    except tracer.SceneError:
        assume(False)  # refused by the reader: not the core's concern
        raise  # unreachable: assume(False) raises


def assert_image_is_finite(scene: tracer.Scene, image: np.ndarray) -> None:
    assert not np.isnan(image).any(), "NaN in the image"
    if scene.render.integrator == "aov":
        depth, object_id = image[..., 0], image[..., 1]
        # depth is infinite exactly where the primary ray missed (object_id -1), by design
        assert np.array_equal(np.isinf(depth), object_id == -1), "inf depth on a hit"
        assert np.isfinite(image[..., 1:]).all()
    else:
        assert np.isfinite(image).all(), "inf in the image"
        assert (image >= 0).all(), "negative light"


@FUZZ
@given(scenes())
def test_random_valid_scenes_render_finite_images(data):
    scene = load_or_skip(data)
    result = tracer.render_with_stats(scene, threads=1, progress=False)
    assert result.image.shape == (3, 4, 5 if scene.render.integrator == "aov" else 3)
    assert_image_is_finite(scene, result.image)
    if scene.render.integrator == "classic":  # the packet tracer agrees wherever it runs
        one_ray = tracer.render_with_stats(scene, threads=1, progress=False, packets=False)
        assert np.array_equal(one_ray.image, result.image)
        for kind in ("primary", "secondary", "shadow"):
            assert one_ray.rays[kind] == result.rays[kind], kind
        meshes = (tracer.scene.Mesh, tracer.scene.Triangle, tracer.scene.Quad)  # core meshes
        if not any(isinstance(o, meshes) for o in scene.objects):
            # Meshes are searched by the wide hierarchy with packets=True (21_wide_bvh.h), which
            # counts its own box tests; every other test is the same.
            assert one_ray.rays == result.rays
    if scene.render.integrator == "path":  # the culled scene queries trace the same paths
        plain = tracer.render_with_stats(scene, threads=1, progress=False, packets=False)
        assert np.array_equal(plain.image, result.image)
        for kind in ("primary", "secondary", "shadow"):  # box and primitive tests differ
            assert plain.rays[kind] == result.rays[kind], kind


def test_the_named_degenerate_cases_render():
    """The cases of the issue, each once for certain (the fuzz above draws them at random)."""
    # Returns at most what it receives (0.5 + 0.2 + 0.3): over 1000 levels a material that gains
    # energy could overflow float32, and the reader refuses it (tracer/scene/brightness.py).
    lit = {"ambient": 0.1, "diffuse": 0.5, "specular": 0.2, "reflectivity": 0.3}
    glow = {**lit, "emission": [1.0, 1.0, 1.0]}
    for integrator in ("classic", "path", "aov"):
        data = scene_dict(
            camera={"eye": [0.0, 0.0, 0.0], "look_at": [0.0, 0.0, -1.0], "width": 4, "height": 3},
            render={"integrator": integrator, "max_depth": 1000, "spp": 2},
            materials={"a": lit, "b": glow},
            lights=[{"type": "point", "position": [0.0, 2.0, 0.0]}],
            objects=[
                {"type": "sphere", "center": [0.0, 0.0, -3.0], "radius": 1e-300, "material": "b"},
                {"type": "sphere", "center": [0.0, 2.0, 0.0], "radius": 0.5, "material": "a"},
                {"type": "plane", "point": [0.0, -1.0, 0.0], "normal": [0, 1, 0], "material": "a"},
                {"type": "plane", "point": [0.0, -1.0, 0.0], "normal": [0, 1, 0], "material": "b"},
                {**closed_cube([0.0, 0.0, 0.0], 5.0), "material": "a"},
            ],
        )
        scene = tracer.load_scene(data)
        assert_image_is_finite(scene, tracer.render(scene, threads=1, progress=False))


def test_what_the_fuzz_found():
    """Each was a NaN or undefined behaviour in the core before it was fixed: an emitting
    triangle of area 7e-153, whose light density squared overflowed in the power heuristic
    (inf / inf); shininess 1e300, whose exponent broke power()'s rounding trick (a left shift
    of a negative number, which UBSan reports under make sanitize); and an aov ray grazing a
    plane at a distance beyond float32's range, whose depth read as inf, a miss, on a hit; a
    sphere and a cylinder of radius 1e-300 at 3.7e-207 from the eye, smaller than the spacing of
    doubles there, whose hit point fell on the centre (normal 0 / 0); and a point light on the
    surface it lights, whose direction 0 / 0 made the one-ray tracer NaN where the packet
    tracer, testing N.L > 0, had skipped it."""
    sliver = [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.4882790216348415e-152, 0.0]]
    data = scene_dict(
        camera={"eye": [2.0, 0.5, 0.5], "look_at": [0.0, 0.0, 0.5], "width": 4, "height": 3},
        render={"integrator": "path", "max_depth": 3, "spp": 4},
        materials={"a": {"emission": [0.0, 0.0, 1.0]}, "b": {"diffuse": 0.8}},
        objects=[
            {"type": "triangle", "vertices": sliver, "material": "a"},
            {"type": "plane", "point": [0.0, -1.0, 0.0], "normal": [0, 1, 0], "material": "b"},
        ],
    )
    scene = tracer.load_scene(data)
    assert_image_is_finite(scene, tracer.render(scene, threads=1, progress=False))
    # power() itself takes any exponent (the reader stops shininess at 1e12, so the core is
    # asked directly): x^n for n = 1e300 is 0 below 1 and 1 at 1, never garbage.
    assert [_core.power(x, 1e300) for x in (0.5, 0.999999, 1.0)] == [0.0, 0.0, 1.0]
    shiny = {"ambient": 0.1, "diffuse": 0.5, "specular": 1.0, "shininess": 1e12}
    data = scene_dict(
        camera={"width": 8, "height": 6},
        materials={"m": shiny},
        lights=[{"type": "point", "position": [0.0, 0.0, 5.0]}],
        objects=[{"type": "sphere", "center": [0.0, 0.0, 0.0], "radius": 1.0, "material": "m"}],
    )
    scene = tracer.load_scene(data)
    image = tracer.render(scene, threads=1, progress=False)
    assert_image_is_finite(scene, image)
    assert image.max() > 0.1  # the ambient and Lambert terms still show
    tilted = [0.0, 1.0, 1.467376386462038e-247]
    data = scene_dict(
        camera={
            "eye": [1.0, 0.0, 0.0],
            "look_at": [0.0, 0.0, 0.0],
            "fov_y": 179.999,
            "width": 4,
            "height": 3,
        },
        render={"integrator": "aov"},
        objects=[{"type": "plane", "point": [0.0, 1.0, 0.0], "normal": tilted, "material": "m"}],
    )
    scene = tracer.load_scene(data)
    image = tracer.render(scene, threads=1, progress=False)
    assert_image_is_finite(scene, image)
    hits = image[..., 1] >= 0
    assert image[..., 0][hits].max() == np.finfo(np.float32).max  # the far hit, saturated
    z = 3.6785700024424245e-207
    for tiny in (
        {"type": "sphere", "center": [0.0, 0.0, z], "radius": 1e-300, "material": "m"},
        {
            "type": "cylinder",
            "base": [0.0, -1.0, z],
            "top": [0.0, 1.0, z],
            "radius": 1e-300,
            "material": "m",
        },
    ):
        for integrator in ("aov", "classic"):
            data = scene_dict(
                camera={
                    "eye": [0.0, 0.0, 0.0],
                    "look_at": [0.0, 0.0, 1.0],
                    "fov_y": 1e-6,
                    "width": 4,
                    "height": 3,
                },
                render={"integrator": integrator},
                materials={"m": shiny},
                lights=[{"type": "directional", "direction": [0.0, 0.0, 1.0]}],
                objects=[tiny],
            )
            scene = tracer.load_scene(data)
            image = tracer.render(scene, threads=1, progress=False)
            assert_image_is_finite(scene, image)
            if integrator == "aov":
                assert (image[..., 1] == 0).all()  # every ray hits it
    on_the_light = [
        {"type": "plane", "point": [0.0, 1e-300, 0.0], "normal": [0, 1, 0], "material": "m"},
        {
            "type": "box",
            "min": [0.0, 0.0, 0.0],
            "max": [2.0, 2.0, 2e-300],
            "material": "m",
            "transform": {"scale": [1.0, 1.0, -1.0]},
        },
    ]
    for obj in on_the_light:
        for integrator in ("classic", "path"):
            data = scene_dict(
                camera={
                    "eye": [0.0, 0.0, 0.0],
                    "look_at": [0.0, 0.0, -1.0],
                    "fov_y": 1e-6,
                    "width": 4,
                    "height": 3,
                },
                render={"integrator": integrator},
                materials={"m": {"ambient": 0.1, "diffuse": 0.6}},
                lights=[{"type": "point", "position": [0.0, 0.0, 0.0]}],
                objects=[obj],
            )
            scene = tracer.load_scene(data)
            one_ray = tracer.render_with_stats(scene, threads=1, progress=False, packets=False)
            assert_image_is_finite(scene, one_ray.image)
            packets = tracer.render_with_stats(scene, threads=1, progress=False)
            assert np.array_equal(one_ray.image, packets.image)


# ------------------------------------------------------------------ memory


def too_big(width: int = 200_000, height: int = 200_000) -> tracer.Scene:
    """Ex 25 at a size the reader refuses (its sides stop at 32768) but a program building the
    model directly can ask for: 200000 x 200000 pixels, 480 GB of float32."""
    scene = tracer.load_scene(SCENES / "ex25.toml")
    return dataclasses.replace(
        scene, camera=dataclasses.replace(scene.camera, width=width, height=height)
    )


needs_meminfo = pytest.mark.skipif(
    render_module.memory_available() is None, reason="no /proc/meminfo or cgroup to read"
)


@needs_meminfo
def test_a_render_too_big_for_memory_is_refused_before_it_starts():
    scene = too_big()
    needed = 200_000 * 200_000 * 3 * 4
    available = render_module.memory_available()
    assert available is not None and available[0] < needed  # so the refusal is due
    with pytest.raises(tracer.ImageTooLargeError) as caught:
        tracer.render(scene, threads=1, progress=False)
    message = str(caught.value)
    assert f"needs {needed} bytes" in message and "bytes" in message.split("and", 1)[1]
    assert "200000x200000" in message
    assert isinstance(caught.value, MemoryError)
    assert not isinstance(caught.value, tracer.SceneError)
    with pytest.raises(tracer.ImageTooLargeError):  # a timed render keeps more copies
        render_module.render_progressive(scene, 1.0, threads=1, progress=False)


@needs_meminfo
def test_a_render_that_fits_is_not_refused():
    scene = too_big(64, 48)
    render_module.check_memory(scene, bytes_per_value=20)
    assert tracer.render(scene, threads=1, progress=False).shape == (48, 64, 3)


def test_memory_available_reads_meminfo():
    found = render_module.memory_available()
    if os.path.exists("/proc/meminfo"):
        assert found is not None
        with open("/proc/meminfo") as f:
            text = f.read()
        total = int(next(x for x in text.splitlines() if x.startswith("MemTotal:")).split()[1])
        assert 0 < found[0] <= total * 1024


def test_the_cli_reports_a_refused_render_in_one_line(tmp_path, monkeypatch, capsys):
    """The CLI's scenes pass the reader, whose sides stop at 32768, so a real machine fits most
    of them; here the machine is made small instead: memory_available() reports 1000 bytes, and
    a 64 x 48 render (36,864 bytes) must be refused with one line and a non-zero status."""
    from tracer.cli import main

    monkeypatch.setattr(render_module, "memory_available", lambda: (1000, "a test's limit"))
    out = tmp_path / "out.png"
    scene = str(SCENES / "ex25.toml")
    status = main(["render", scene, "-o", str(out), "--width", "64", "--height", "48", "--quiet"])
    captured = capsys.readouterr()
    assert status != 0
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1, captured.err
    assert lines[0].startswith("rtlab: error: ")
    assert "needs 36864 bytes" in lines[0] and "1000 bytes" in lines[0]
    assert not out.exists()


@needs_meminfo
def test_image_sizes_do_not_overflow_the_check():
    """Python integers: 2^31 x 2^31 pixels is computed exactly, not wrapped to a small size."""
    scene = too_big(2**31, 2**31)
    needed = 2**62 * 12
    assert needed > 2**64  # past any 64-bit size_t
    with pytest.raises(tracer.ImageTooLargeError, match=f"needs {needed} bytes"):
        render_module.check_memory(scene)
