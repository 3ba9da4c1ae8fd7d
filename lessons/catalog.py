"""The course's lessons, in the lecture's order (the lecture: the slides the README names).

Each lesson names the slide it teaches, the concepts its checks check (in the lecture's words:
a failing check names one of these), and the functions a student writes, which are the
solution regions marked in tracer/cpp/ (lessons/markers.py).
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent


@dataclass(frozen=True)
class Lesson:
    id: str  # "L04"
    name: str  # the folder's name after the id: lessons/L04_lambert/
    title: str  # in the lecture's words
    slide: str  # the slide it teaches (its title as the lecture gives it)
    writes: str  # what the student writes
    concepts: tuple[str, ...]  # what its checks check, each named in the lecture's words

    @property
    def folder(self) -> Path:
        return HERE / f"{self.id}_{self.name}"

    @property
    def text_path(self) -> Path:
        return self.folder / "lesson.md"

    @property
    def number(self) -> int:
        return int(self.id[1:])


LESSONS: tuple[Lesson, ...] = (
    Lesson(
        "L01",
        "camera",
        "Rays and the camera: p = o + t d, primary rays through pixel centres",
        "What is a Ray?; Perspective Ray Tracing",
        "the camera's frame and primary rays",
        ("the ray p = o + t d", "the camera's frame", "primary rays through pixel centres"),
    ),
    Lesson(
        "L02",
        "sphere",
        "The sphere and its five cases",
        "Intersecting a Sphere",
        "ray/sphere: roots, nearest hit in range, the five cases",
        (
            "the roots of the quadratic",
            "the nearest hit in range",
            "the five cases: none, once, tangent, internal, twice",
        ),
    ),
    Lesson(
        "L03",
        "plane",
        "Implicit surfaces: the plane",
        "Implicit Surfaces",
        "ray/plane",
        ("the plane (p - a).n = 0", "a ray parallel to the plane", "the hit in range"),
    ),
    Lesson(
        "L04",
        "lambert",
        "Ambient and Lambert (N.L), coloured lights",
        "Light Reflection",
        "the ambient and diffuse terms, the normal facing the ray",
        (
            "ambient light",
            "diffuse (Lambertian) reflection N.L",
            "the direction to the light L",
            "the normal facing the ray",
            "coloured lights",
        ),
    ),
    Lesson(
        "L05",
        "shadows",
        "Shadow rays",
        "Interaction between Lights and Objects",
        "the shadow ray, its range, and where it starts",
        (
            "objects block light",
            "the shadow ray towards the light",
            "the shadow ray's range",
            "where the shadow ray starts",
        ),
    ),
    Lesson(
        "L06",
        "specular",
        "Specular: R = 2(N.L)N - L and the Phong highlight",
        "Light Reflection",
        "the mirror vector, the Phong term",
        ("the mirror vector R = 2(N.L)N - L", "the Phong highlight"),
    ),
    Lesson(
        "L07",
        "chain",
        "The reflection-coefficient chain: the simple ray tracing algorithm (Ex 25)",
        "Specular Reflected Light; Simple Ray Tracing Algorithm",
        "trace(): the chain, its stops",
        (
            "the colour of one hit: ambient, and N.L diffuse if not in shadow",
            "the reflection-coefficient chain",
            "stop when no intersection",
            "stop when coef << 1",
            "stop at the maximum number of bounces",
        ),
    ),
    Lesson(
        "L08",
        "box_triangle",
        "Boxes and triangles",
        "Intersecting a Complex Object",
        "the slab test, the watertight two-sided triangle",
        (
            "the axis-aligned box (slab test)",
            "the box's nearest hit in range",
            "the generic triangle",
            "the triangle seen from both sides",
            "the triangle's point and normal",
        ),
    ),
    Lesson(
        "L09",
        "mesh_bvh",
        "Meshes and bounding volumes (the bunny)",
        "Intersecting a Complex Object",
        "the bounding box, the hierarchy's closest hit",
        (
            "the bounding box of the object",
            "the closest hit in the hierarchy",
            "a ray that misses a box skips the triangles in it",
        ),
    ),
    Lesson(
        "L10",
        "smooth_normals",
        "Smooth normals (Gouraud)",
        "Intersecting a Complex Object",
        "interpolated vertex normals",
        (
            "Gouraud shading: the vertex normals weighted by the barycentric coordinates",
            "Gouraud shading: the interpolated normal made unit length again",
        ),
    ),
    Lesson(
        "L11",
        "stereo",
        "Stereoscopy",
        "Stereoscopy",
        "a stereo pair of cameras",
        (
            "the eye separation",
            "the parallel-axis asymmetric frustum",
            "parallax: none on the convergence plane, never vertical",
        ),
    ),
    Lesson(
        "L12",
        "cornell",
        "True global illumination: the Cornell box",
        "True Global Ray Tracing",
        "the path tracer's estimator: sampling, next-event estimation, MIS",
        (
            "light bounces many times: the cosine-weighted bounce",
            "each bounce attenuates light: Russian roulette",
            "next-event estimation: a point on the area light",
            "multiple importance sampling: the power heuristic",
        ),
    ),
    Lesson(
        "L13",
        "precision",
        "Precision: stiff and extreme cases",
        "Efficiency and Complexity",
        "the robust quadratic, self-intersection offsets",
        (
            "the robust quadratic: the discriminant without cancellation",
            "the robust quadratic: the root without cancellation",
            "stiff and extreme cases: far, tiny and grazing spheres",
            "self-intersection offsets: along the normal, by the error bound",
        ),
    ),
)

LESSON_IDS: tuple[str, ...] = tuple(lesson.id for lesson in LESSONS)
BY_ID: dict[str, Lesson] = {lesson.id: lesson for lesson in LESSONS}


class UnknownLessonError(KeyError):
    """A lesson id that is not in the catalogue; the message suggests the near spelling."""

    def __str__(self) -> str:
        return str(self.args[0])


def _normalise(text: str) -> str:
    """'l4', 'L4', 'L04', '4' and 'L04_lambert' all mean L04."""
    text = text.strip()
    head = text.split("_", 1)[0].upper().lstrip("L")
    return f"L{int(head):02d}" if head.isdigit() else text


def suggest_lesson(text: str, known: set[str] | tuple[str, ...] = LESSON_IDS) -> str:
    """' (did you mean L04?)' for a near spelling, else ''."""
    names = {**{i: i for i in known}}
    for lesson in LESSONS:
        if lesson.id in known:
            names[f"{lesson.id}_{lesson.name}"] = lesson.id
            names[lesson.name] = lesson.id
    candidate = _normalise(text)
    if candidate in known and candidate != text:
        return f" (did you mean {candidate}?)"
    close = difflib.get_close_matches(text, list(names), n=1, cutoff=0.6)
    return f" (did you mean {names[close[0]]}?)" if close else ""


def get_lesson(text: str) -> Lesson:
    """The lesson `text` names exactly (an id such as L04); UnknownLessonError otherwise."""
    if text in BY_ID:
        return BY_ID[text]
    raise UnknownLessonError(
        f"unknown lesson {text!r}{suggest_lesson(text)}; the lessons are "
        f"{LESSON_IDS[0]}..{LESSON_IDS[-1]} (rtlab lesson list)"
    )


def later_or_equal(lesson: str) -> set[str]:
    """The ids of lesson `lesson` and every later one: the regions a student tree stubs."""
    number = get_lesson(lesson).number
    return {i for i in LESSON_IDS if BY_ID[i].number >= number}
