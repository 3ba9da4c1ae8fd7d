"""Stiff cases: tiny, huge and distant spheres, very narrow fields of view, grazing rays, and
self-intersection at every scale. The expected answers come from exact rational arithmetic
(fractions.Fraction) on the very rays the core traces, so they are independent of how the core
rounds; a naive implementation is shown to fail the same checks."""

from __future__ import annotations

import math
import random
from decimal import Decimal, getcontext
from fractions import Fraction

import numpy as np
import pytest

import tracer
from tests.helpers import material, scene_dict, sphere
from tracer import _core
from tracer.render import to_core


def exact_discriminant(center, radius, o, d) -> Fraction:
    """b^2 - a c of the ray/sphere quadratic, exactly, for the given double inputs."""
    f = [Fraction(oi) - Fraction(ci) for oi, ci in zip(o, center, strict=True)]
    dd = [Fraction(x) for x in d]
    a = sum(x * x for x in dd)
    b = sum(x * y for x, y in zip(f, dd, strict=True))
    c = sum(x * x for x in f) - Fraction(radius) ** 2
    return b * b - a * c


def naive_discriminant(center, radius, o, d) -> float:
    f = np.subtract(o, center)
    a, b, c = np.dot(d, d), np.dot(f, d), np.dot(f, f) - radius * radius
    return float(b * b - a * c)


def coverage(center, radius, eye, width, height, fov_y):
    """The core's rendered mask of a sphere, and the exact mask for the core's own rays."""
    data = scene_dict(
        camera={"eye": eye, "look_at": center, "width": width, "height": height, "fov_y": fov_y},
        materials={"m": material(ambient=1.0)},
        objects=[sphere(center, radius)],
    )
    scene = tracer.load_scene(data)
    image = tracer.render(scene, threads=2)[..., 0]
    core = to_core(scene)
    exact = np.zeros((height, width), dtype=bool)
    naive = np.zeros((height, width), dtype=bool)
    for j in range(height):
        for i in range(width):
            o, d = core.primary_ray(i + 0.5, j + 0.5)
            exact[j, i] = exact_discriminant(center, radius, o, d) >= 0
            naive[j, i] = naive_discriminant(center, radius, o, d) >= 0
    return image > 0.5, exact, naive


def angular_fov(radius, distance, fill):
    """A vertical field of view (degrees) in which the sphere's disc fills `fill` of the height."""
    return math.degrees(2 * math.atan(math.asin(radius / distance) / fill))


@pytest.mark.parametrize(
    ("center", "radius", "eye"),
    [
        ([1.0e6, -3.0e5, 2.0e5], 1.0e-3, [0.0, 0.0, 0.0]),  # tiny and far: D ~ r^2 << b^2
        ([0.0, 0.0, 0.0], 1.0e-6, [0.3, 0.2, 1.0]),  # tiny and near
        ([2.0e7, 1.0e7, -3.0e7], 1.0e6, [0.0, 1.0, 0.0]),  # huge and far
    ],
)
def test_silhouette_is_exact_at_any_scale(center, radius, eye):
    distance = math.dist(center, eye)
    mask, exact, naive = coverage(center, radius, eye, 32, 32, angular_fov(radius, distance, 0.7))
    assert 100 < exact.sum() < 1024  # the disc is in the picture, with a silhouette
    assert np.array_equal(mask, exact), f"{np.sum(mask != exact)} pixels differ"
    if radius == 1.0e-3:
        # The textbook formula loses every digit of D here; the exact check must be able to tell.
        assert not np.array_equal(naive, exact)


def test_grazing_rays_classified_exactly():
    """Rays whose line passes the centre at r (1 +- 2^-40): tangent within 1e-12 relative."""
    rng = random.Random(5)
    for _ in range(300):
        r = 10 ** rng.uniform(-4, 4)
        c = [rng.uniform(-1, 1) * 10 ** rng.uniform(-3, 5) for _ in range(3)]
        d = np.array([rng.gauss(0, 1) for _ in range(3)])
        d /= np.linalg.norm(d)
        side = np.cross(d, [0.3, 0.5, 0.7])
        side /= np.linalg.norm(side)
        miss = r * (1 + rng.choice([-1, 1]) * 2.0**-40)
        o = np.array(c) + side * miss - d * 10 * r
        name, hit = _core.intersect_sphere(c, r, list(o), list(d))
        truth = exact_discriminant(c, r, list(o), list(d)) >= 0
        assert (hit is not None) == truth, (r, c, name)


