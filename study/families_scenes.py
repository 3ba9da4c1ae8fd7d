"""Issue 11's scene families (appended to study/families.py's FAMILIES):

- ``nearly-touching``: two spheres, a sphere on a plane, two parallel planes, with a gap from
  1e-1 of the size down to one ulp of the coordinates at the contact; rays aimed into the gap and
  at the near-contact region (protocol "touching": the decision metrics and which surface is
  met first, study/chains.py);
- ``mirror-chains``: the same pairs, rays reflected at every hit for up to BOUNCES bounces
  (protocol "chain", study/chains.py);
- ``grazing-cylinder``: issue 11's grazing rays on cylinders, a sibling of ``grazing`` (the
  spheres' family) so that the spheres' figures and frozen rays stay as they are;
- ``far-camera``: cameras 1 .. 1e8 away from a unit-size scene with fields of view down to
  1e-7 degrees (protocol "camera", study/cameras.py);
- ``rotated-boxes``: the self-intersection protocol on boxes under random rotations
  (study/shapes.py RotatedBox: the truth takes the core's own double matrix as exact).

Every scene lies along the x axis (or, for cylinders, a coordinate axis), so that what the
scene language describes is what the core builds, exactly (an oblique cylinder axis goes
through a rounded frame matrix, tracer/scene/placement.py frame(): its rounding would be the
description's, not the method's)."""

from __future__ import annotations

import math

import numpy as np

from study.families import FAMILIES, Array, Case, Family, _f32, _normalize, _perp, _units
from study.shapes import Cylinder, Group, Plane, Sphere

#: The gap's sweep: 1e-1 .. 1e-15 of the radius, and one ulp (2^-52: the contact lies at about
#: the radius, where the spacing of doubles is 2^-52 of it).
GAPS = (*(10.0**-e for e in range(1, 16)), 2.0**-52)
QUICK_GAPS = (1e-1, 1e-8, 2.0**-52)


def _pairs(knob: float, rng: np.random.Generator) -> list[tuple[Group, float, float, float]]:
    """The three nearly touching pairs at relative gap ``knob``: (group, radius, the contact's
    x, the gap). The first surface's face is the plane x = x0 (x0 about the radius, so that the
    gap's ulps are those of the coordinates), the second's at x0 + gap, at least one ulp."""
    r = _f32(10.0 ** rng.uniform(-2, 2))
    x0 = _f32(r * rng.uniform(0.5, 2))
    out = []
    for j in range(3):
        if j == 2:  # two parallel planes
            far = max(float(np.float64(x0) + knob * r), float(np.nextafter(x0, math.inf)))
            g = Group((Plane((x0, 0.0, 0.0), (1.0, 0.0, 0.0)),
                       Plane((far, 0.0, 0.0), (-1.0, 0.0, 0.0))))  # fmt: skip
            out.append((g, r, x0, far - x0))
            continue
        c = x0 + r  # exact: both have 24 bits, within a factor 4
        cb = max(float(np.float64(c) + knob * r), float(np.nextafter(c, math.inf)))
        second = Sphere((cb, 0.0, 0.0), r)
        first = Sphere((x0 - r, 0.0, 0.0), r) if j == 0 else Plane((x0, 0.0, 0.0), (1.0, 0.0, 0.0))
        out.append((Group((first, second)), r, x0, cb - c))
    return out


def _inside(group: Group, p: Array) -> np.ndarray:
    bad = np.zeros(len(p), dtype=bool)
    for m in group.members:
        if isinstance(m, Sphere):
            bad |= np.linalg.norm(p - np.array(m.center), axis=1) < m.radius
    return bad


