"""The path tracer against analytic answers: furnaces (where every path's expectation is
known), inverse-square point lights, directional irradiance, mirrors, max_depth as Mitsuba
counts it, and the same image whatever the thread count.

Statistical checks compare a mean over many pixels, whose expectation is the analytic value,
with its standard error from the pixels' own spread: |mean - expected| < 4.5 standard errors
(a false alarm about once in 150,000 runs for a normal mean; far more than a 1% bias at these
sample counts)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import tracer
from tests.helpers import SCENES, material, plane, scene_dict, sphere

Z = 4.5


def path_scene(**parts):
    data = scene_dict(**parts)
    data["render"] = {"integrator": "path", "spp": 16, "max_depth": 10, **parts.get("render", {})}
    return tracer.load_scene(data)


def check_mean(values, expected):
    values = np.asarray(values, dtype=np.float64).ravel()
    mean, error = values.mean(), values.std(ddof=1) / np.sqrt(values.size)
    assert abs(mean - expected) < Z * error + 1e-7, f"mean {mean} +- {error}, expected {expected}"
    return mean, error


def inner_disc(width, radius_px, margin=1.5):
    """Pixels wholly inside a centred disc of the given radius in pixels."""
    c = (np.arange(width) + 0.5) - width / 2
    xx, yy = np.meshgrid(c, c)
    return np.hypot(xx, yy) < radius_px - margin


def test_white_furnace_convex_diffuse_object_reads_albedo_times_environment():
    """A convex diffuse object under a uniform environment L: every direction from its surface
    sees the environment, so it reflects exactly rho L, however many bounces are allowed."""
    rho, L = 0.6, 0.8
    scene = path_scene(
        camera={"eye": [0, 0, 3], "look_at": [0, 0, 0], "width": 48, "height": 48, "fov_y": 60.0},
        render={"background": [L, L, L], "spp": 32},
        materials={"m": material(color=[1, 1, 1], diffuse=rho, ambient=0.0)},
        objects=[sphere([0, 0, 0], 1.0)],
    )
    image = tracer.render(scene, threads=2)
    # The sphere's outline: half-angle asin(r / D) against the half field of view.
    radius_px = 24 * np.tan(np.arcsin(1 / 3)) / np.tan(np.radians(30))
    inside = inner_disc(48, radius_px)
    assert inside.sum() > 400
    check_mean(image[inside], rho * L)
    corners = image[:6, :6]
    assert np.allclose(corners, L, rtol=1e-6)  # seen directly: exactly L


def test_furnace_closed_emitting_enclosure_reads_le_over_one_minus_rho():
    """Inside a closed diffuse enclosure whose inner side emits Le with albedo rho, radiance is
    Le (1 + rho + rho^2 + ...) = Le / (1 - rho) everywhere: it needs every bounce (Russian
    roulette ends the paths without bias) and a watertight mesh wound to face inward."""
    rho, Le = 0.6, 0.5
    ico = trimesh.creation.icosphere(subdivisions=3, radius=2.0)
    scene = path_scene(
        camera={
            "eye": [0.2, 0.1, 0.0],
            "look_at": [0, 0, -1],
            "width": 32,
            "height": 32,
            "fov_y": 90.0,
        },
        render={"max_depth": 1000, "spp": 32},
        materials={"m": material(color=[1, 1, 1], diffuse=rho, ambient=0.0, emission=[Le] * 3)},
        objects=[
            {
                "type": "mesh",
                "vertices": ico.vertices.tolist(),
                "faces": ico.faces[:, ::-1].tolist(),
                "material": "m",
            }
        ],
    )
    image = tracer.render(scene, threads=2)
    check_mean(image[..., 1], Le / (1 - rho))


def test_point_light_falls_off_with_the_square_of_distance():
    """max_depth 2 is direct lighting only, and with one point light there is nothing random:
    the floor below the light at height h reads rho / pi * I / h^2 exactly."""
    for h in (1.0, 2.0, 4.0):
        scene = path_scene(
            camera={"eye": [0, 10, 0], "look_at": [0, 0, 0], "up": [0, 0, -1]},
            render={"max_depth": 2, "spp": 1},  # the pixel centre: the point below the light
            materials={"m": material(color=[1, 1, 1], diffuse=0.5, ambient=0.0)},
            lights=[{"type": "point", "position": [0, h, 0], "color": [3.0, 3.0, 3.0]}],
            objects=[plane([0, 0, 0], [0, 1, 0])],
        )
        got = float(tracer.render(scene, threads=1)[0, 0, 0])
        assert got == pytest.approx(0.5 / np.pi * 3.0 / h**2, rel=1e-6)


def test_directional_light_is_irradiance():
    scene = path_scene(
        camera={"eye": [0, 10, 0], "look_at": [0, 0, 0], "up": [0, 0, -1]},
        render={"max_depth": 2, "spp": 1},
        materials={"m": material(color=[1, 0.5, 0.25], diffuse=0.8, ambient=0.0)},
        lights=[{"type": "directional", "direction": [1.0, -1.0, 0.0], "color": [2.0, 2.0, 2.0]}],
        objects=[plane([0, 0, 0], [0, 1, 0])],
    )
    got = tracer.render(scene, threads=1)[0, 0]
    cos = 1 / np.sqrt(2)
    assert [float(v) for v in got] == pytest.approx(
        [0.8 * c / np.pi * 2.0 * cos for c in (1, 0.5, 0.25)], rel=1e-6
    )


def test_perfect_mirror_reflects_the_environment_exactly():
    scene = path_scene(
        render={"background": [0.3, 0.6, 0.9], "spp": 4},
        materials={"m": material(diffuse=0.0, ambient=0.0, reflectivity=1.0)},
        objects=[sphere([0, 0, 0], 1.0)],
    )
    got = tracer.render(scene, threads=1)[0, 0]
    assert [float(v) for v in got] == pytest.approx([0.3, 0.6, 0.9], rel=1e-6)


def test_max_depth_counts_as_mitsuba_does():
    """1: only emitters seen directly (the lit floor is black, the emitter and the environment
    show); 2: plus direct lighting."""
    base = dict(
        camera={"eye": [0, 3, 3], "look_at": [0, 0, 0], "width": 16, "height": 16, "fov_y": 60.0},
        materials={
            "m": material(diffuse=0.8, ambient=0.0),
            "lamp": material(diffuse=0.0, ambient=0.0, emission=[4.0, 4.0, 4.0]),
        },
        lights=[{"type": "point", "position": [0, 2, 0], "color": [1, 1, 1]}],
        objects=[plane([0, 0, 0], [0, 1, 0]), sphere([0.5, 0.5, 0], 0.3, "lamp")],
    )
    one = tracer.render(path_scene(render={"max_depth": 1}, **base), threads=1)
    two = tracer.render(path_scene(render={"max_depth": 2}, **base), threads=1)
    floor = (slice(12, 16), slice(0, 4))
    assert np.all(one[floor] == 0) and np.all(two[floor] > 0)
    assert one.max() == pytest.approx(4.0, rel=1e-6)  # the lamp, seen directly


def test_same_image_whatever_the_thread_count():
    scene = tracer.load_scene(SCENES / "cornell_box.toml").with_overrides(
        width=40, height=40, spp=4
    )
    images = [tracer.render(scene, threads=t) for t in (1, 2, 5)]
    assert np.array_equal(images[0], images[1]) and np.array_equal(images[0], images[2])
    other = tracer.render(scene.with_overrides(seed=1), threads=2)
    assert not np.array_equal(images[0], other)


def test_progressive_rendering_spends_its_budget_in_whole_passes():
    from tracer.render import render_progressive, render_with_stats

    scene = tracer.load_scene(SCENES / "cornell_box.toml").with_overrides(
        width=24, height=24, spp=2
    )
    once = render_progressive(scene, 1e-6, threads=2)  # the budget is gone after one pass
    assert once.rays["primary"] == 24 * 24 * 2
    first_pass = render_with_stats(scene.with_overrides(seed=0), threads=2).image
    assert np.array_equal(once.image, first_pass)
    longer = render_progressive(scene, 0.5, threads=2)
    assert longer.rays["primary"] > 4 * once.rays["primary"]
    assert longer.seconds < 2.0


def _both_queries(scene):
    """The scene path traced with the lecture's scene queries (packets=False) and with the
    culled ones (packets=True), each checked to be the tracer it claims."""
    plain = tracer.render_with_stats(scene, threads=2, progress=False, packets=False)
    culled = tracer.render_with_stats(scene, threads=2, progress=False, packets=True)
    assert (plain.integrator, culled.integrator) == ("path", "path_culled")
    return plain, culled


def _same_paths(plain, culled):
    """Bit-identical images from the same rays: every primary, secondary and shadow ray."""
    assert np.array_equal(plain.image, culled.image)
    for kind in ("primary", "secondary", "shadow"):
        assert plain.rays[kind] == culled.rays[kind], kind


def test_culled_queries_trace_the_cornell_box_bit_for_bit():
    """The culled queries (tracer/cpp/20_path.h CulledQueries) skip an object only where its
    world bounds prove the ray cannot hit it: the same hits, so the same image, bit for bit."""
    scene = tracer.load_scene(SCENES / "cornell_box.toml").with_overrides(
        width=32, height=32, spp=8
    )
    plain, culled = _both_queries(scene)
    _same_paths(plain, culled)
    assert plain.image.max() > 1  # the light, seen directly: a real render, not a black one
    # Not vacuous: the culled tracer tested fewer primitives (the blocks and the light it
    # skipped), for the box tests of the world bounds it made instead.
    assert culled.rays["primitive_tests"] < 0.8 * plain.rays["primitive_tests"]


def _box(lo, hi, transform=None, material="m"):
    data = {"type": "box", "min": lo, "max": hi, "material": material}
    if transform is not None:
        data["transform"] = transform
    return data


def test_culled_queries_agree_on_every_kind_of_object_and_placement():
    """Spheres and planes (tested as before), boxes under rotations, non-uniform scales and a
    thin slab (their bounds widened by the margin argued at WorldBounds::around(Box)), a box
    seen from far away (the margin's term in the ray origin's size), meshes, an emitting quad,
    cylinders and tori (never culled), and an environment light: the same image either way."""
    grey = material(color=[0.7, 0.6, 0.5], diffuse=0.8, ambient=0.0)
    glossy = material(color=[0.9, 0.9, 0.9], diffuse=0.3, specular=0.5, shininess=20.0,
                      ambient=0.0)  # fmt: skip
    lamp = material(color=[1, 1, 1], diffuse=0.0, ambient=0.0, emission=[6.0, 5.0, 4.0])
    spin = {"scale": [0.4, 0.2, 0.3], "rotate": {"axis": [1, 2, 3], "degrees": 37.0},
            "translate": [0.6, -0.3, 0.2]}  # fmt: skip
    slab = {"scale": [0.8, 1e-3, 0.8], "rotate": {"axis": [1, 0, 1], "degrees": 60.0},
            "translate": [-0.5, 0.4, -0.4]}  # fmt: skip
    objects = [
        plane([0, -1, 0], [0, 1, 0], "grey"),
        sphere([-0.6, -0.5, 0.3], 0.4, "glossy"),
        sphere([0.0, 1.6, 0.0], 0.2, "lamp"),
        _box([-1, -1, -1], [1, 1, 1], spin, "grey"),
        _box([-1, -1, -1], [1, 1, 1], slab, "glossy"),
        _box([0.2, -1.0, -1.2], [0.9, -0.2, -0.6], None, "grey"),
        {"type": "quad", "corner": [-0.3, 1.3, -0.3], "edge1": [0.6, 0, 0],
         "edge2": [0, 0, 0.6], "material": "lamp"},
        {"type": "quad", "corner": [-2, -1, -2], "edge1": [4, 0, 0], "edge2": [0, 3, 0],
         "material": "grey"},
        {"type": "cylinder", "base": [0.9, -1, 0.8], "top": [0.9, -0.2, 0.8], "radius": 0.2,
         "capped": True, "material": "grey"},
        {"type": "torus", "center": [-0.2, -0.8, 1.0], "axis": [0, 1, 0], "major_radius": 0.3,
         "minor_radius": 0.1, "material": "glossy"},
    ]  # fmt: skip
    near = path_scene(
        camera={"eye": [0.3, 0.5, 4.0], "look_at": [0, -0.2, 0], "width": 40, "height": 32,
                "fov_y": 45.0},
        render={"background": [0.2, 0.25, 0.3], "spp": 4, "max_depth": 6},
        materials={"grey": grey, "glossy": glossy, "lamp": lamp},
        objects=objects,
    )  # fmt: skip
    plain, culled = _both_queries(near)
    _same_paths(plain, culled)
    assert culled.rays["primitive_tests"] < plain.rays["primitive_tests"]  # some were culled
    # The same scene from 1e5 away through a narrow field of view: ray origins of size 1e5
    # (the margin's per-reach term) meeting the boxes' edges.
    far = near.with_overrides(eye=[3e4, 5e4, 8e4], fov_y=0.002, spp=2)
    plain, culled = _both_queries(far)
    _same_paths(plain, culled)
    background = np.array([0.2, 0.25, 0.3], dtype=np.float32)  # seen directly: exactly it
    assert np.count_nonzero(np.any(plain.image != background, axis=-1)) > 32 * 40 / 2


def test_culled_queries_agree_where_a_plane_lies_on_a_small_meshs_face():
    """A cube mesh of 12 triangles (its wide tree one node of leaves, searched by
    WideBVH::search_flat() from CulledQueries) whose floor lies in a plane, seen from inside at
    1e6: the plane's hit and the mesh's agree in t to within rounding, so which one is kept
    depends on which boxes the search's slab tests let through. A first version of the flat
    search tested every triangle, no boxes, and kept the mesh where the lecture kept the plane
    (hypothesis found it: tests/tracer/test_core_fuzz.py); the same search as the hierarchy's
    keeps the same hits."""
    big = 1e6
    corners = [[x, y, z] for x in (-big, big) for y in (0.0, 2 * big) for z in (-big, big)]
    faces = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    scene = tracer.load_scene(
        {
            "camera": {"eye": [0.0, big, 0.0], "look_at": [0.0, 0.0, 0.0], "up": [0.0, 0.0, 1.0],
                       "fov_y": 1.0, "width": 16, "height": 12},
            "render": {"integrator": "path", "max_depth": 2, "spp": 4, "seed": 0},
            "materials": {"a": {}, "b": {"color": [0.0, 0.0, 0.0]}},
            "objects": [sphere([0.0, 0.0, 0.0], 1.0, "a"), plane([0, 0, 0], [0, 1, 0], "a"),
                        plane([0, 0, 0], [0, 0, 1], "a"), plane([0, 0, 0], [0, 0, 1], "b"),
                        {"type": "mesh", "vertices": corners, "faces": faces, "material": "b"}],
        }
    )  # fmt: skip
    plain, culled = _both_queries(scene)
    _same_paths(plain, culled)
    assert plain.rays["secondary"] > 0  # some paths go on from the plane (material a)