def exact_t(center, radius, o, d) -> float:
    getcontext().prec = 60
    f = [Decimal(oi) - Decimal(ci) for oi, ci in zip(o, center, strict=True)]
    dd = [Decimal(x) for x in d]
    a = sum(x * x for x in dd)
    b = sum(x * y for x, y in zip(f, dd, strict=True))
    c = sum(x * x for x in f) - Decimal(radius) ** 2
    return float((-b - (b * b - a * c).sqrt()) / a)


def test_hit_distance_accurate_on_huge_and_distant_spheres():
    """t to about 1e-12 relative, where the naive form's cancellation would cost digits."""
    rng = random.Random(11)
    for _ in range(200):
        r = 10 ** rng.uniform(-3, 7)
        dist = r * 10 ** rng.uniform(0.001, 6)
        c = [0.0, 0.0, -dist]
        o = [rng.uniform(-0.3, 0.3) * r, rng.uniform(-0.3, 0.3) * r, 0.0]
        d = [0.0, 0.0, -1.0]
        _, hit = _core.intersect_sphere(c, r, o, d)
        assert hit is not None
        assert hit["t"] == pytest.approx(exact_t(c, r, o, d), rel=1e-12)


def test_spawned_rays_never_hit_their_own_sphere():
    """pbrt-v4's re-intersection test (shapes_test.cpp): radii from 1e-4 to 1e4 at positions up
    to 1e4, rays from random points; a ray spawned outward from the hit must miss the sphere, and
    one spawned inward must reach the far side, not the surface it leaves."""
    rng = random.Random(3)
    for _ in range(2000):
        r = 10 ** rng.uniform(-4, 4)
        c = [rng.uniform(-1, 1) * 10 ** rng.uniform(-4, 4) for _ in range(3)]
        target = np.array(c) + r * _unit(rng)
        o = target + _unit(rng) * r * 10 ** rng.uniform(0, 2)
        _, hit = _core.intersect_sphere(c, r, list(o), list(target - o))
        if hit is None:
            continue
        n = np.array(hit["normal"])
        out = _unit(rng)
        if np.dot(out, n) < 0:
            out = -out
        origin = _core.offset_ray_origin(hit["point"], hit["error"], list(n), list(out))
        assert _core.intersect_sphere(c, r, origin, list(out))[1] is None
        inward = -n + 0.5 * _unit(rng)
        origin = _core.offset_ray_origin(hit["point"], hit["error"], list(n), list(inward))
        _, far = _core.intersect_sphere(c, r, origin, list(inward))
        chord = -2 * r * np.dot(inward, n) / np.dot(inward, inward)  # exact far-side t
        assert far is not None and far["t"] == pytest.approx(chord, rel=1e-6)


def _unit(rng: random.Random) -> np.ndarray:
    v = np.array([rng.gauss(0, 1) for _ in range(3)])
    return v / np.linalg.norm(v)


@pytest.mark.parametrize("scale", [1e-4, 1.0, 1e4])
def test_no_shadow_acne_far_from_the_origin(scale):
    """A lit sphere of radius `scale` placed 1e5 * scale from the origin: every pixel facing the
    light must be lit (acne would leave specks of bare ambient), and none facing away."""
    c = [1.0e5 * scale, -2.0e5 * scale, 3.0e5 * scale]
    eye = [c[0], c[1] + 1.0 * scale, c[2] + 4.0 * scale]
    light_dir = [-0.3, -0.5, -1.0]
    data = scene_dict(
        camera={"eye": eye, "look_at": c, "width": 48, "height": 48, "fov_y": 35.0},
        materials={"m": material(ambient=0.1, diffuse=0.8)},
        lights=[{"type": "directional", "direction": light_dir}],
        objects=[sphere(c, scale)],
    )
    scene = tracer.load_scene(data)
    image = tracer.render(scene, threads=2)[..., 0]
    core = to_core(scene)
    L = -np.array(light_dir) / np.linalg.norm(light_dir)
    checked = 0
    for j in range(48):
        for i in range(48):
            o, d = core.primary_ray(i + 0.5, j + 0.5)
            hit = core.closest_hit(o, d)
            if hit is None:
                continue
            nl = float(np.dot(hit["normal"], L))
            want = 0.1 + 0.8 * max(nl, 0.0)
            assert image[j, i] == pytest.approx(want, rel=1e-5, abs=1e-6), (i, j, nl)
            checked += 1
    assert checked > 500


