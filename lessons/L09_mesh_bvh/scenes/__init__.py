"""L09's scene checks (lessons/scene_checks.py): two balls passing through each other as one
mesh and two crossing sheets of triangles (the hierarchy's boxes overlap: the closest hit must
be searched past the first leaf with a hit), and a cap of a ball searched through the bounding box
of the whole mesh only, seen with every direction component negative (the box's slab test).

The analytic values are the closest hit of every triangle of the scene file's mesh, found here
by testing each (Moeller-Trumbore, in double precision), never by the tracer's hierarchy.
"A ray that misses a box skips the triangles in it" changes how many triangles are tested, not
the picture: the probes check it (the ray counts' box and triangle tests have no reference)."""

import math
import tomllib
from pathlib import Path

from lessons.probe import HIDDEN
from lessons.scene_checks import Analytic, SceneCheck, cross, dot, sub, unit

HERE = Path(__file__).resolve().parent


def closest_mesh_hit(name: str, i: int, j: int) -> float:
    """The distance to the nearest of all the mesh's triangles along pixel (i, j)'s centre ray
    (slide "Perspective Ray Tracing"), every triangle tested."""
    scene = tomllib.loads((HERE / f"{name}.toml").read_text())
    cam = scene["camera"]
    eye, look_at = tuple(cam["eye"]), tuple(cam["look_at"])
    forward = unit(sub(look_at, eye))
    right = unit(cross(forward, (0.0, 1.0, 0.0)))
    up = cross(right, forward)
    h = 2 * math.tan(math.radians(cam["fov_y"]) / 2)
    w = h * cam["width"] / cam["height"]
    x, y = (i + 0.5) / cam["width"] - 0.5, 0.5 - (j + 0.5) / cam["height"]
    d = unit(tuple(f + x * w * r + y * h * u for f, r, u in zip(forward, right, up, strict=True)))  # type: ignore[arg-type]
    mesh = next(o for o in scene["objects"] if o["type"] == "mesh")
    vs = [tuple(v) for v in mesh["vertices"]]
    best = math.inf
    for f in mesh["faces"]:
        p0, p1, p2 = (vs[k] for k in f)
        e1, e2 = sub(p1, p0), sub(p2, p0)
        q = cross(d, e2)
        det = dot(e1, q)
        if det == 0:
            continue
        s = sub(eye, p0)
        b1 = dot(s, q) / det
        r = cross(s, e1)
        b2 = dot(d, r) / det
        t = dot(e2, r) / det
        if b1 >= 0 and b2 >= 0 and b1 + b2 <= 1 and 0 < t < best:
            best = t
    return best


# float32 output: half an ulp of a depth below 4 is 2.4e-7; the double arithmetic's roundings
# ~1e-15. 2e-6 holds both; a farther triangle taken for the closest is off by far more.
FLOAT32 = 2e-6

SCENES = [
    SceneCheck(
        "L09",
        "overlapping_balls",
        "the closest hit in the hierarchy",
        "two balls passing through each other, one mesh of 160 triangles",
        analytic=(
            Analytic(
                36,
                25,
                "depth",
                (closest_mesh_hit("overlapping_balls", 36, 25),),
                FLOAT32,
                "the nearest of all 160 triangles along the pixel's ray, each tested, "
                "where the balls' boxes overlap",
            ),
            Analytic(
                40,
                30,
                "depth",
                (closest_mesh_hit("overlapping_balls", 40, 30),),
                FLOAT32,
                "the same along the axis",
            ),
        ),
        hint="a leaf's hit shrinks the range; keep visiting every box that starts before the "
        "closest hit so far: boxes overlap, so the first leaf with a hit need not hold the "
        "nearest",
    ),
    SceneCheck(
        "L09",
        "crossed_sheets",
        "the closest hit in the hierarchy",
        "two sheets of triangles crossing along a line, one mesh",
        visibility=HIDDEN,
        analytic=(
            Analytic(
                31,
                20,
                "depth",
                (closest_mesh_hit("crossed_sheets", 31, 20),),
                FLOAT32,
                "the nearest of all 144 triangles along the pixel's ray, each tested",
            ),
        ),
        hint="in a leaf, test every triangle and keep the nearest, the range shrunk to it",
    ),
    SceneCheck(
        "L09",
        "bounding_box",
        "the bounding box of the object",
        "a cap of a ball searched through the bounding box of the mesh, seen from above and aside",
        visibility=HIDDEN,
        hint="the slab test of the mesh's box: for a negative component of d the near plane is "
        "the max, and the box counts only where its interval meets the ray's range",
    ),
]
