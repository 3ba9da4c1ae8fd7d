"""Stereoscopy (slide "Stereoscopy"): a stereo pair of cameras, the parallel-axis asymmetric
frustum (tracer/cpp/03_camera.h stereo_eye()), its layouts and Dubois' anaglyph.

The closed forms are checked on the core's own primary rays: a ray's unnormalized direction
is affine in the pixel coordinates, so three rays give the map from pixels to directions, and
inverting it says where any point lands in an eye, with no formula of the camera copied here.
"""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest

import tracer
from tests.helpers import material, scene_dict, sphere
from tracer import _core
from tracer.render import (
    DUBOIS_LEFT,
    DUBOIS_RIGHT,
    anaglyph,
    compose_stereo,
    eye_scene,
    render_progressive,
    render_with_stats,
)
from tracer.scene import SceneError, parse_scene

EYE = np.array([0.3, 1.2, 6.0])
LOOK_AT = np.array([-0.2, 0.8, 0.0])
UP = np.array([0.1, 1.0, 0.0])
FOV_Y, W, H = 50.0, 64, 48
SEPARATION, CONVERGENCE = 0.4, 5.0
#: Pixel coordinates come out of a 3x2 solve on doubles of magnitude ~W: rounding leaves
#: ~1e-13 px; 1e-9 px is far below any pixel and far above that noise.
PIXEL_TOL = 1e-9


def frame() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    f = (LOOK_AT - EYE) / np.linalg.norm(LOOK_AT - EYE)
    r = np.cross(f, UP)
    r /= np.linalg.norm(r)
    return f, r, np.cross(r, f)


def camera(side: int = 0, separation: float = SEPARATION, convergence: float = CONVERGENCE,
           eye: np.ndarray = EYE, look_at: np.ndarray = LOOK_AT) -> _core.Scene:  # fmt: skip
    core = _core.Scene()
    core.set_camera(tuple(eye), tuple(look_at), tuple(UP), FOV_Y, W, H, side, separation,
                    convergence)  # fmt: skip
    return core


class Projection:
    """Where a point lands in a camera, from the core's primary rays alone."""

    def __init__(self, core: _core.Scene, forward: np.ndarray | None = None) -> None:
        """``forward``: the camera's viewing direction (by default the pair's shared one)."""
        f = frame()[0] if forward is None else forward / np.linalg.norm(forward)
        samples = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]
        rays = [core.primary_ray(sx, sy) for sx, sy in samples]
        self.origin = np.array(rays[0][0])
        # The direction scaled to a unit component along the shared forward: affine in (sx, sy).
        d = [np.array(dd) / np.dot(dd, f) for _, dd in rays]
        self.a, self.b, self.c = d[0], d[1] - d[0], d[2] - d[0]
        self.f = f

    def direction(self, w: np.ndarray) -> tuple[float, float]:
        """The pixel (sx, sy) whose ray runs along ``w`` (a point at infinity)."""
        w = np.asarray(w, dtype=float) / np.dot(w, self.f)
        m = np.stack([self.b, self.c], axis=1)
        (sx, sy), *_ = np.linalg.lstsq(m, w - self.a, rcond=None)
        return float(sx), float(sy)

    def point(self, p: np.ndarray) -> tuple[float, float]:
        return self.direction(np.asarray(p) - self.origin)


def eyes(**kw) -> tuple[Projection, Projection]:
    return Projection(camera(-1, **kw)), Projection(camera(+1, **kw))


def test_the_eyes_sit_half_the_separation_either_side_along_right():
    _, r, _ = frame()
    left, right = eyes()
    assert left.origin == pytest.approx(EYE - SEPARATION / 2 * r, abs=1e-14)
    assert right.origin == pytest.approx(EYE + SEPARATION / 2 * r, abs=1e-14)
    assert Projection(camera(0)).origin == pytest.approx(EYE, abs=0)


def test_a_point_on_the_convergence_plane_lands_on_the_same_pixel_in_both_eyes():
    f, r, u = frame()
    left, right = eyes()
    for x, y in [(0.0, 0.0), (0.9, 0.4), (-1.3, -0.7)]:
        p = EYE + CONVERGENCE * f + x * r + y * u
        (lx, ly), (rx, ry) = left.point(p), right.point(p)
        assert 0 < lx < W and 0 < ly < H  # it is in the picture
        assert abs(lx - rx) < PIXEL_TOL and abs(ly - ry) < PIXEL_TOL


