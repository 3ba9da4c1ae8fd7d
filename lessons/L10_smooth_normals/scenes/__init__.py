"""L10's scene checks (lessons/scene_checks.py): the icosahedron, a mesh as coarse as a sphere's
can be, smooth-shaded (Gouraud: its 20 facets must not show), and seen straight at a face's
centroid, where the blend of the vertex normals is shortest (it must be made unit again).

Both references interpolate the same vertex normals (POV-Ray's mesh2 normal_vectors, Mitsuba's
PLY vertex normals: converters/). The analytic values are computed here in double precision:
by the icosahedron's symmetry each vertex normal is the unit vector to the vertex, and the hit
and its barycentric coordinates follow from the ray and the faces (Moeller-Trumbore written out
below), never from the tracer.

Both scenes are the renormalisation's concept: a lit smooth mesh runs the whole smooth normal,
the blend and then its renormalisation, and a normal left short darkens it as much as a wrong
weight changes it. checks.py's DEPENDS lets the renormalisation's checks follow from the
weights' (its probes run the blend too): a wrong weight is named by the weights' probes, the
scenes listed as following from it; a normal left short fails the scenes and the
renormalisation's probes alone. Were a scene the weights', a short normal would fail it and be
named a wrong weight (rtlab lesson check L10 caught that)."""

import math

from lessons.probe import HIDDEN, Vec
from lessons.scene_checks import Analytic, SceneCheck, cross, dot, sub, unit

PHI = (1 + math.sqrt(5)) / 2
VERTICES: list[Vec] = [
    (-1, PHI, 0), (1, PHI, 0), (-1, -PHI, 0), (1, -PHI, 0), (0, -1, PHI), (0, 1, PHI),
    (0, -1, -PHI), (0, 1, -PHI), (PHI, 0, -1), (PHI, 0, 1), (-PHI, 0, -1), (-PHI, 0, 1),
]  # fmt: skip
FACES = [
    (0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
    (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9),
    (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1),
]  # fmt: skip


def ray(eye: Vec, look_at: Vec, up: Vec, fov_y: float, width: int, height: int, i: int,
        j: int) -> Vec:  # fmt: skip
    """The unit direction through the centre of pixel (i, j) (slide "Perspective Ray Tracing")."""
    forward = unit(sub(look_at, eye))
    right = unit(cross(forward, up))
    true_up = cross(right, forward)
    h = 2 * math.tan(math.radians(fov_y) / 2)
    w = h * width / height
    x, y = (i + 0.5) / width - 0.5, 0.5 - (j + 0.5) / height
    return unit(
        tuple(f + x * w * r + y * h * u for f, r, u in zip(forward, right, true_up, strict=True))
    )  # type: ignore[return-value]


def smooth_normal(o: Vec, d: Vec) -> tuple[float, Vec, Vec]:
    """The nearest hit of the ray on the icosahedron: its t, the Gouraud normal (b0 n0 + b1 n1
    + b2 n2 made unit, n = the unit vector to each vertex) and the face normal."""
    best: tuple[float, Vec, Vec] | None = None
    for f in FACES:
        p0, p1, p2 = (VERTICES[k] for k in f)
        e1, e2 = sub(p1, p0), sub(p2, p0)
        q = cross(d, e2)
        det = dot(e1, q)
        s = sub(o, p0)
        b1 = dot(s, q) / det
        r = cross(s, e1)
        b2 = dot(d, r) / det
        t = dot(e2, r) / det
        if b1 < 0 or b2 < 0 or b1 + b2 > 1 or t <= 0 or (best and t >= best[0]):
            continue
        n0, n1, n2 = (unit(VERTICES[k]) for k in f)
        blend = tuple(
            (1 - b1 - b2) * a + b1 * b + b2 * c for a, b, c in zip(n0, n1, n2, strict=True)
        )
        best = (t, unit(blend), unit(cross(e1, e2)))  # type: ignore[arg-type]
    assert best is not None, "the ray misses the icosahedron"
    return best


# smooth_icosahedron: pixels (40, 30) (the axis) and (47, 24).
ICO = ((1.0, 1.5, 7.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 12.0, 81, 61)
ICO_CENTRE = smooth_normal(ICO[0], ray(*ICO, 40, 30))
ICO_OFF = smooth_normal(ICO[0], ray(*ICO, 47, 24))

# face_centre: the axis meets face (0, 11, 5) at its centroid (-1, 1, 1)(1 + phi) / 3; there
# the normal is (-1, 1, 1) / sqrt(3), the light on that line: N.L = 1, the colour 0.1 c + 0.8 c.
CENTROID_T = math.sqrt(3 * 16.0) - math.sqrt(3) * (1 + PHI) / 3
CENTROID_N = (-1 / math.sqrt(3), 1 / math.sqrt(3), 1 / math.sqrt(3))
CENTROID_COLOR = tuple(0.9 * c for c in (0.85, 0.7, 0.55))

# float32 output: half an ulp of a unit normal's components is 6e-8, of a colour below 1 the
# same, of a depth below 8 4.8e-7; the double arithmetic's roundings ~1e-15. 2e-6 holds them
# with room; what the checks separate is far larger: the face normal differs from the Gouraud
# normal at these pixels by over 0.05, a blend left unnormalised shades the centroid 0.79 as
# bright.
FLOAT32 = 2e-6

SCENES = [
    SceneCheck(
        "L10",
        "smooth_icosahedron",
        "Gouraud shading: the interpolated normal made unit length again",
        "the icosahedron (20 faces), smooth-shaded, lit from behind the eye",
        analytic=(
            Analytic(
                40,
                30,
                "normal",
                ICO_CENTRE[1],
                FLOAT32,
                "b0 n0 + b1 n1 + b2 n2 made unit, n the unit vectors to the hit face's "
                "vertices, b the hit's barycentric coordinates",
            ),
            Analytic(47, 24, "normal", ICO_OFF[1], FLOAT32, "the same at pixel (47, 24)"),
        ),
        hint="N = b0 n0 + b1 n1 + b2 n2 with b0 = 1 - b1 - b2, each weight with its own "
        "vertex (b1 with p1, b2 with p2), made unit length",
    ),
    SceneCheck(
        "L10",
        "face_centre",
        "Gouraud shading: the interpolated normal made unit length again",
        "the smooth icosahedron seen straight at a face's centroid, lit along the view",
        visibility=HIDDEN,
        analytic=(
            Analytic(
                40,
                30,
                "depth",
                (CENTROID_T,),
                FLOAT32,
                "|eye| - |centroid| = sqrt(48) - sqrt(3) (1 + phi) / 3",
            ),
            Analytic(
                40,
                30,
                "normal",
                CENTROID_N,
                FLOAT32,
                "the mean of the three unit vertex normals, made unit: (-1, 1, 1) / sqrt 3",
            ),
            Analytic(
                40,
                30,
                "color",
                CENTROID_COLOR,
                FLOAT32,
                "0.1 c + 0.8 N.L c with N.L = 1 (the light on the axis)",
            ),
        ),
        hint="a blend of unit normals is shorter than 1 between different normals: normalize "
        "it again",
    ),
]
