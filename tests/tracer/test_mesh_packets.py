"""Packets of primary rays through the mesh hierarchy (tracer/cpp/22_mesh_packets.h, the aov
integrator in scenes of meshes, packets=True) give every pixel what the lecture's one-ray code
gives it (16_mesh.h Mesh::traverse, packets=False).

Each lane's box decisions are slab_test()'s and each accepted triangle is intersect_triangle()'s
for that ray; only the order in which leaves are reached differs, which could change which of
two triangles hit at exactly the same t is kept. No such tie occurs in these images, so they are
required to be identical, channel by channel: a difference would be either a tie or a bug, and
either needs a look."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tests.helpers import SCENES, left_eye, pixel_direction
from tracer.render import render_with_stats
from tracer.scene import Mesh, load_scene


def meshes_only(name: str, **overrides):
    scene = load_scene(SCENES / name).with_overrides(integrator="aov", **overrides)
    return dataclasses.replace(scene, objects=tuple(o for o in scene.objects
                                                    if isinstance(o, Mesh)))  # fmt: skip


def both(scene):
    packets = render_with_stats(scene, threads=2, progress=False, packets=True)
    plain = render_with_stats(scene, threads=2, progress=False, packets=False)
    return packets, plain


# Sizes that are not multiples of a packet's 4 x 2 pixels nor of a tile's 16: partial packets
# at every tile's right and bottom edges.
@pytest.mark.parametrize("name", ["bunny.toml", "bunny_smooth.toml", "inside_mesh.toml"])
def test_aov_images_are_identical(name):
    scene = meshes_only(name, width=131, height=77)
    packets, plain = both(scene)
    assert np.array_equal(packets.image, plain.image)
    depth = packets.image[..., 0]
    assert np.isfinite(depth).any()
    assert np.isinf(depth).any() == name.startswith("bunny")  # inside_mesh: every ray hits
    assert packets.rays["primary"] == plain.rays["primary"] == 131 * 77
    assert (packets.integrator, plain.integrator) == ("aov_packets", "aov")


def test_two_meshes_and_an_oblique_camera():
    """Two meshes (each ray keeps its range from the first into the second) seen along a
    diagonal, from inside the bunny's bounding box and with a wide field of view, so that
    packets straddle the axes' sign changes and the axis of largest direction component."""
    scene = meshes_only("bunny.toml", width=90, height=70)
    bunny = scene.objects[0]
    low, high = bunny.vertices.min(axis=0), bunny.vertices.max(axis=0)
    shifted = dataclasses.replace(bunny, vertices=bunny.vertices + (high - low) * [0.6, 0, 0.3])
    centre = (low + high) / 2
    camera = dataclasses.replace(scene.camera, eye=tuple(centre + (high - low) * [0.4, 0.2, 0.45]),
                                 look_at=tuple(centre), fov_y=100.0)  # fmt: skip
    scene = dataclasses.replace(scene, objects=(bunny, shifted), camera=camera)
    packets, plain = both(scene)
    assert (packets.integrator, plain.integrator) == ("aov_packets", "aov")
    assert np.array_equal(packets.image, plain.image)
    ids = set(np.unique(packets.image[..., 1]).tolist())
    assert {0.0, 1.0} <= ids  # both meshes are seen