def nearly_touching(knob: float, n: int, rng: np.random.Generator) -> list[Case]:
    """Half the rays aimed at a point inside the gap (x0 < x < x0 + gap) from a grazing
    direction (|d.x| 10^-4 .. 1 of the rest), half at the near-contact region (within a few
    gaps of the contact in x, within sqrt(3 r gap) of the axis: where the surfaces are a few
    gaps apart) from any direction; origins 2 radii away, outside both surfaces."""
    cases = []
    for group, r, x0, gap in _pairs(knob, rng):
        k = n // 24
        rho = math.sqrt(r * gap) * 3 * np.sqrt(rng.uniform(0, 1, k))
        phi = rng.uniform(0, 2 * math.pi, k)
        q = np.c_[np.zeros(k), rho * np.cos(phi), rho * np.sin(phi)]
        into = np.arange(k) % 2 == 0
        q[:, 0] = np.where(into, x0 + gap * rng.uniform(0.05, 0.95, k),
                           x0 + gap * rng.uniform(-3, 4, k))  # fmt: skip
        d = _units(rng, k)
        slant = 10.0 ** -rng.uniform(0, 4, k) * rng.choice([-1.0, 1.0], k)
        d[:, 0] = np.where(into, slant * np.linalg.norm(d[:, 1:], axis=1), d[:, 0])
        d = _normalize(d)
        o = q - 2 * r * d
        flip = _inside(group, o)
        o = np.where(flip[:, None], q + 2 * r * d, o)
        d = np.where(flip[:, None], -d, d)
        cases.append(Case(group, o, q - o, protocol="touching"))  # type: ignore[arg-type]
    return cases


