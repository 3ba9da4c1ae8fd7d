"""Boxes, triangles, meshes, cylinders, tori, transforms and the bounding volume hierarchy,
checked against geometry computed independently here (numpy, exact constructions)."""

from __future__ import annotations

import math
import random

import numpy as np
import pytest
import trimesh

import tracer
from tests.helpers import SCENES, material, scene_dict, sphere
from tracer.cli import main
from tracer.render import to_core


def core_of(objects, **render):
    data = scene_dict(materials={"m": material(ambient=1.0)}, objects=objects, render=render)
    return to_core(tracer.load_scene(data))


def hit(core, o, d):
    return core.closest_hit(list(map(float, o)), list(map(float, d)))


def mesh_obj(m: trimesh.Trimesh, **extra):
    return {"type": "mesh", "vertices": m.vertices.tolist(), "faces": m.faces.tolist(),
            "material": "m", **extra}  # fmt: skip


# --------------------------------------------------------------------------- triangles


def test_triangle_front_is_counter_clockwise_and_t_is_exact():
    core = core_of([{"type": "triangle", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
                     "material": "m"}])  # fmt: skip
    h = hit(core, (0.25, 0.25, 3), (0, 0, -1))
    assert h["t"] == 3.0 and h["normal"] == pytest.approx((0, 0, 1))
    assert hit(core, (0.75, 0.75, 3), (0, 0, -1)) is None  # outside the hypotenuse


def test_closed_mesh_is_watertight_at_its_vertices_and_edges():
    """Rays through every vertex and every edge midpoint of a closed icosphere, which contains
    its centre: from the centre outward, and from outside through the point to the centre. Each
    must hit (Moeller-Trumbore lets some of these through the cracks)."""
    ico = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
    ico.vertices += [0.01, -0.02, 0.03]  # off the axes, so no coordinate is trivially exact
    core = core_of([mesh_obj(ico)])
    centre = np.array([0.01, -0.02, 0.03])
    targets = [np.asarray(v) for v in ico.vertices]
    targets += [(ico.vertices[a] + ico.vertices[b]) / 2 for a, b in ico.edges_unique]
    for target in targets:
        assert hit(core, centre, target - centre) is not None
        outside = centre + 3 * (target - centre)
        assert hit(core, outside, centre - outside) is not None


def test_camera_inside_a_closed_mesh_sees_no_background():
    ico = trimesh.creation.icosphere(subdivisions=3, radius=2.0)
    data = scene_dict(
        camera={
            "eye": [0.1, 0.2, 0.0],
            "look_at": [0, 0, -1],
            "width": 64,
            "height": 48,
            "fov_y": 100.0,
        },
        render={"background": [1.0, 0.0, 0.0]},
        materials={"m": material(color=[0, 1, 0], ambient=1.0)},
        objects=[mesh_obj(ico)],
    )
    image = tracer.render(tracer.load_scene(data), threads=2)
    assert np.all(image[..., 0] == 0) and np.all(image[..., 1] == 1)


# --------------------------------------------------------------------------- acceleration


@pytest.mark.parametrize("acceleration", ["bounding_box", "none"])
def test_hierarchy_changes_the_counts_not_the_image(acceleration):
    bunny = trimesh.creation.icosphere(subdivisions=4)  # 5120 triangles
    base = scene_dict(
        camera={"eye": [0, 0.5, 4], "look_at": [0, 0, 0], "width": 48, "height": 36},
        materials={"m": material(ambient=0.1, diffuse=0.8, reflectivity=0.3)},
        lights=[{"type": "point", "position": [2, 3, 4]}],
        objects=[mesh_obj(bunny), sphere([1.5, 0, 0], 0.4)],
    )
    fast = tracer.render_with_stats(tracer.load_scene(base), threads=2)
    base["render"]["acceleration"] = acceleration
    slow = tracer.render_with_stats(tracer.load_scene(base), threads=2)
    assert np.array_equal(fast.image, slow.image)
    assert fast.rays["primitive_tests"] * 20 < slow.rays["primitive_tests"]
    assert slow.rays["box_tests"] <= fast.rays["box_tests"]


# --------------------------------------------------------------------------- boxes