# The eye on a triangle: every ray meets that triangle at a t within rounding of 0, where
# intersect_triangle()'s t-error guard decides, which 22_mesh_packets.h computes lane by lane,
# asking starts_off_the_plane_heading_in() for each doubtful lane. "centroid": the centroid of a
# bunny's triangle, within rounding of its plane, so that the question says yes for some rays;
# "plane": a triangle in the plane z = 0 and the eye exactly in it, so that it says no. With the
# question left out, every doubtful lane rejected or every one accepted, one of these images
# differed from the one-ray code's (both tried by editing 22_mesh_packets.h).
@pytest.mark.parametrize("on", ["centroid", "plane"])
def test_an_eye_on_a_triangle(on):
    scene = meshes_only("bunny.toml", width=64, height=48)
    bunny = scene.objects[0]
    if on == "centroid":
        eye = bunny.vertices[bunny.faces[5000]].mean(axis=0)
        look_at = (bunny.vertices.min(axis=0) + bunny.vertices.max(axis=0)) / 2
    else:
        corners = np.array([[-10.0, -10.0], [10.0, -10.0], [0.0, 10.0]])
        vertices = np.vstack([np.c_[corners, np.zeros(3)], np.c_[corners, np.ones(3)]])
        faces = np.array([[0, 1, 2], [3, 4, 5]], dtype=np.int32)
        bunny = dataclasses.replace(bunny, vertices=vertices, faces=faces, smooth=False,
                                    normals=None)  # fmt: skip
        eye, look_at = np.array([0.25, 0.5, 0.0]), np.array([3.0, 1.0, 0.2])
    camera = dataclasses.replace(scene.camera, eye=tuple(eye.tolist()),
                                 look_at=tuple(look_at.tolist()), fov_y=120.0)  # fmt: skip
    scene = dataclasses.replace(scene, camera=camera, objects=(bunny,))
    packets, plain = both(scene)
    assert (packets.integrator, plain.integrator) == ("aov_packets", "aov")
    assert np.array_equal(packets.image, plain.image)
    assert np.isfinite(plain.image[..., 0]).mean() > 0.2  # it sees the mesh


def test_scenes_with_other_objects_trace_one_ray_at_a_time():
    """A plane beside the bunny: the packets do not serve the scene, and the image is the
    one-ray code's all the same."""
    scene = load_scene(SCENES / "bunny.toml").with_overrides(integrator="aov", width=40,
                                                              height=30)  # fmt: skip
    assert {type(o).__name__ for o in scene.objects} == {"Mesh", "Plane"}
    packets, plain = both(scene)
    assert packets.integrator == plain.integrator == "aov"
    assert np.array_equal(packets.image, plain.image)


# A packet whose pixels lie outside the image rectangle of every mesh's root box is not traced
# (12_packet.h pixel_rect()): its rays would miss the box. A triangle a fifth of a pixel
# across, whose box is seen by the one pixel centre it covers, at the image's corners, at a
# packet's first and last pixel, and on both sides of a tile's edge: the packets must find it
# where the one-ray code does. A rectangle off by more than its two pixels of margin loses it:
# with the rows' axis flipped 14 of these cases failed, with the stereo window's shift left out
# 7 (both tried by editing pixel_rect()).
@pytest.mark.parametrize("pixel", [(0, 0), (36, 20), (4, 2), (3, 1), (15, 15), (16, 16), (7, 3)])
@pytest.mark.parametrize("stereo", [False, True])
def test_a_mesh_seen_by_one_pixel(pixel, stereo):
    scene = meshes_only("bunny.toml", width=37, height=21)
    if stereo:  # side by side; the triangle is placed for the left eye
        from tracer.scene.model import Stereo

        stereo_pair = Stereo(eye_separation=1.0, convergence=2.0)
        camera = dataclasses.replace(scene.camera, stereo=stereo_pair)
        scene = dataclasses.replace(scene, camera=camera)
    i, j = pixel
    cam = scene.camera
    # A fifth of a pixel across at distance 10, around the pixel centre's ray.
    corners = [(i + 0.4, j + 0.6), (i + 0.6, j + 0.6), (i + 0.5, j + 0.4)]
    vertices = left_eye(cam)[0] + 10 * np.array([pixel_direction(cam, *c) for c in corners])
    tiny = dataclasses.replace(scene.objects[0], vertices=vertices,
                               faces=np.array([[0, 1, 2]], dtype=np.int32), smooth=False,
                               normals=None)  # fmt: skip
    scene = dataclasses.replace(scene, objects=(tiny,))
    packets, plain = both(scene)
    assert (packets.integrator, plain.integrator) == ("aov_packets", "aov")
    assert np.array_equal(packets.image, plain.image)
    hits = np.argwhere(np.isfinite(plain.image[..., 0])).tolist()
    assert [j, i] in hits  # the left eye's (or the only) image, columns 0 to 36
    assert len(hits) <= 1 + stereo  # the right eye sees it once at most
