"""The packet tracer (12_packet.h, the default) against the one-ray tracer (10_classic.h, the
lecture's code as written): the same image bit for bit, and the same ray counts. Both do the
same IEEE-754 operations in the same order and the build forbids fused multiply-add, so any
difference at all is a bug in the packet code.

Packets serve scenes of spheres and planes only (12_packet.h says why); a scene with any other
object is traced one ray at a time even when packets are asked for. Every render reports which
tracer ran (RenderResult.integrator), so each comparison below first checks that it compares
the two tracers and not the one-ray code with itself."""

from __future__ import annotations

import math

import numpy as np
import pytest

import tracer
from tests.helpers import (
    classic_scenes,
    left_eye,
    material,
    pixel_direction,
    plane,
    scene_dict,
    sphere,
)
from tracer import _core
from tracer.render import to_core

CLASSIC = classic_scenes()


def packets_serve(path) -> bool:
    return all(type(o).__name__ in ("Sphere", "Plane") for o in tracer.load_scene(path).objects)


PACKET_SCENES = [p for p in CLASSIC if packets_serve(p)]
OTHER_SCENES = [p for p in CLASSIC if not packets_serve(p)]


def packets_agree(scene):
    """Render the scene with both tracers; require that the two ran, and the same image and ray
    counts. Returns the one-ray tracer's result."""
    a = tracer.render_with_stats(scene, threads=2, packets=False)
    b = tracer.render_with_stats(scene, threads=2, packets=True)
    assert (a.integrator, b.integrator) == ("classic", "classic_packets")
    assert np.array_equal(a.image, b.image), f"{int((a.image != b.image).sum())} values differ"
    assert a.rays == b.rays
    return a


def test_the_canonical_scenes_exercise_both_tracers():
    """So the parametrized tests below are neither empty nor one-sided."""
    assert len(PACKET_SCENES) >= 10
    assert {"ex25", "mirrors", "shadows", "case_internal"} <= {p.stem for p in PACKET_SCENES}
    assert {"boxes_triangles", "bunny", "torus_cylinder"} <= {p.stem for p in OTHER_SCENES}


@pytest.mark.parametrize("path", PACKET_SCENES, ids=[p.stem for p in PACKET_SCENES])
@pytest.mark.parametrize("spp", [1, 3])
def test_packets_equal_single_rays(path, spp):
    scene = tracer.load_scene(path).with_overrides(width=97, height=61, spp=spp, seed=3)
    packets_agree(scene)


def test_power_of_a_packet_is_each_lanes_one_ray_power():
    """power() takes a whole shininess (1 to 1024) by squaring and any other by exp(n ln x); a
    packet whose lanes mix the two (a packet straddling two materials) must give each lane the
    one-ray code's bits. The image is float, where one double ulp rarely shows, so this compares
    power() itself: a packet's lanes at once (8 with AVX-512, 4 with AVX2, 2 with SSE2) against
    one-ray calls, bit for bit; each row of 8 exponents below in packets of that many."""
    import random

    rng = random.Random(5)
    width = _core.rays_per_packet
    kinds = ([60.0, 60.5, 1.0, 0.5, 1024.0, 1025.0, 10.0, 3.25], [60.0] * 8, [60.5] * 8,
             [2.0, 3.0, 5.0, 7.0, 11.0, 13.0, 17.0, 1000.0], [1e300, 1.0] * 4)  # fmt: skip
    for _ in range(200):
        for row in kinds:
            for start in range(0, len(row), width):
                n = row[start : start + width]
                x = [rng.choice([rng.random(), 1 - rng.random() * 1e-6, 1.0]) for _ in n]
                lanes = _core.power_lanes(x, n)
                one = [_core.power(xi, ni) for xi, ni in zip(x, n, strict=True)]
                assert [v.hex() for v in lanes] == [v.hex() for v in one], (x, n)