def test_box_faces_and_normals_with_a_transform():
    """A unit box rotated 90 degrees about z and moved: the ray along -x meets the face that was
    the box's -y face; t and the normal follow from the construction."""
    box = {"type": "box", "min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5], "material": "m",
           "transform": {"scale": [2, 1, 1], "rotate": {"axis": [0, 0, 1], "degrees": 90},
                         "translate": [0, 0, -3]}}  # fmt: skip
    core = core_of([box])
    # After scale: x in [-1, 1]; after the rotation, that extent lies along y; x in [-0.5, 0.5].
    h = hit(core, (5, 0, -3), (-1, 0, 0))
    assert h["t"] == pytest.approx(4.5, rel=1e-12)
    assert h["normal"] == pytest.approx((1, 0, 0), abs=1e-12)
    h = hit(core, (0, 5, -3), (0, -1, 0))
    assert h["t"] == pytest.approx(4.0, rel=1e-12)
    assert h["normal"] == pytest.approx((0, 1, 0), abs=1e-12)
    h = hit(core, (0, 0, -3), (0, 0, 1))  # from inside: the far face
    assert h["t"] == pytest.approx(0.5, rel=1e-12)


# --------------------------------------------------------------------------- cylinders


def test_cylinder_side_and_caps():
    cyl = {"type": "cylinder", "base": [0, 0, 0], "top": [0, 2, 0], "radius": 0.5, "material": "m"}
    core = core_of([cyl])
    h = hit(core, (3, 1, 0), (-1, 0, 0))
    assert h["t"] == pytest.approx(2.5, rel=1e-12) and h["normal"] == pytest.approx(
        (1, 0, 0), abs=1e-12
    )
    h = hit(core, (0.1, 5, 0.2), (0, -1, 0))
    assert h["t"] == pytest.approx(3.0, rel=1e-12) and h["normal"] == pytest.approx(
        (0, 1, 0), abs=1e-12
    )
    core = core_of([dict(cyl, capped=False)])
    h = hit(core, (0.1, 5, 0.2), (0, -1, 0))
    assert h is None  # an open tube: straight down its axis and out


# --------------------------------------------------------------------------- tori


def torus_points(R, r, rng, n):
    """Points on the outer half of a torus around z, with their outward normals."""
    for _ in range(n):
        phi, theta = rng.uniform(0, 2 * math.pi), rng.uniform(-math.pi / 2, math.pi / 2)
        ring = np.array([R * math.cos(phi), R * math.sin(phi), 0.0])
        normal = np.array(
            [math.cos(theta) * math.cos(phi), math.cos(theta) * math.sin(phi), math.sin(theta)]
        )
        yield ring + r * normal, normal


@pytest.mark.parametrize(("R", "r"), [(1.0, 0.3), (1.0, 1e-3), (1e3, 1.0), (1e-3, 1e-6)])
def test_torus_hits_land_on_the_surface_even_thin_and_grazing(R, r):
    """Rays that end at a known surface point q, coming from outside at angles down to grazing
    (1 degree from the tangent plane): t must be the distance to q."""
    core = core_of([{"type": "torus", "center": [0, 0, 0], "axis": [0, 0, 1], "major_radius": R,
                     "minor_radius": r, "material": "m"}])  # fmt: skip
    rng = random.Random(4)
    for q, n in torus_points(R, r, rng, 300):
        tangent = np.cross(n, [0.3, 0.4, 0.5])
        tangent /= np.linalg.norm(tangent)
        elevation = math.radians(rng.uniform(1, 90))
        d = -(math.sin(elevation) * n + math.cos(elevation) * tangent)
        s = 0.2 * r  # start near q: on the outer half the way in is clear
        h = hit(core, q - s * d, d)
        assert h is not None
        assert h["t"] == pytest.approx(s, rel=1e-6, abs=1e-9 * R)


def test_torus_hole_is_empty():
    core = core_of([{"type": "torus", "center": [0, 0, 0], "axis": [0, 0, 1], "major_radius": 1,
                     "minor_radius": 0.3, "material": "m"}])  # fmt: skip
    assert hit(core, (0, 0, 5), (0, 0, -1)) is None
    h = hit(core, (1, 0, 5), (0, 0, -1))
    assert h["t"] == pytest.approx(4.7, rel=1e-12)


# --------------------------------------------------------------------------- self-intersection