def test_offset_rounds_one_ulp_further_away():
    """offset_ray_origin's last step is nextafter away from the surface, in each component: an
    error bound far below an ulp of p moves p by exactly one ulp."""
    p = [1.0, -2.0, 0.0]
    tiny = [1e-300] * 3
    got = _core.offset_ray_origin(p, tiny, [1.0, -1.0, 0.0], [1.0, -1.0, 0.0])
    assert got[0] == math.nextafter(1.0, math.inf)
    assert got[1] == math.nextafter(-2.0, -math.inf)
    assert got[2] == 0.0  # no offset along z: unchanged
    got = _core.offset_ray_origin(p, tiny, [0.0, 0.0, 1.0], [0.0, 0.0, -1.0])
    assert got[:2] == [1.0, -2.0] and got[2] == math.nextafter(-1e-300, -math.inf)


def test_power_matches_libm_pow():
    """power.h's exp(n ln x) against libm's pow: relative error about |n ln x| 2^-53 <= 2e-13
    (|n ln x| < 708 while the result is a normal double); 5e-13 leaves room for the rest."""
    rng = random.Random(9)
    worst = 0.0
    for _ in range(20000):
        x, n = rng.uniform(1e-6, 1.0), rng.uniform(0.5, 500.0)
        want = math.pow(x, n)
        if want < 1e-300:
            continue
        worst = max(worst, abs(_core.power(x, n) - want) / want)
    assert worst < 5e-13
    assert _core.power(1.0, 60.0) == 1.0
    assert _core.power(0.5, 2.0) == pytest.approx(0.25, rel=1e-15)


def test_power_of_a_whole_exponent_by_squaring_is_within_its_bound():
    """A whole exponent 1 <= n <= 1024 goes by repeated squaring (power.h): n - 1 roundings at
    most, so a relative error within gamma(n - 1) = (n - 1) u / (1 - (n - 1) u), u = 2^-53,
    against x^n computed exactly (Fraction); exact where no rounding happens (powers of two,
    n = 1). Both ends of the range, and the exponents just outside it, which take exp(n ln x)."""
    u = 2.0**-53
    rng = random.Random(11)
    exponents = [1, 2, 3, 10, 60, 255, 256, 1023, 1024] + [rng.randint(1, 1024) for _ in range(60)]
    worst = 0.0
    for n in exponents:
        for x in (rng.uniform(1e-3, 1.0), rng.uniform(0.9, 1.0), 1 - rng.random() * 1e-9):
            exact = Fraction(x) ** n
            if exact < Fraction(2.0**-1022):
                continue
            got = _core.power(x, float(n))
            bound = (n - 1) * u / (1 - (n - 1) * u)
            error = abs(Fraction(got) - exact) / exact
            assert error <= bound, (x, n, float(error), bound)
            worst = max(worst, float(error))
    assert worst > 0  # roundings did happen: the bound was tested, not only exact cases
    assert _core.power(0.5, 1024.0) == 0.0  # 2^-1024, below 2^-1022: flushed to 0, as before
    assert _core.power(0.5, 1000.0) == 2.0**-1000
    assert _core.power(0.75, 1.0) == 0.75
    # Just outside the range, and not whole: exp(n ln x), whose error grows with |n ln x|.
    for x, n in ((0.999, 1025.0), (0.999, 60.5), (0.999, 0.5)):
        assert _core.power(x, n) == pytest.approx(math.pow(x, n), rel=5e-13)
