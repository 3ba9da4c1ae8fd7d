"""Failing rays frozen as regression tests (issue 11, part 5: "the rays that fail, saved as hex
floats, and frozen as regression tests"). ``freeze`` picks representative rays from a run's
failures.json (per family, method and metric, a few from different knob values) and writes
them to tests/study/frozen/, a file per family named after it; ``failing_metrics`` runs one
frozen ray again through the same metric (study/metrics.py) on a one-ray case, for rtlab and
for the method that failed, so tests/study/test_frozen.py can hold both: rtlab gets it right,
and the failure is still reproduced (the ray is still a stiff one).

Origins, directions, spawned directions and lights are hex floats; a shape's numbers are JSON
numbers as failures.json has them (Python writes the shortest repr that reads back to the same
double, so they are exact too)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from study.shapes import Box, Mesh, Plane, Shape, Sphere, Triangle

#: Rays kept per family, method and metric (each from another knob value where there are).
PER = 2
#: The metrics a frozen ray is replayed by, per protocol (study/metrics.py's failing indices).
METRICS = {"decision": ("wrong_decisions", "leaks", "bound_violations"),
           "spawn": ("self_hits", "missed_far"), "shadow": ("false_occlusions",),
           "scale": ("scale_mismatches",)}  # fmt: skip


class FreezeError(ValueError):
    """Bad input to freeze (no such failures.json, or not one)."""


def _vec(v: list[float]) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))


def shape_from(obj: dict[str, Any]) -> Shape:
    """The study's shape from a failure's ``shape`` (its kind and scene_object())."""
    kind = obj["kind"]
    if kind == "sphere":
        return Sphere(_vec(obj["center"]), float(obj["radius"]))
    if kind == "plane":
        return Plane(_vec(obj["point"]), _vec(obj["normal"]))
    if kind == "triangle":
        a, b, c = (_vec(v) for v in obj["vertices"])
        return Triangle(a, b, c)
    if kind == "box":
        return Box(_vec(obj["min"]), _vec(obj["max"]))
    if kind == "mesh":
        return Mesh(tuple(_vec(v) for v in obj["vertices"]),
                    tuple((int(f[0]), int(f[1]), int(f[2])) for f in obj["faces"]))  # fmt: skip
    if kind in ("placed-cylinder", "placed-elliptic-cylinder", "placed-torus"):
        return _placed_from(obj)
    raise FreezeError(f"shape.kind: {kind!r} is not a shape the study has")


def _placed_from(obj: dict[str, Any]) -> Shape:
    """A cylinder or torus under a transform (study/shapes.py PlacedCylinder, PlacedTorus): its
    own coordinates' numbers and the scene language's transform, as scene_object() wrote them."""
    from study.shapes import PlacedCylinder, PlacedTorus, Placement

    tf = obj["transform"]
    placement = Placement(_vec(tf["scale"]), _vec(tf["rotate"]["axis"]),
                          float(tf["rotate"]["degrees"]), _vec(tf["translate"]))  # fmt: skip
    if obj["kind"] == "placed-torus":
        return PlacedTorus(float(obj["major_radius"]), float(obj["minor_radius"]), placement)  # type: ignore[return-value]
    if any(float(x) != 0 for x in obj["base"]) or any(float(x) != 0 for x in obj["top"][:2]):
        raise FreezeError(f"shape: {obj['kind']} expected base 0 and top on +z, got {obj}")
    return PlacedCylinder(float(obj["radius"]), float(obj["top"][2]), placement)  # type: ignore[return-value]


def freeze(failures: list[dict[str, Any]], per: int = PER) -> dict[str, list[dict[str, Any]]]:
    """Representative failing rays per family: for each method (rtlab's own failures are bugs
    to fix, not rays to freeze) and metric, up to ``per`` rays, the first of each knob value
    in the order failures.json lists them. Entries without a protocol (failures.json from
    before it recorded one) are left out: they cannot be replayed."""
    chosen: dict[tuple[str, str, str], list[dict[str, Any]]] = {}
    for f in failures:
        if f["method"] == "rtlab" or "protocol" not in f:
            continue
        if f["metric"] not in METRICS.get(f["protocol"], ()):
            continue
        key = (f["family"], f["method"], f["metric"])
        mine = chosen.setdefault(key, [])
        if len(mine) < per and all(x["knob_value"] != f["knob_value"] for x in mine):
            mine.append(f)
    out: dict[str, list[dict[str, Any]]] = {}
    for (family, _, _), entries in chosen.items():
        out.setdefault(family, []).extend(entries)
    return out


def write_frozen(failures_json: Path, out: Path, per: int = PER) -> dict[str, int]:
    """Freeze failures_json's rays into out/FAMILY.json (each written atomically); returns the
    count per family."""
    from tracer.image import atomic_path

    try:
        failures = json.loads(failures_json.read_text())
    except FileNotFoundError:
        raise FreezeError(f"--from: {failures_json}: no such file; expected the failures.json "
                          "of `rtlab study stiff`") from None  # fmt: skip
    except json.JSONDecodeError as error:
        raise FreezeError(f"--from: {failures_json}: not JSON ({error})") from None
    if not isinstance(failures, list):
        raise FreezeError(f"--from: {failures_json}: expected a list of failing rays")
    frozen = freeze(failures, per)
    out.mkdir(parents=True, exist_ok=True)
    for family, entries in sorted(frozen.items()):
        with atomic_path(out / f"{family}.json") as tmp:
            tmp.write_text(json.dumps(entries, indent=1, allow_nan=False) + "\n")
    return {family: len(entries) for family, entries in sorted(frozen.items())}


def _hex3(v: list[str]) -> np.ndarray:
    return np.array([[float.fromhex(x) for x in v]])


def case_of(entry: dict[str, Any]) -> Any:
    """The one-ray Case of a frozen entry, as its family generated it."""
    from study.families import Case

    return Case(
        shape_from(entry["shape"]),
        _hex3(entry["origin"]),
        _hex3(entry["direction"]),
        protocol=entry["protocol"],
        leave=_hex3(entry["leave"]) if "leave" in entry else None,
        outward=np.array([entry["outward"]]) if "outward" in entry else None,
        light=tuple(float.fromhex(x) for x in entry["light"]) if "light" in entry else None,  # type: ignore[arg-type]
        scale_k=int(entry.get("scale_k", 0)),
    )


def failing_metrics(entry: dict[str, Any], method: Any) -> set[str]:
    """The metrics by which ``method`` fails the frozen ray now (empty: it gets it right); and
    for a first-hit ray, "undecidable" if the truth no longer decides it."""
    from study import metrics, truth

    case = case_of(entry)
    if case.protocol == "decision":
        tru = truth.truth(case.shape, case.origins, case.directions)
        result = metrics.decision(case, method, tru)
        extra = {"undecidable"} if tru.undecidable[0] else set()
    elif case.protocol == "spawn":
        result, extra = metrics.spawn(case, method), set()
    elif case.protocol == "shadow":
        result = metrics.shadow(case, method)
        extra = {"undecidable"} if result[1] else set()
    else:
        result, extra = metrics.scale(case, method), set()
    return {m for m, idx in result[2].items() if 0 in idx} | extra