def mirror_chains(knob: float, n: int, rng: np.random.Generator) -> list[Case]:
    """Rays started in the gap (at its middle in x, a few contact widths from the axis) into
    the wedge between the surfaces: towards the contact, slanted across the gap
    (|d.x| 10^-3 .. 1 of the rest), so that they bounce between the two surfaces."""
    cases = []
    for group, r, x0, gap in _pairs(knob, rng):
        k = max(n // 100, 4)
        width = math.sqrt(r * gap)
        o = np.zeros((k, 3))
        o[:, 0] = x0 + gap / 2
        o[:, 1] = width * rng.uniform(0.5, 3, k)
        o[:, 2] = width * rng.uniform(-1, 1, k)
        d = np.c_[10.0 ** -rng.uniform(0, 3, k) * rng.choice([-1.0, 1.0], k),
                  -np.ones(k), rng.uniform(-0.5, 0.5, k)]  # fmt: skip
        cases.append(Case(group, o, _normalize(d), protocol="chain"))  # type: ignore[arg-type]
    return cases


def grazing_cylinder(knob: float, n: int, rng: np.random.Generator) -> list[Case]:
    """Rays whose line passes the cylinder's axis at r (1 +- 2^-k), at mid-height, slanted along
    the axis by at most 0.3 radians: they meet the side only (the height is 4 r), never a cap."""
    cases = []
    for _ in range(4):
        r = _f32(10.0 ** rng.uniform(-3, 3))
        base = np.array([_f32(x) for x in rng.uniform(-1, 1, 3) * r * 10.0 ** rng.uniform(0, 3)])
        axis = int(rng.integers(3))
        e = np.zeros(3)
        e[axis] = rng.choice([-1.0, 1.0])
        top = base + 4 * r * e
        k = n // 16
        across = _perp(np.tile(e, (k, 1)), rng)
        side = np.cross(e, across)
        slant = rng.uniform(-0.3, 0.3, k)
        d = _normalize(np.cos(slant)[:, None] * across + np.sin(slant)[:, None] * e)
        miss = r * (1 + rng.choice([-1.0, 1.0], k) * 2.0**-knob)
        mid = base + 2 * r * e
        o = mid + side * miss[:, None] - d * (10 * r)
        shape = Cylinder(tuple(base), tuple(float(x) for x in top), r)  # type: ignore[arg-type]
        cases.append(Case(shape, o, d))  # type: ignore[arg-type]
    return cases


def far_camera(knob: float, n: int, rng: np.random.Generator) -> list[Case]:
    """A unit-size sphere, box and triangle seen from ``knob`` away: rtlab's own pixel rays
    (study/cameras.py) of a camera whose field of view fits the shape in the frame
    (2 atan(0.6 / distance): 6.9e-7 degrees at 1e8), and of one zoomed 8 times further in
    (8.6e-8 degrees at 1e8)."""
    from study.cameras import CameraCase, pixel_rays
    from study.shapes import Box, Triangle

    side = max(int(math.sqrt(n // 40)), 2)  # 5 x 5 pixels quick, 10 x 10 full
    centre = np.array([_f32(x) for x in rng.uniform(-1, 1, 3)])
    # Every coordinate float32-representable (_f32), as in the other families: centre +- 0.5 may
    # need a bit more than float has, and a float method would then trace another box (a face
    # moved by half a float ulp, beyond the bound a face hit claims on its own axis).
    shapes = [
        Sphere(tuple(centre), 0.5),
        Box(tuple(_f32(x) for x in centre - 0.5), tuple(_f32(x) for x in centre + 0.5)),
        Triangle(*(tuple(_f32(x) for x in centre + 0.5 * u) for u in _units(rng, 3))),
    ]
    cases = []
    for shape in shapes:
        for zoom in (1, 8):
            u = _units(rng, 1)[0]
            eye = centre + knob * u
            up = _perp(u[None, :], rng)[0] + 0.3 * _units(rng, 1)[0]
            fov = math.degrees(2 * math.atan(0.6 / knob)) / zoom
            cam = {"eye": [float(x) for x in eye], "look_at": [float(x) for x in centre],
                   "up": [float(x) for x in up], "fov_y": fov, "width": side,
                   "height": side}  # fmt: skip
            o, d = pixel_rays(shape, cam)
            cases.append(CameraCase(shape, o, d, protocol="camera", camera=cam))  # type: ignore[arg-type]
    return cases


def rotated_boxes(knob: float, n: int, rng: np.random.Generator) -> list[Case]:
    """study/families.py self_intersection()'s protocol on boxes placed by a random rotation
    (any axis, any angle) and a translation at coordinates about ``knob``: hit a face, spawn from
    the hit a ray leaving outward or inward; it must not meet the face it leaves."""
    from study.shapes import RotatedBox

    cases = []
    for _ in range(2):
        size = knob * 10.0 ** rng.uniform(-2, 0)
        half = size * rng.uniform(0.2, 1, 3)
        axis = _units(rng, 1)[0]
        shape = RotatedBox(tuple(-half), tuple(half), tuple(axis), float(rng.uniform(0, 360)),
                           tuple(rng.uniform(-1, 1, 3) * knob))  # type: ignore[arg-type]  # fmt: skip
        m = np.asarray(shape.matrix())
        k = n // 16
        ax = rng.integers(0, 3, k)
        sign = rng.choice([-1.0, 1.0], k)
        q = rng.uniform(-0.95, 0.95, (k, 3)) * half
        q[np.arange(k), ax] = sign * half[ax]
        nn = np.zeros((k, 3))
        nn[np.arange(k), ax] = sign
        q = q @ m[:, :3].T + m[:, 3]
        nn = _normalize(nn @ np.linalg.inv(m[:, :3]))  # the inverse transpose, row by row
        back = _units(rng, k)
        back = np.where((np.sum(back * nn, axis=1) < 0)[:, None], -back, back)
        o = q + back * (size * 10.0 ** rng.uniform(0, 2, k))[:, None]
        leave = _units(rng, k)
        outward = np.arange(k) % 2 == 0
        facing = np.sum(leave * nn, axis=1) > 0
        leave = np.where((facing != outward)[:, None], -leave, leave)
        cases.append(Case(shape, o, _normalize(q - o), protocol="spawn", leave=leave,
                          outward=outward))  # fmt: skip
    return cases


SCENE_FAMILIES = (
    Family("nearly-touching", "gap (relative to the radius)", GAPS, QUICK_GAPS,
           ("sphere", "plane"), nearly_touching, "wrong_object", stiffer="down"),
    Family("mirror-chains", "gap (relative to the radius)", GAPS, QUICK_GAPS,
           ("sphere", "plane"), mirror_chains, "chain_errors", stiffer="down"),
    Family("grazing-cylinder", "k (miss distance r(1 +- 2^-k))",
           tuple(float(k) for k in range(1, 53)), (4.0, 40.0, 52.0), ("cylinder",),
           grazing_cylinder),
    Family("far-camera", "camera distance / scene size", tuple(10.0**e for e in range(0, 9)),
           (1.0, 1e4, 1e8), ("sphere", "box", "triangle"), far_camera),
    Family("rotated-boxes", "coordinate scale", tuple(10.0**e for e in range(-8, 9)),
           (1e-8, 1.0, 1e8), ("box",), rotated_boxes, "self_hits", stiffer="both"),
)  # fmt: skip

FAMILIES.update({f.name: f for f in SCENE_FAMILIES})