def test_nearer_points_cross_and_farther_points_do_not():
    """Negative parallax in front of the convergence plane, positive behind it."""
    f, r, _ = frame()
    left, right = eyes()
    near, far = EYE + 2.0 * f + 0.2 * r, EYE + 20.0 * f + 0.2 * r
    assert right.point(near)[0] - left.point(near)[0] < -1
    assert right.point(far)[0] - left.point(far)[0] > 1


def test_a_point_at_infinity_lands_eye_separation_over_convergence_apart():
    """Parallel axes: a direction w lands where the single camera puts it, each eye's window
    shifted (e/2)/C the other way on the image plane (distance 1): e/C apart in all, which is
    the eye separation itself measured on the convergence plane."""
    f, r, u = frame()
    plane_units = 2 * math.tan(math.radians(FOV_Y) / 2) * W / H / W  # one pixel, at distance 1
    centre = Projection(camera(0))
    left, right = eyes()
    for w in [f, f + 0.3 * r - 0.2 * u, f - 0.25 * r + 0.15 * u]:
        (cx, cy), (lx, ly), (rx, ry) = centre.direction(w), left.direction(w), right.direction(w)
        half = SEPARATION / 2 / CONVERGENCE
        assert (cx - lx) * plane_units == pytest.approx(half, abs=1e-12)
        assert (rx - cx) * plane_units == pytest.approx(half, abs=1e-12)
        assert (rx - lx) * plane_units * CONVERGENCE == pytest.approx(SEPARATION, abs=1e-12)
        assert abs(ly - cy) < PIXEL_TOL and abs(ry - cy) < PIXEL_TOL


def points_around() -> list[np.ndarray]:
    f, r, u = frame()
    rng = np.random.default_rng(9)
    return [EYE + z * f + x * r + y * u
            for z, x, y in zip(rng.uniform(1.5, 40, 50), rng.uniform(-1, 1, 50),
                               rng.uniform(-1, 1, 50), strict=True)
            for x, y in [(x * z * 0.4, y * z * 0.3)]]  # fmt: skip


def test_off_axis_has_no_vertical_parallax_where_toe_in_has():
    """The off-axis pair: every point at the same row in both eyes. Toe-in (each eye a plain
    camera turned to look at the convergence point) tilts the image planes against each other:
    off-centre points land on different rows, which the eyes cannot fuse."""
    left, right = eyes()
    off_axis = max(abs(left.point(p)[1] - right.point(p)[1]) for p in points_around())
    assert off_axis < PIXEL_TOL

    f, r, _ = frame()
    target = EYE + CONVERGENCE * f
    eye_l, eye_r = EYE - SEPARATION / 2 * r, EYE + SEPARATION / 2 * r
    toe_l = Projection(camera(0, eye=eye_l, look_at=target), target - eye_l)
    toe_r = Projection(camera(0, eye=eye_r, look_at=target), target - eye_r)
    toe_in = max(abs(toe_l.point(p)[1] - toe_r.point(p)[1]) for p in points_around())
    assert toe_in > 0.05  # pixels: measured 0.51 px for this 64x48 camera
    # And toe-in does converge: the convergence point itself lands on one pixel.
    assert toe_l.point(target) == pytest.approx(toe_r.point(target), abs=PIXEL_TOL)


def test_a_window_shifted_the_wrong_way_is_caught():
    """Injection: the convergence sign flipped moves each window the wrong way; the check of
    the convergence plane must see it."""
    f, _, _ = frame()
    left, right = eyes(convergence=-CONVERGENCE)
    p = EYE + CONVERGENCE * f
    assert abs(left.point(p)[0] - right.point(p)[0]) > 1  # injected: the eyes disagree


# --------------------------------------------------------------------------- the scene language


def stereo_data(layout: str = "side_by_side", **camera) -> dict:
    cam = {"eye": list(EYE), "look_at": list(LOOK_AT), "up": list(UP), "fov_y": FOV_Y,
           "width": 16, "height": 12,
           "stereo": {"eye_separation": SEPARATION, "convergence": CONVERGENCE,
                      "layout": layout}}  # fmt: skip
    cam.update(camera)
    return scene_dict(
        camera=cam,
        materials={
            "m": material(ambient=0.2, diffuse=0.8),
            "w": material(color=[0.2, 0.5, 0.9], diffuse=0.7),
        },
        lights=[{"type": "point", "position": [3.0, 6.0, 8.0]}],
        objects=[sphere([-0.2, 0.8, 0.0], 1.0), sphere([1.2, 0.5, 2.0], 0.5, "w")],
    )