@pytest.mark.parametrize("smooth", [False, True])
def test_no_shadow_acne_on_a_mesh_far_from_the_origin(smooth):
    c = np.array([1.0e4, -2.0e4, 3.0e4])
    ico = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
    ico.vertices += c
    light_dir = np.array([-0.3, -0.5, -1.0])
    data = scene_dict(
        camera={
            "eye": (c + np.array([0.0, 1.0, 4.0])).tolist(),
            "look_at": c.tolist(),
            "width": 40,
            "height": 40,
            "fov_y": 35.0,
        },
        materials={"m": material(ambient=0.1, diffuse=0.8)},
        lights=[{"type": "directional", "direction": light_dir.tolist()}],
        objects=[mesh_obj(ico, smooth=smooth)],
    )
    scene = tracer.load_scene(data)
    image = tracer.render(scene, threads=2)[..., 0]
    core = to_core(scene)
    L = -light_dir / np.linalg.norm(light_dir)
    checked = 0
    for j in range(40):
        for i in range(40):
            o, d = core.primary_ray(i + 0.5, j + 0.5)
            h = core.closest_hit(o, d)
            if h is None:
                continue
            ng = np.array(h["normal"]) if not smooth else None
            if ng is not None and np.dot(ng, L) <= 1e-6:
                continue  # unlit by its own orientation; acne shows on lit faces
            nl = max(float(np.dot(h["normal"], L)), 0.0)
            if smooth and nl < 0.05:
                continue  # at the terminator a smooth normal may face a light its face does not
            assert image[j, i] == pytest.approx(0.1 + 0.8 * nl, rel=1e-5), (i, j)
            checked += 1
    assert checked > 300


# --------------------------------------------------------------------------- aov


def test_aov_channels_from_hand_computed_geometry(tmp_path):
    data = scene_dict(
        camera={"eye": [0, 0, 5], "look_at": [0, 0, 0], "width": 3, "height": 3, "fov_y": 60.0},
        render={"integrator": "aov"},
        materials={"m": material()},
        objects=[
            {"type": "plane", "point": [0, 0, -5], "normal": [0, 0, 1], "material": "m"},
            sphere([0, 0, 0], 1.0),
        ],
    )
    scene = tracer.load_scene(data)
    ch = tracer.aov_channels(tracer.render(scene, threads=1))
    assert ch["depth"][1, 1] == pytest.approx(4.0, rel=1e-7)
    assert ch["object_id"][1, 1] == 1 and ch["object_id"][0, 0] == 0
    assert (ch["N.X"][1, 1], ch["N.Y"][1, 1], ch["N.Z"][1, 1]) == pytest.approx((0, 0, 1), abs=1e-7)
    # Corner pixel: the plane z = -5, ten units ahead along the axis, at the ray's slant.
    _, d = to_core(scene).primary_ray(0.5, 0.5)
    assert ch["depth"][0, 0] == pytest.approx(10.0 / -d[2], rel=1e-6)
    out = tmp_path / "a.exr"
    assert main(["render", str(_write(tmp_path, data)), "-o", str(out), "--quiet"]) == 0
    back = tracer.load_exr_channels(out)
    assert sorted(back) == sorted(["depth", "object_id", "N.X", "N.Y", "N.Z"])
    assert back["depth"][1, 1] == pytest.approx(4.0, rel=1e-7)


def test_aov_miss_is_infinite_depth_and_id_minus_one():
    data = scene_dict(render={"integrator": "aov"}, objects=[sphere([0, 5, 0], 1.0)])
    ch = tracer.aov_channels(tracer.render(tracer.load_scene(data)))
    assert math.isinf(ch["depth"][0, 0]) and ch["object_id"][0, 0] == -1


def _write(tmp_path, data):
    """The scene dict as a TOML file (tables and arrays of tables, by hand)."""
    lines = []

    def value(v):
        if isinstance(v, str):
            return f'"{v}"'
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        return repr(float(v)) if isinstance(v, float) else str(v)

    for table in ("camera", "render"):
        lines.append(f"[{table}]")
        lines += [f"{k} = {value(v)}" for k, v in data[table].items()]
    for name, m in data["materials"].items():
        lines.append(f"[materials.{name}]")
        lines += [f"{k} = {value(v)}" for k, v in m.items()]
    for obj in data["objects"]:
        lines.append("[[objects]]")
        lines += [f"{k} = {value(v)}" for k, v in obj.items()]
    path = tmp_path / "scene.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_hierarchy_keeps_leaves_small_on_the_bunny():
    """A binned SAH hierarchy over the bunny's 99,785 triangles: a primary ray tests a handful
    of triangles, not hundreds (an empty bin once poisoned every split cost, leaving leaves of
    up to 70 triangles; this bound would have caught it)."""
    scene = tracer.load_scene(SCENES / "bunny.toml").with_overrides(
        width=96, height=64, integrator="aov"
    )
    rays = tracer.render_with_stats(scene, threads=2).rays
    assert rays["primitive_tests"] / rays["primary"] < 10
    assert rays["box_tests"] / rays["primary"] < 30
