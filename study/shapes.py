"""The primitives a study case is made of, as the scene language describes them: the same
numbers go to every method and to the ground truth (study/truth.py), nothing else."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

Vec = tuple[float, float, float]


def _scale(v: Vec, s: float) -> Vec:
    return (v[0] * s, v[1] * s, v[2] * s)


@dataclass(frozen=True)
class Sphere:
    center: Vec
    radius: float
    kind = "sphere"

    def scene_object(self) -> dict[str, Any]:
        return {"type": "sphere", "center": list(self.center), "radius": self.radius}

    def scaled(self, s: float) -> Sphere:
        return Sphere(_scale(self.center, s), self.radius * s)


@dataclass(frozen=True)
class Plane:
    point: Vec
    normal: Vec  # as described; the core normalises it, the truth need not (same plane)
    kind = "plane"

    def scene_object(self) -> dict[str, Any]:
        return {"type": "plane", "point": list(self.point), "normal": list(self.normal)}

    def scaled(self, s: float) -> Plane:
        return Plane(_scale(self.point, s), self.normal)


@dataclass(frozen=True)
class Triangle:
    a: Vec
    b: Vec
    c: Vec
    kind = "triangle"

    def scene_object(self) -> dict[str, Any]:
        return {"type": "triangle", "vertices": [list(self.a), list(self.b), list(self.c)]}

    def scaled(self, s: float) -> Triangle:
        return Triangle(_scale(self.a, s), _scale(self.b, s), _scale(self.c, s))


@dataclass(frozen=True)
class Box:
    lo: Vec
    hi: Vec
    kind = "box"

    def scene_object(self) -> dict[str, Any]:
        return {"type": "box", "min": list(self.lo), "max": list(self.hi)}

    def scaled(self, s: float) -> Box:
        return Box(_scale(self.lo, s), _scale(self.hi, s))


Shape = Sphere | Plane | Triangle | Box
