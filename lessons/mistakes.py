"""Known-wrong versions of the solution: classic student mistakes, each a small edit of one
solution region, kept as data in the lesson's folder (lessons/Lnn_name/mistakes/*.json):

    {"description": "...", "concept": "the concept whose check must catch it",
     "file": "05_sphere.h", "function": "sphere_t", "old": "text in the region", "new": "..."}

write_mistake() writes a submission holding the edited file, after checking that the edit
changed the region (and only it).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from lessons.catalog import get_lesson
from lessons.markers import parse
from lessons.student import CORE


class MistakeError(ValueError):
    """A mistake whose edit does not apply to its region."""


@dataclass(frozen=True)
class Mistake:
    lesson: str
    name: str
    description: str
    concept: str
    file: str
    function: str
    old: str
    new: str


def mistakes(lesson: str) -> list[Mistake]:
    folder = get_lesson(lesson).folder / "mistakes"
    found = []
    for path in sorted(folder.glob("*.json")):
        data = json.loads(path.read_text())
        found.append(Mistake(lesson=lesson, name=path.stem, **data))
    return found


def mutated_text(mistake: Mistake, core: Path = CORE) -> str:
    """The core file with the mistake's edit made inside its region; MistakeError when the
    edit's old text is not exactly once in the region or the region did not change."""
    text = (core / mistake.file).read_text()
    regions = [
        r
        for r in parse(text, mistake.file)
        if r.function == mistake.function and r.lesson == mistake.lesson and not r.is_copy
    ]
    if len(regions) != 1:
        raise MistakeError(
            f"{mistake.name}: no single region of {mistake.function}() in {mistake.file}"
        )
    region = regions[0]
    lines = text.split("\n")
    body = "\n".join(lines[region.begin : region.end - 1])
    if body.count(mistake.old) != 1:
        raise MistakeError(f"{mistake.name}: its 'old' text is not once in {mistake.function}()")
    edited = body.replace(mistake.old, mistake.new)
    if edited == body:
        raise MistakeError(f"{mistake.name}: the edit changes nothing")
    return "\n".join([*lines[: region.begin], edited, *lines[region.end - 1 :]])


def write_mistake(mistake: Mistake, out: Path, core: Path = CORE) -> Path:
    """A submission directory `out` holding every core file with a region of the mistake's
    lesson (the solution's), the mutated one edited; returns the mutated file."""
    out.mkdir(parents=True, exist_ok=True)
    for path in sorted([*core.glob("*.h"), *core.glob("*.cpp")]):
        if any(r.lesson == mistake.lesson for r in parse(path.read_text(), path.name)):
            (out / path.name).write_text(path.read_text())
    target = out / mistake.file
    target.write_text(mutated_text(mistake, core))
    return target