def test_a_stereo_camera_reads_writes_and_overrides():
    scene = tracer.load_scene(stereo_data("over_under"))
    st = scene.camera.stereo
    assert (st.eye_separation, st.convergence, st.layout) == (SEPARATION, CONVERGENCE,
                                                              "over_under")  # fmt: skip
    assert parse_scene(scene.to_dict()) == scene
    assert scene.with_overrides(width=8).camera.stereo == st
    mono = tracer.load_scene(scene_dict())
    assert mono.camera.stereo is None and "stereo" not in mono.to_dict()["camera"]
    default = stereo_data()
    del default["camera"]["stereo"]["layout"]
    assert tracer.load_scene(default).camera.stereo.layout == "side_by_side"


@pytest.mark.parametrize(
    ("stereo", "key", "words"),
    [
        ({"eye_separation": 0.0, "convergence": 5.0}, "camera.stereo.eye_separation",
         "expected a positive number"),
        ({"eye_separation": -1, "convergence": 5.0}, "camera.stereo.eye_separation",
         "expected a positive number"),
        ({"eye_separation": 0.1, "convergence": 0}, "camera.stereo.convergence",
         "expected a positive number"),
        ({"convergence": 5.0}, "camera.stereo.eye_separation", "missing"),
        ({"eye_separation": 0.1}, "camera.stereo.convergence", "missing"),
        ({"eye_separation": 0.1, "convergence": 5.0, "layout": "side-by-side"},
         "camera.stereo.layout", "did you mean 'side_by_side'"),
        ({"eye_separation": 0.1, "convergence": 5.0, "layout": "anaglif"},
         "camera.stereo.layout", "did you mean 'anaglyph'"),
        ({"eye_separation": 0.1, "convergence": 5.0, "layout": 3}, "camera.stereo.layout",
         "expected a string"),
        ({"eye_seperation": 0.1, "convergence": 5.0}, "camera.stereo.eye_seperation",
         "did you mean 'eye_separation'"),
        ({"eye_separation": "wide", "convergence": 5.0}, "camera.stereo.eye_separation",
         "expected a number"),
        ([0.1, 5.0], "camera.stereo", "expected a table"),
        ({"eye_separation": 1.0, "convergence": 1e-300}, "camera.stereo.convergence",
         "expected at least eye_separation / 1e+06"),
    ],
)  # fmt: skip
def test_bad_stereo_settings_name_the_key(stereo, key, words):
    data = stereo_data()
    data["camera"]["stereo"] = stereo
    with pytest.raises(SceneError) as info:
        parse_scene(data, source="pair.toml")
    message = str(info.value)
    assert message.startswith(f"pair.toml: {key}:"), message
    assert words in message, message


def test_a_misspelt_stereo_key_in_camera_is_suggested():
    data = stereo_data()
    data["camera"]["steereo"] = data["camera"].pop("stereo")
    with pytest.raises(SceneError, match=r"camera\.steereo: unknown key.*did you mean 'stereo'"):
        parse_scene(data)


# --------------------------------------------------------------------------- rendering the pair


@pytest.fixture(scope="module")
def pair() -> tuple[np.ndarray, np.ndarray]:
    scene = tracer.load_scene(stereo_data())
    left = tracer.render(eye_scene(scene, "left"), threads=1)
    right = tracer.render(eye_scene(scene, "right"), threads=1)
    return left, right


def test_each_eye_is_its_own_view(pair):
    left, right = pair
    assert left.shape == right.shape == (12, 16, 3)
    assert np.abs(left - right).max() > 0.1  # the eyes see the scene from different places


@pytest.mark.parametrize(
    ("layout", "shape"),
    [("side_by_side", (12, 32, 3)), ("over_under", (24, 16, 3)), ("anaglyph", (12, 16, 3)),
     ("left", (12, 16, 3)), ("right", (12, 16, 3))],
)  # fmt: skip
def test_layouts_compose_the_eyes(pair, layout, shape):
    left, right = pair
    scene = tracer.load_scene(stereo_data(layout))
    assert scene.camera.image_shape == shape[:2]
    result = render_with_stats(scene, threads=2, progress=False)
    assert result.image.shape == shape and result.image.dtype == np.float32
    assert np.array_equal(result.image, compose_stereo(layout, left, right))
    eyes_rendered = 1 if layout in ("left", "right") else 2
    assert result.rays["primary"] == eyes_rendered * 16 * 12
    if layout == "side_by_side":
        assert np.array_equal(result.image[:, :16], left)
        assert np.array_equal(result.image[:, 16:], right)
    if layout == "over_under":
        assert np.array_equal(result.image[:12], left)
        assert np.array_equal(result.image[12:], right)