def test_power_of_a_shared_whole_exponent_is_each_lanes_one_ray_power():
    """Where a packet's rays met one material whose shininess is whole, the packet tracer takes
    x^n by power_whole(), squaring by the bits of a plain integer, in place of power(); each
    lane must get the one-ray power()'s bits (the float image rarely shows one double ulp, so
    this compares the powers themselves), for every whole exponent and bases from 1 down to
    where x^n is flushed to 0 (below 2^-1022). The lanes without a highlight, whose bases may
    be 0 or negative, are computed too but not taken: only that they are finite is asked."""
    import random

    rng = random.Random(12)
    width = _core.rays_per_packet
    flushed = between = 0
    for n in range(1, 1025):
        for _ in range(2):
            x = [rng.choice([rng.random(), 1 - rng.random() * 1e-6, 1.0, 0.5**rng.uniform(0, 3)])
                 for _ in range(width)]  # fmt: skip
            lanes = _core.power_whole_lanes(x, n)
            one = [_core.power(xi, float(n)) for xi in x]
            assert [v.hex() for v in lanes] == [v.hex() for v in one], (x, n)
            flushed += sum(v == 0.0 for v in one)
            between += sum(0.0 < v < 1.0 for v in one)
    assert flushed > 100 and between > 1000  # both ends were reached
    assert all(math.isfinite(v) for v in _core.power_whole_lanes([0.0, -0.5] * (width // 2), 61))
    with pytest.raises(ValueError, match="1 to 1024"):
        _core.power_whole_lanes([0.5] * width, 1025)


def test_leaving_origins_are_each_lanes_offset_ray_origin():
    """The packet tracer computes the origin offset_ray_origin() gives a ray leaving on the
    normal's side once per point and takes it for every such ray, running offset_ray_origin()
    again only in a packet where a lane leaves on the other side (12_packet.h
    leaving_origin()). No canonical scene has a lane that leaves on the other side (a shadow ray
    goes only where N.L > 0, a mirror ray where d.N < 0), and a lane that did would move its
    origin by an ulp, which the float image would not show; so this compares the origins
    themselves: packets of lanes on both sides, on the plane (toward.N = 0) and at points of
    every size, against one-ray calls, bit for bit. (With the other side's lanes given the
    normal's side's origin, or every lane the other side's, this test failed.)"""
    import random

    rng = random.Random(8)
    sides = {"front": 0, "back": 0, "plane": 0}
    width = _core.rays_per_packet  # 2,400 lanes in all, in packets of the build's width
    for _ in range(2400 // width):
        p, err, n, toward = [], [], [], []
        for _ in range(width):
            scale = 10.0 ** rng.uniform(-3, 3)
            pk = [rng.uniform(-1, 1) * scale for _ in range(3)]
            nk = [rng.gauss(0, 1) for _ in range(3)]
            norm = sum(c * c for c in nk) ** 0.5
            nk = [c / norm for c in nk]
            tk = [rng.gauss(0, 1) for _ in range(3)]
            if rng.random() < 0.2:  # along the plane: toward.N = 0 exactly (N along an axis)
                nk, tk = [0.0, 0.0, 1.0], [tk[0], tk[1], 0.0]
            side = sum(a * b for a, b in zip(tk, nk, strict=True))
            sides["plane" if side == 0 else "back" if side < 0 else "front"] += 1
            p.append(pk), n.append(nk), toward.append(tk)
            err.append([abs(c) * 1e-15 for c in pk])
        lanes = _core.leaving_origins(p, err, n, toward)
        one = [_core.offset_ray_origin(*args) for args in zip(p, err, n, toward, strict=True)]
        assert [[c.hex() for c in o] for o in lanes] == [[c.hex() for c in o] for o in one]
    assert min(sides.values()) > 100, sides


def test_leaving_origins_of_lanes_on_an_axis_plane_are_offset_ray_origin():
    """Where a packet's rays all met one plane whose normal is an axis's unit vector, the
    packet tracer takes the normal's coordinate along that axis for dot products with it and
    offsets the origin along that axis alone (12_packet.h dot_unit(), away_origin()); the
    binding does so for lanes that share such a normal. Bit for bit against one-ray calls: each
    axis, zeros of either sign in the normal and in the points, error bounds of every size and
    zero, and lanes leaving on both sides and along the plane. (With the offset's zero
    coordinates left out of p + offset, a point's -0 stayed -0 where offset_ray_origin() makes
    it +0: this test failed.)"""
    import random

    rng = random.Random(11)
    width = _core.rays_per_packet
    normals = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-0.0, 1.0, -0.0]]
    sides = {"front": 0, "back": 0, "plane": 0}
    for n in normals * 60:
        axis = n.index(1.0)
        p, err, toward = [], [], []
        for _ in range(width):
            scale = 10.0 ** rng.uniform(-3, 3)
            pk = [rng.choice([rng.uniform(-1, 1) * scale, 0.0, -0.0]) for _ in range(3)]
            tk = [rng.gauss(0, 1) for _ in range(3)]
            if rng.random() < 0.2:
                tk[axis] = 0.0  # along the plane
            side = tk[axis]
            sides["plane" if side == 0 else "back" if side < 0 else "front"] += 1
            e = rng.choice([0.0, 1e-15 * max(abs(c) for c in pk)])
            p.append(pk), toward.append(tk), err.append([e, e, e])
        lanes = _core.leaving_origins(p, err, [n] * width, toward)
        one = [
            _core.offset_ray_origin(pk, ek, n, tk)
            for pk, ek, tk in zip(p, err, toward, strict=True)
        ]
        assert [[c.hex() for c in o] for o in lanes] == [[c.hex() for c in o] for o in one]
    assert min(sides.values()) > 100, sides


def axis_room(eye: list[float], look_at: list[float]) -> dict:
    """A room of planes whose normals are axes' unit vectors (a mirror floor, a mirror wall, a back
    wall whose normal has zeros of both signs) and a ceiling facing down (not a unit vector's
    direction: the general dot products), with spheres, lights inside and one under the floor."""
    return scene_dict(
        camera={"eye": eye, "look_at": look_at, "fov_y": 70.0, "width": 31, "height": 23},
        render={"max_depth": 6},
        materials={
            "m": material(ambient=0.1, diffuse=0.6, specular=0.5, reflectivity=0.3),
            "mirror": material(ambient=0.05, diffuse=0.3, specular=0.4, reflectivity=0.8),
        },
        lights=[
            {"type": "point", "position": [1.0, 3.0, 2.0]},
            {"type": "point", "position": [-1.0, -2.0, 1.0]},
            {"type": "directional", "direction": [-0.4, -1.0, -0.3]},
        ],
        objects=[
            plane([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], "mirror"),
            plane([-4.0, 0.0, 0.0], [1.0, 0.0, 0.0], "mirror"),
            plane([0.0, 0.0, -6.0], [-0.0, 0.0, 1.0]),
            plane([0.0, 5.0, 0.0], [0.0, -1.0, 0.0]),
            sphere([-1.5, 1.0, -2.0], 1.0),
            sphere([1.5, 0.5, -1.0], 0.5, "mirror"),
        ],
    )


@pytest.mark.parametrize("below", [False, True])
def test_packet_lanes_trace_as_single_rays_in_a_room_of_axis_planes(below):
    """Each lane's colour in double precision, as trace() gives it for the lane's ray, bit for
    bit (a difference an image of floats would hide), and the same ray counts: packets of rays
    from the eye, from under the floor (where the floor is seen from behind, and its normal
    turned), along the floor (d.y = 0: parallel to it) and from points on it (o.y = 0)."""
    scene = to_core(tracer.load_scene(axis_room([0.5, 2.0, 4.0], [-1.0, 0.5, -3.0])))
    rng = np.random.default_rng(5 + below)
    width = _core.rays_per_packet
    kinds = {"eye": 0, "under": 0, "along": 0, "on": 0}
    for _ in range(160):
        kind = list(kinds)[int(rng.integers(0, 4))] if not below else "under"
        kinds[kind] += 1
        origins, directions = [], []
        for _ in range(width):
            d = rng.normal(size=3)
            o = [0.5, 2.0, 4.0]
            if kind == "eye":
                d[1] = -abs(d[1])  # toward the floor, mostly
            elif kind == "under":
                o, d[1] = [0.3, -1.0, 1.0], abs(d[1])
            elif kind == "along":
                o, d[1] = [0.2, 1.0, 0.5], 0.0
            else:
                o = [float(rng.uniform(-3, 3)), 0.0, float(rng.uniform(-5, 3))]
            origins.append(o), directions.append(d.tolist())
        colours, counts = scene.trace_packet(origins, directions)
        one = [scene.trace(o, d) for o, d in zip(origins, directions, strict=True)]
        assert [[c.hex() for c in col] for col in colours] == [
            [c.hex() for c in col] for col, _ in one
        ]
        assert counts == {k: sum(c[k] for _, c in one) for k in counts}
    assert min(kinds.values()) > 20 or below, kinds


def test_trace_packet_refuses_what_a_packet_cannot_hold():
    """Scene.trace_packet takes 1 to rays_per_packet rays, a direction for each origin, and a
    scene of spheres and planes; anything else is refused with a message, not traced."""
    width = _core.rays_per_packet
    scene = to_core(tracer.load_scene(axis_room([0.5, 2.0, 4.0], [-1.0, 0.5, -3.0])))
    for origins, directions in (
        ([], []),
        ([[0.0, 1.0, 0.0]] * (width + 1), [[0.0, 0.0, -1.0]] * (width + 1)),
        ([[0.0, 1.0, 0.0]] * 2, [[0.0, 0.0, -1.0]]),
    ):
        with pytest.raises(ValueError, match=f"1 to {width} origins and as many directions"):
            scene.trace_packet(origins, directions)
    boxed = scene_dict(
        objects=[{"type": "box", "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0], "material": "m"}]
    )
    with pytest.raises(ValueError, match="spheres and planes only"):
        to_core(tracer.load_scene(boxed)).trace_packet([[0.0, 0.5, 3.0]], [[0.0, 0.0, -1.0]])


def test_packets_equal_single_rays_in_a_room_of_axis_planes():
    """The whole render, with the render's culling, from inside the room and from under it."""
    packets_agree(tracer.load_scene(axis_room([0.5, 2.0, 4.0], [-1.0, 0.5, -3.0])))
    packets_agree(tracer.load_scene(axis_room([0.3, -1.0, 1.0], [-1.0, 0.5, -3.0])))


@pytest.mark.parametrize("path", OTHER_SCENES, ids=[p.stem for p in OTHER_SCENES])
def test_packets_fall_back_to_single_rays_for_other_objects(path):
    """Boxes, triangles, meshes, cylinders and tori are traced one ray at a time, and the
    render says so rather than claiming packets."""
    scene = tracer.load_scene(path).with_overrides(width=16, height=12)
    assert tracer.render_with_stats(scene, threads=2, packets=True).integrator == "classic"


def test_one_box_among_spheres_makes_the_scene_one_ray_at_a_time():
    box = {"type": "box", "min": [-0.1, -0.1, -0.1], "max": [0.1, 0.1, 0.1], "material": "m"}
    lit = material(ambient=0.2, diffuse=0.7)
    spheres = scene_dict(
        camera={"width": 8, "height": 6},
        materials={"m": lit},
        lights=[{"type": "point", "position": [2.0, 2.0, 4.0]}],
        objects=[sphere([0.0, 0.0, 0.0], 0.5), sphere([0.6, 0.0, 0.0], 0.2)],
    )
    with_box = {**spheres, "objects": [*spheres["objects"], box]}
    assert tracer.render_with_stats(tracer.load_scene(spheres)).integrator == "classic_packets"
    assert tracer.render_with_stats(tracer.load_scene(with_box)).integrator == "classic"


def test_packets_equal_single_rays_on_a_stiff_scene():
    """Tiny and huge spheres far from the origin, where every rounding shows."""
    c = [1.0e5, -2.0e5, 3.0e5]
    data = scene_dict(
        camera={"eye": [c[0], c[1] + 1.0, c[2] + 4.0], "look_at": c, "width": 37, "height": 29},
        render={"max_depth": 4},
        materials={"m": material(ambient=0.1, diffuse=0.7, specular=0.5, reflectivity=0.5)},
        lights=[
            {"type": "directional", "direction": [-0.3, -0.5, -1.0]},
            {"type": "point", "position": [c[0] + 2, c[1] + 3, c[2] + 1]},
        ],
        objects=[
            sphere(c, 1.0),
            sphere([c[0] + 0.9, c[1], c[2] + 0.9], 1e-3),
            sphere([c[0], c[1] - 1e6 - 1.0, c[2]], 1e6),
        ],
    )
    packets_agree(tracer.load_scene(data))


@pytest.mark.parametrize("integrator", ["aov", "path"])
def test_other_integrators_report_themselves(integrator):
    data = scene_dict(
        camera={"width": 4, "height": 3},
        render={"integrator": integrator},
        objects=[sphere([0.0, 0.0, 0.0], 0.5)],
    )
    # Packets concern the classic model; the path tracer's packets=True is its culled scene
    # queries (the same image: tests/tracer/test_path.py).
    fast = {"aov": "aov", "path": "path_culled"}[integrator]
    for packets, expected in ((False, integrator), (True, fast)):
        result = tracer.render_with_stats(tracer.load_scene(data), threads=1, packets=packets)
        assert result.integrator == expected


def pixel_ray(i: int, j: int, camera: dict) -> tuple[np.ndarray, np.ndarray, float]:
    """The eye (the left one, for a stereo pair), its unit ray direction through pixel (i, j)'s
    centre, and a fifth of a pixel's width per unit distance along it."""
    cam = tracer.load_scene(scene_dict(camera=camera)).camera
    d = pixel_direction(cam, i + 0.5, j + 0.5)
    fifth = float(np.linalg.norm(pixel_direction(cam, i + 0.6, j + 0.5) - d))
    return left_eye(cam)[0], d, fifth


# A packet of primary rays skips the spheres whose bounding box's image rectangle holds none of
# its pixels (12_packet.h pixel_rect(), two pixels of margin): those rays would miss them. A
# sphere a fifth of a pixel across, seen by the one pixel centre it covers, at the image's
# corners, on both sides of a packet's edge (8 pixels of a row) and of a tile's (16): the
# packets must show it where the one-ray code does, also for a stereo pair's left eye.
@pytest.mark.parametrize("pixel", [(0, 0), (36, 20), (7, 3), (8, 3), (15, 15), (16, 16)])
@pytest.mark.parametrize("stereo", [False, True])
def test_a_sphere_seen_by_one_pixel(pixel, stereo):
    camera = {"width": 37, "height": 21}
    if stereo:
        camera["stereo"] = {"eye_separation": 1.0, "convergence": 2.0, "layout": "side_by_side"}
    i, j = pixel
    eye, d, fifth = pixel_ray(i, j, camera)
    data = scene_dict(camera=camera, materials={"m": material(ambient=1.0)},
                      objects=[sphere(list(eye + 10 * d), 10 * fifth)])  # fmt: skip
    a = packets_agree(tracer.load_scene(data))
    lit = np.argwhere(a.image.sum(axis=-1) > 0).tolist()
    assert [j, i] in lit  # the left eye's (or the only) image, columns 0 to 36
    assert len(lit) <= 1 + stereo  # the right eye sees it once at most


# A packet of primary rays that all met one plane skips, for their reflections, the spheres
# whose mirror image's rectangle holds none of its pixels, and for their shadow rays, the
# spheres whose shadow's rectangle holds none (12_packet.h mirrored_rect(), shadow_rect(), two
# pixels of margin). A camera that sees only the floor, and a sphere a fifth of a pixel across
# placed so that the one pixel centre named sees its reflection, or its shadow: at the image's
# corners and on both sides of a packet's edge (8 pixels of a row) and of a tile's (16). The
# packets must show both where the one-ray code does (which these tests also check).
FLOOR_CAMERA = {"eye": [0.0, 2.0, 6.0], "look_at": [0.0, 0.0, 0.0], "width": 37, "height": 21}
FLOOR_PIXELS = [(0, 0), (36, 20), (7, 3), (8, 3), (15, 15), (16, 16)]


def floor_hit(i: int, j: int, camera: dict = FLOOR_CAMERA) -> tuple[np.ndarray, ...]:
    """pixel_ray()'s eye and direction, the point where that ray meets the floor y = 0, and
    pixel_ray()'s fifth of a pixel."""
    eye, d, fifth = pixel_ray(i, j, camera)
    assert d[1] < 0  # every pixel sees the floor
    return eye, d, eye + d * (-eye[1] / d[1]), fifth


def light_at(kind: str, position: np.ndarray, toward: np.ndarray) -> dict:
    """A point light at `position`, or a distant one shining from it towards `toward`."""
    if kind == "point":
        return {"type": "point", "position": position.tolist()}
    return {"type": "directional", "direction": (toward - position).tolist()}


def mirrored_sphere(i: int, j: int, fifths: float, camera: dict = FLOOR_CAMERA) -> dict:
    """A sphere whose mirror image in the floor lies 3 past it on pixel (i, j)'s ray, `fifths`
    fifths of a pixel in radius there: the pixel centre sees its reflection."""
    eye, d, p, fifth = floor_hit(i, j, camera)
    image = eye + d * (np.linalg.norm(p - eye) + 3.0)
    centre = [float(image[0]), float(-image[1]), float(image[2])]
    return sphere(centre, fifths * fifth * float(np.linalg.norm(image - eye)))


def mirror_floor(camera: dict, ball: dict) -> dict:
    """A mirror for a floor, seen by `camera` with one level of reflection, and a ball that
    glows (ambient 1)."""
    return scene_dict(
        camera=camera,
        render={"max_depth": 2},
        materials={"m": material(ambient=1.0), "mirror": material(reflectivity=1.0)},
        objects=[plane([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], "mirror"), ball],
    )


def shadowed_floor(camera: dict, light: dict, centre: np.ndarray, radius: float) -> dict:
    """A diffuse floor seen by `camera`, lit by `light` (no other terms), and a black ball."""
    return scene_dict(
        camera=camera,
        render={"max_depth": 1},
        materials={"m": material(), "floor": material(diffuse=1.0)},
        lights=[light],
        objects=[plane([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], "floor"), sphere(list(centre), radius)],
    )


@pytest.mark.parametrize("pixel", FLOOR_PIXELS)
@pytest.mark.parametrize("stereo", [False, True])
def test_a_reflection_seen_by_one_pixel(pixel, stereo):
    i, j = pixel
    camera = dict(FLOOR_CAMERA)
    if stereo:
        camera["stereo"] = {"eye_separation": 1.0, "convergence": 4.0, "layout": "side_by_side"}
    a = packets_agree(tracer.load_scene(mirror_floor(camera, mirrored_sphere(i, j, 1, camera))))
    assert a.image[j, i].sum() > 0  # the reflection, where the mirror image was put (left eye)


@pytest.mark.parametrize("pixel", FLOOR_PIXELS)
@pytest.mark.parametrize("light", ["point", "directional"])
def test_a_shadow_seen_by_one_pixel(pixel, light):
    i, j = pixel
    eye, _, p, fifth = floor_hit(i, j)
    position = np.array([3.0, 5.0, 2.0])
    centre = p + 0.5 * (position - p)  # halfway to the light, on pixel (i, j)'s shadow ray
    radius = fifth * float(np.linalg.norm(centre - eye))
    data = shadowed_floor(FLOOR_CAMERA, light_at(light, position, p), centre, radius)
    a = packets_agree(tracer.load_scene(data))
    assert a.image[j, i].sum() == 0  # in the shadow
    assert (a.image.sum(axis=-1) > 0).mean() > 0.9  # and the floor around it lit


def test_packets_equal_single_rays_around_planes():
    """Where the floor's culling must give up, or could go wrong: a tilted mirror and a wall
    besides the floor; spheres resting on the floor, cutting through it, under it, and one
    higher than the point light; a point light under the floor, one above, a distant one."""
    data = scene_dict(
        camera={"eye": [0.5, 3.0, 9.0], "look_at": [0.0, 0.5, 0.0], "fov_y": 60.0},
        render={"max_depth": 4},
        materials={
            "m": material(ambient=0.1, diffuse=0.6, specular=0.5, reflectivity=0.4),
            "mirror": material(ambient=0.05, diffuse=0.3, reflectivity=0.8),
        },
        lights=[
            {"type": "point", "position": [2.0, 3.0, 3.0]},
            {"type": "point", "position": [-1.0, -2.0, 1.0]},
            {"type": "directional", "direction": [-0.4, -1.0, -0.3]},
        ],
        objects=[
            plane([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], "mirror"),
            plane([0.0, 0.0, -6.0], [0.0, 0.2, 1.0]),
            plane([-7.0, 0.0, 0.0], [1.0, 0.3, 0.1], "mirror"),
            sphere([-1.5, 1.0, 0.0], 1.0),
            sphere([1.5, 0.2, 0.5], 0.7),
            sphere([0.0, -2.0, 2.0], 0.8),
            sphere([2.5, 3.5, -1.0], 0.6),
            sphere([0.3, 0.05, 2.5], 0.05),
        ],
    )
    scene = tracer.load_scene(data).with_overrides(width=97, height=61)
    packets_agree(scene)


# Shadow rays from a packet's points on spheres skip the spheres that cannot shadow those
# (12_packet.h cannot_shadow(): the light's cones, or a distant light's cylinders, of the two
# spheres do not overlap). A sphere a fifth of a pixel across, halfway from the point of a big
# sphere that one pixel centre sees to the light: that pixel alone is in its shadow, and the
# packets must agree.
@pytest.mark.parametrize("pixel", [(18, 10), (15, 8), (16, 8), (14, 10), (23, 12), (20, 5)])
@pytest.mark.parametrize("light", ["point", "directional"])
def test_a_sphere_shadowed_at_one_pixel(pixel, light):
    camera = {"width": 37, "height": 21}
    i, j = pixel
    eye, d, fifth = pixel_ray(i, j, camera)
    b = float(np.dot(eye, d))  # the unit sphere at the origin: t^2 + 2 b t + |eye|^2 - 1 = 0
    disc = b * b - (float(np.dot(eye, eye)) - 1.0)
    assert disc > 0  # the pixel sees the big sphere
    x = eye + d * (-b - np.sqrt(disc))
    position = np.array([3.0, 4.0, 5.0])
    assert np.dot(x, position - x) > 0  # and its point faces the light
    centre = x + 0.5 * (position - x)
    radius = 0.5 * fifth * float(np.linalg.norm(x - eye))  # its shadow: a fifth of a pixel
    data = scene_dict(
        camera=camera,
        render={"max_depth": 1},
        materials={"m": material(), "lit": material(diffuse=1.0)},
        lights=[light_at(light, position, x)],
        objects=[sphere([0.0, 0.0, 0.0], 1.0, "lit"), sphere(centre.tolist(), radius)],
    )
    a = packets_agree(tracer.load_scene(data))
    assert a.image[j, i].sum() == 0  # in the small sphere's shadow
    assert a.image[j, i - 1].sum() > 0 and a.image[j, i + 1].sum() > 0  # its neighbours lit


# The rectangles of a sphere's image and of its mirror image are exact, and that of its shadow
# on a plane nearly so (12_packet.h sphere_rect(), shadow_rect(): the image of a polygon 2%
# outside the shadow), each with two pixels of margin. A ball some fifteen pixels in radius
# whose edge (or the edge of its reflection, or of its shadow) passes a fifth of a pixel inside
# one pixel centre, with nothing of it beyond that pixel in its packet (or tile): at a packet's
# first column with the ball to its left, at its last column with the ball to its right, at a
# tile's first row with the ball above it and at its last row with the ball below. The packets
# must show that pixel as the one-ray code does, and the pixel beyond it must show nothing of
# the ball (so the edge is where the test says). Smaller rectangles, which the tests of a ball a
# fifth of a pixel across above cannot tell from these, fail here: the ball's angular radius,
# a point light's cone's or a distant light's cylinder's radius taken at half its size, each
# tried by editing the code.
EDGE_CAMERA = {"width": 48, "height": 32}
EDGE_FLOOR_CAMERA = {"eye": [0.0, 2.0, 6.0], "look_at": [0.0, 0.0, 0.0], "width": 48, "height": 32}
# (pixel, the image's direction from that pixel into the ball, the pixel beyond the edge)
EDGES = [
    ((8, 12), "left", (9, 12)),
    ((15, 12), "right", (14, 12)),
    ((20, 16), "up", (20, 17)),
    ((20, 15), "down", (20, 14)),
]
TOWARD = {
    "left": np.array([-1.0, 0.0, 0.0]),
    "right": np.array([1.0, 0.0, 0.0]),
    "up": np.array([0.0, 1.0, 0.0]),
    "down": np.array([0.0, -1.0, 0.0]),
}


def edge_centre(x: np.ndarray, d: np.ndarray, radius: float, inside: float, toward: np.ndarray):
    """The centre of a ball of `radius` that the line through x along unit d passes `inside`
    within its edge, off the line at x in `toward`'s direction made perpendicular to d."""
    u = toward - np.dot(toward, d) * d
    return x + (radius - inside) * u / np.linalg.norm(u)


def meets(o: np.ndarray, d: np.ndarray, centre: np.ndarray, radius: float) -> bool:
    """Whether the ray from o along unit d meets the ball ahead of o."""
    f = o - centre
    b = float(np.dot(f, d))
    c = float(np.dot(f, f)) - radius * radius
    return b * b - c >= 0 and (c < 0 or b < 0)


@pytest.mark.parametrize(("pixel", "toward", "beyond"), EDGES)
def test_the_edge_of_a_large_sphere_in_one_pixel(pixel, toward, beyond):
    (i, j), radius = pixel, 1.5
    eye, d, fifth = pixel_ray(i, j, EDGE_CAMERA)
    centre = edge_centre(eye + 6.0 * d, d, radius, fifth * 6.0, TOWARD[toward])
    data = scene_dict(camera=EDGE_CAMERA, materials={"m": material(ambient=1.0)},
                      objects=[sphere(centre.tolist(), radius)])  # fmt: skip
    a = packets_agree(tracer.load_scene(data))
    assert a.image[j, i].sum() > 0
    assert a.image[beyond[1], beyond[0]].sum() == 0


@pytest.mark.parametrize(("pixel", "toward", "beyond"), EDGES)
def test_the_edge_of_a_large_spheres_reflection_in_one_pixel(pixel, toward, beyond):
    (i, j), radius = pixel, 1.0
    eye, d, p, fifth = floor_hit(i, j, EDGE_FLOOR_CAMERA)
    past = float(np.linalg.norm(p - eye)) + 3.0  # the mirror image's distance along the ray
    image = edge_centre(eye + past * d, d, radius, fifth * past, TOWARD[toward])
    centre = image * np.array([1.0, -1.0, 1.0])
    for column, row in (pixel, beyond):  # the primary rays meet the floor, not the ball
        e, dk, _ = pixel_ray(column, row, EDGE_FLOOR_CAMERA)
        assert not meets(e, dk, centre, radius)
    data = mirror_floor(EDGE_FLOOR_CAMERA, sphere(list(centre), radius))
    a = packets_agree(tracer.load_scene(data))
    assert a.image[j, i].sum() > 0
    assert a.image[beyond[1], beyond[0]].sum() == 0


@pytest.mark.parametrize(("pixel", "toward", "beyond"), EDGES)
@pytest.mark.parametrize("light", ["point", "directional"])
def test_the_edge_of_a_large_spheres_shadow_in_one_pixel(pixel, toward, beyond, light):
    (i, j), radius = pixel, 0.8
    eye, _, p, fifth = floor_hit(i, j, EDGE_FLOOR_CAMERA)
    position = np.array([1.0, 6.0, -2.0])
    w = (position - p) / np.linalg.norm(position - p)  # from p towards the light
    # The ball halfway to the light, the shadow ray from p inside its edge by half a fifth of a
    # pixel at p (the floor point a fifth of a pixel away moves the ray that much there); the
    # image's direction into the ball taken on the floor (rows: along -z, up in the image).
    into = {"left": [-1.0, 0, 0], "right": [1.0, 0, 0], "up": [0, 0, -1.0], "down": [0, 0, 1.0]}
    half = 0.5 * float(np.linalg.norm(position - p))
    inside = 0.5 * fifth * float(np.linalg.norm(p - eye))
    centre = edge_centre(p + half * w, w, radius, inside, np.array(into[toward]))
    for column, row in (pixel, beyond):  # the primary rays meet the floor, not the ball
        e, dk, _ = pixel_ray(column, row, EDGE_FLOOR_CAMERA)
        assert not meets(e, dk, centre, radius)
    data = shadowed_floor(EDGE_FLOOR_CAMERA, light_at(light, position, p), centre, radius)
    a = packets_agree(tracer.load_scene(data))
    assert a.image[j, i].sum() == 0  # in the shadow
    assert a.image[beyond[1], beyond[0]].sum() > 0  # and the pixel beyond it lit


# With several samples a pixel, a packet holds eight samples in order (at spp = 2, those of four
# pixels of a row) and skips what none of its samples' image points can see. A mirror image 0.4
# pixel in radius at the centre of the first pixel of a packet (columns 4m of a tile's rows):
# the packet's last samples lie 2.5 pixels or more from it, past the rectangle's margin, so a
# span taken from them alone would lose the reflection. (Pixels where one of the seeded samples
# meets it.)
@pytest.mark.parametrize("pixel", [(4, 3), (12, 10), (20, 17), (28, 6)])
def test_a_reflection_in_the_first_pixel_of_a_packet_of_samples(pixel):
    i, j = pixel
    data = scene_dict(
        camera=FLOOR_CAMERA,
        render={"max_depth": 2, "spp": 2, "seed": 5},
        materials={"m": material(ambient=1.0), "mirror": material(reflectivity=1.0)},
        objects=[plane([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], "mirror"), mirrored_sphere(i, j, 4)],
    )
    a = packets_agree(tracer.load_scene(data))
    assert a.image[j, i].sum() > 0  # some sample of the pixel sees the reflection


def random_scene(seed: int) -> dict:
    """Spheres, planes and lights thrown at random around the origin, for the culling's corners:
    a camera above or below the planes, tilted and axis-aligned planes, spheres resting on,
    cutting or under them, tiny and large, lights below planes, inside spheres or level with
    them, distant lights grazing a plane."""
    rng = np.random.default_rng(seed)

    def unit() -> list[float]:
        v = rng.normal(size=3)
        return (v / np.linalg.norm(v)).tolist()

    def point(scale: float) -> list[float]:
        return (rng.uniform(-scale, scale, size=3)).tolist()

    planes = [plane([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], "a")]
    for _ in range(int(rng.integers(0, 3))):
        planes.append(plane(point(3.0), unit(), "b"))
    spheres = []
    for _ in range(int(rng.integers(2, 9))):
        r = float(rng.choice([0.02, 0.3, 1.0, 2.5]))
        c = point(4.0)
        if rng.random() < 0.4:
            c[1] = r * float(rng.choice([1.0, 0.5, -1.2]))  # on, through or under the floor
        spheres.append(sphere(c, r, str(rng.choice(["a", "b"]))))
    lights = []
    for _ in range(int(rng.integers(1, 4))):
        kind = rng.random()
        if kind < 0.15:
            c = spheres[0]["center"]
            lights.append({"type": "point", "position": c})  # inside a sphere
        elif kind < 0.6:
            lights.append({"type": "point", "position": point(8.0)})
        elif kind < 0.75:
            lights.append({"type": "directional", "direction": [1.0, 0.0, 0.3]})  # grazing
        else:
            lights.append({"type": "directional", "direction": unit()})
    eye = (np.array(unit()) * rng.uniform(6.0, 12.0)).tolist()
    return scene_dict(
        camera={"eye": eye, "look_at": point(1.0), "fov_y": 50.0, "width": 41, "height": 29},
        render={"max_depth": 4, "spp": int(rng.choice([1, 1, 2])), "seed": seed},
        materials={
            "a": material(ambient=0.1, diffuse=0.6, specular=0.4, reflectivity=0.5),
            "b": material(ambient=0.05, diffuse=0.4, reflectivity=0.9),
        },
        lights=lights,
        objects=planes + spheres,
    )


@pytest.mark.parametrize("seed", range(40))
def test_packets_equal_single_rays_on_random_scenes(seed):
    packets_agree(tracer.load_scene(random_scene(seed)))


# A tile that no sphere's rectangle reaches and through which no plane is seen (12_packet.h
# plane_unseen(): the sign of each primary ray's direction along the plane's normal, bounded at
# the tile's corners with a millionth to spare) is filled with the background without tracing a
# ray. A camera 1 above the floor (or below it) tilted so that the floor's horizon crosses the
# image at `row`: on a tile's edge (16), between two rows of pixel centres inside a tile (8),
# through a row of pixel centres (15.5: those rays graze the floor, and the tile above must be
# traced), and for the left eye of a stereo pair, whose window is shifted.
SKY = [0.1, 0.2, 0.3]


def horizon_scene(row: float, below: bool = False, **render) -> dict:
    height, fov_y = 40, 60.0
    tilt = (0.5 - row / height) * 2 * np.tan(np.radians(fov_y / 2))  # d.y = 0 on that row
    eye_y = -1.0 if below else 1.0
    return scene_dict(
        camera={
            "eye": [0.0, eye_y, 4.0],
            "look_at": [0.0, eye_y - tilt, 3.0],
            "fov_y": fov_y,
            "width": 37,
            "height": height,
        },
        render={"max_depth": 3, "background": SKY, **render},
        materials={"m": material(ambient=0.2, diffuse=0.6, reflectivity=0.5)},
        lights=[{"type": "point", "position": [2.0, 3.0 * eye_y, 5.0]}],
        objects=[plane([0.0, 0.0, 0.0], [0.0, 1.0, 0.0]), sphere([1.5, 0.5 * eye_y, -2.0], 0.5)],
    )


@pytest.mark.parametrize("row", [16.0, 8.0, 15.5, 32.0])
@pytest.mark.parametrize("below", [False, True])
@pytest.mark.parametrize("stereo", [False, True])
def test_the_sky_beyond_a_horizon(row, below, stereo):
    data = horizon_scene(row, below)
    if stereo:
        data["camera"]["stereo"] = {"eye_separation": 0.5, "convergence": 4.0,
                                    "layout": "side_by_side"}  # fmt: skip
    scene = tracer.load_scene(data)
    a = packets_agree(scene)
    # The last row of centres above the horizon and the first below it. From above the floor
    # the rows above the horizon see the sky; from below, the rows above see the floor.
    above, under = int(np.ceil(row - 0.5)) - 1, int(np.floor(row + 0.5))
    sky, floor = (under, above) if below else (above, under)
    assert (a.image[sky] == np.float32(SKY)).all()  # the one-ray code's image: the sky,
    assert (a.image[floor] != np.float32(SKY)).any(axis=-1).all()  # and the floor
    if not stereo and not below:  # the tile of the last sky row: filled where wholly sky
        tile = 16 * (sky // 16)
        unseen = _core.plane_unseen(to_core(scene), 0, 0.5, 36.5, tile + 0.5,
                                    min(tile + 16, 40) - 0.5)  # fmt: skip
        assert unseen == (row >= tile + 16)


def test_a_sky_tile_with_nothing_traced_is_black():
    """With a min_coefficient above the first level's 1, trace() colours no ray: a filled tile
    must be black too, and counted as the one-ray code counts it. (fill_background() also
    blackens max_depth 0, which the scene reader refuses.)"""
    a = packets_agree(tracer.load_scene(horizon_scene(16.0, min_coefficient=2.0)))
    assert (a.image == 0).all()


def test_plane_unseen_never_hides_a_plane_a_ray_meets():
    """Where plane_unseen() says no primary ray of a span meets the plane, every pixel centre's
    ray direction (computed apart, in numpy) has a component along the normal of the sign that
    never meets it: the opposite of dot(point - eye, n)'s, or zero. Spans of 1 to 16 pixels
    across random cameras and tilted planes; both answers must occur."""
    rng = np.random.default_rng(11)
    answers = {True: 0, False: 0}
    for seed in range(40):
        data = random_scene(seed)
        scene = tracer.load_scene(data)
        core = to_core(scene)
        cam = scene.camera
        eye = np.array(cam.eye)
        planes = [o for o in scene.objects if type(o).__name__ == "Plane"]
        for k, pl in enumerate(planes):
            n = np.array(pl.normal) / np.linalg.norm(pl.normal)
            num = float(np.dot(np.array(pl.point) - eye, n))
            for _ in range(20):
                w, h = (int(v) for v in rng.integers(1, 17, size=2))
                i0, j0 = (
                    int(rng.integers(0, cam.width - w + 1)),
                    int(rng.integers(0, cam.height - h + 1)),
                )
                unseen = _core.plane_unseen(core, k, i0 + 0.5, i0 + w - 0.5, j0 + 0.5, j0 + h - 0.5)
                answers[unseen] += 1
                if not unseen:
                    continue
                for i in range(i0, i0 + w):
                    for j in range(j0, j0 + h):
                        along = float(np.dot(pixel_direction(cam, i + 0.5, j + 0.5), n))
                        assert along == 0 or (along > 0) != (num > 0), (seed, k, i, j)
    assert min(answers.values()) > 100, answers


def test_ex25s_sky_is_filled():
    """Ex 25 at the bench's size: the top left tile sees neither the floor nor a sphere (so the
    render fills it), the bottom left one sees the floor."""
    from reference.bench import ex25_scene

    core = to_core(ex25_scene(1920, 1024))
    assert _core.plane_unseen(core, 0, 0.5, 15.5, 0.5, 15.5)
    assert not _core.plane_unseen(core, 0, 0.5, 15.5, 1008.5, 1023.5)