def test_packets_and_single_rays_agree_for_both_eyes():
    scene = tracer.load_scene(stereo_data())
    a = render_with_stats(scene, threads=1, packets=True, progress=False)
    b = render_with_stats(scene, threads=1, packets=False, progress=False)
    assert a.integrator == "classic_packets" and b.integrator == "classic"
    assert np.array_equal(a.image, b.image)


def test_an_object_on_the_convergence_plane_covers_the_same_pixels_in_both_eyes():
    """Rendered: a quad lying on the convergence plane is seen by both eyes on the same pixels
    (the frusta coincide there); moved off the plane, it is not (the check can fail)."""
    f, r, u = frame()

    def masks(distance: float) -> tuple[np.ndarray, np.ndarray]:
        c = EYE + distance * f
        corner = c - 1.4 * r - 1.0 * u
        quad = {"type": "quad", "corner": list(corner), "edge1": list(2.8 * r),
                "edge2": list(2.0 * u), "material": "m"}  # fmt: skip
        data = stereo_data(width=40, height=30)
        data["objects"] = [quad]
        data["render"]["integrator"] = "aov"
        image = tracer.render(tracer.load_scene(data), threads=1)
        ids = image[..., 1]
        return ids[:, :40] >= 0, ids[:, 40:] >= 0

    left, right = masks(CONVERGENCE)
    assert left.sum() > 100 and np.array_equal(left, right)
    left, right = masks(CONVERGENCE * 0.6)
    assert left.sum() > 100 and not np.array_equal(left, right)


def test_an_aov_anaglyph_is_refused():
    data = stereo_data("anaglyph")
    data["render"]["integrator"] = "aov"
    with pytest.raises(SceneError, match=r"camera\.stereo\.layout: expected side_by_side"):
        tracer.render(tracer.load_scene(data), threads=1)


def test_a_single_camera_costs_nothing_extra():
    """A mono scene traces one eye's rays: no second render, no shift."""
    data = stereo_data()
    del data["camera"]["stereo"]
    result = render_with_stats(tracer.load_scene(data), threads=1, progress=False)
    assert result.image.shape == (12, 16, 3) and result.rays["primary"] == 16 * 12


# --------------------------------------------------------------------------- Dubois' anaglyph

#: The published matrices have three decimals: six entries rounded by at most 0.0005 each.
PUBLISHED_ROUNDING = 6 * 0.0005
#: Rec. 709 luminance weights: how bright each of the display's primaries looks.
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def test_dubois_rows_sum_to_one_so_white_stays_white():
    rows = DUBOIS_LEFT.sum(axis=1) + DUBOIS_RIGHT.sum(axis=1)
    assert rows == pytest.approx([1, 1, 1], abs=PUBLISHED_ROUNDING)
    white = np.ones((1, 1, 3), np.float32)
    assert anaglyph(white, white)[0, 0] == pytest.approx([1, 1, 1], abs=PUBLISHED_ROUNDING)


def test_dubois_sends_red_to_the_left_eye_and_cyan_to_the_right():
    """Red-cyan glasses, red over the left eye: the anaglyph's red comes from the left image,
    its green and blue from the right."""
    assert DUBOIS_LEFT[0].sum() > 1 > 0 > DUBOIS_RIGHT[0].sum()
    assert DUBOIS_RIGHT[1].sum() > 1 > 0 > DUBOIS_LEFT[1].sum()
    assert DUBOIS_RIGHT[2].sum() > 1 > 0 > DUBOIS_LEFT[2].sum()


def channel_split(left: np.ndarray, right: np.ndarray) -> np.ndarray:
    """The plain anaglyph: red from the left eye, green and blue from the right."""
    return np.concatenate([left[..., :1], right[..., 1:]], axis=-1)


def eye_luminances(image: np.ndarray) -> tuple[float, float]:
    """What each eye sees through ideal filters: the left (red) the red channel, the right
    (cyan) green and blue, weighted by how bright each primary looks."""
    px = image.reshape(-1, 3).mean(axis=0)
    return float(px[0] * LUMINANCE[0]), float(px[1:] @ LUMINANCE[1:])


def test_dubois_keeps_both_eyes_lit_where_a_channel_split_blinds_one():
    """Retinal rivalry: a saturated object seen by one eye and not the other. Through a plain
    split a pure red object is black to the right eye, a green or blue one black to the left;
    Dubois' projection gives both eyes light from each primary (and greys stay grey in both)."""
    for primary in np.eye(3):
        img = np.broadcast_to(primary, (2, 2, 3)).astype(np.float32)
        split = eye_luminances(channel_split(img, img))
        dubois = eye_luminances(anaglyph(img, img))
        assert min(split) == 0.0
        # measured 0.176 (green), 0.36 (red), 0.42 (blue)
        assert min(dubois) / max(dubois) > 0.15, (primary, dubois)
    grey = np.full((2, 2, 3), 0.5, np.float32)
    assert anaglyph(grey, grey) == pytest.approx(grey, abs=PUBLISHED_ROUNDING)
    # Injection: the plain split in place of Dubois must fail the rivalry bound above.
    red = np.broadcast_to(np.eye(3)[0], (2, 2, 3)).astype(np.float32)
    lum = eye_luminances(channel_split(red, red))
    assert not min(lum) / max(lum) > 0.15


def test_the_anaglyph_never_shows_negative_light():
    blue = np.broadcast_to(np.eye(3)[2], (2, 2, 3)).astype(np.float32)
    raw = blue.reshape(-1, 3) @ (DUBOIS_LEFT + DUBOIS_RIGHT).T
    assert raw.min() < 0  # the projection asks for negative green here
    assert anaglyph(blue, blue).min() == 0.0


def test_the_largest_separation_allowed_still_renders_finite_rays():
    """At the bound, eye_separation = 1e6 convergence, the window shift is 5e5 plane units:
    the rays are still finite and unit length (past it the reader refuses, above)."""
    data = stereo_data()
    data["camera"]["stereo"].update(eye_separation=1e6, convergence=1.0)
    scene = tracer.load_scene(data)
    image = tracer.render(scene, threads=1)
    assert np.isfinite(image).all()
    core = camera(-1, separation=1e6, convergence=1.0)
    _, d = core.primary_ray(0.5, 0.5)
    assert np.linalg.norm(d) == pytest.approx(1.0, abs=1e-15)


def test_memory_is_counted_for_both_eyes_and_their_composition(monkeypatch):
    """A side_by_side pair keeps both eyes (2 w h pixels) and their composition (2 w h): four
    times one eye's image. Memory is made to hold three: a single camera fits, the pair not."""
    tr = sys.modules["tracer.render"]  # the module: tracer.render is also the function
    one_eye = 16 * 12 * 3 * 4  # bytes: float32 RGB
    monkeypatch.setattr(tr, "memory_available", lambda: (3 * one_eye, "the test"))
    data = stereo_data()
    tr.check_memory(tracer.load_scene({**data, "camera": {**data["camera"], "stereo": None}}))
    with pytest.raises(tr.ImageTooLargeError, match="a 32x12 image needs 9216 bytes"):
        tr.check_memory(tracer.load_scene(data))


def test_a_progressive_render_refines_both_eyes():
    scene = tracer.load_scene(stereo_data("over_under"))
    result = render_progressive(scene, 0.0, threads=1)
    assert result.image.shape == (24, 16, 3)
    single = render_with_stats(scene, threads=1, progress=False).image
    assert np.array_equal(result.image, single)  # one pass of spp = 1: the same rays


def test_the_render_summary_counts_samples_per_eye(tmp_path, capsys):
    """A side-by-side pair traces one primary ray per pixel of each eye: the summary says 1 spp
    per eye (dividing by one eye's pixels would say 2)."""
    from tests.helpers import SCENES
    from tracer.cli import main

    text = (SCENES / "shadows.toml").read_text()
    stereo = "[camera]\nstereo = { eye_separation = 0.2, convergence = 5.0 }\n"
    scene = tmp_path / "pair.toml"
    scene.write_text(text.replace("[camera]\n", stereo, 1))
    argv = ["render", str(scene), "-o", str(tmp_path / "pair.npy"), "--width", "8", "--height", "6"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "8x6 per eye, 1 spp" in out, out
