"""The solution markers in tracer/cpp/: which lines a student writes, for which lesson.

Syntax (one region is the whole body of one function, so that a stub can replace it)::

    inline double lambert_term(const Vec3 &N, const Vec3 &L) {
        // BEGIN SOLUTION L04
        // PROMPT: The slide's intensity factor N.L for a unit normal N and unit direction L
        // PROMPT: to the light.
        return dot(N, L);
        // END SOLUTION
    }

- ``// BEGIN SOLUTION Lnn`` opens a region of lesson Lnn (one of lessons.catalog.LESSONS); it
  must be the first line of a function's body, right after the line that opens the body with
  ``{``. The function's name (and its parameters, which the stub passes on so that none is
  unused) is read from the signature above.
- ``// PROMPT: text`` lines, right after BEGIN and optional, are the prompt a student tree
  shows in place of the solution (several lines join into one paragraph).
- ``// GIVEN: code`` lines, right after the prompt and optional, are what a tree of an
  earlier lesson holds in the region instead of a stub: a plain version that works, which this
  lesson refines (lesson L13 makes the roots and the ray's offset robust; until then every tree
  has the textbook quadratic and a fixed epsilon, so that its spheres render).
- ``// END SOLUTION`` closes the region; the next line must close the function (``}``).
- Regions do not nest. A lesson whose code is spread over several functions has several
  regions.

A composite region (code that reveals several lessons) is marked with the latest lesson it
reveals, so that every student tree up to that lesson hides it. The packet tracer
(tracer/cpp/12_packet.h) restates the one-ray solution lane by lane: its regions are copies
(Region.is_copy), hidden like the solution they copy but not part of any exercise.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

BEGIN = re.compile(r"^(?P<indent>\s*)//\s*BEGIN SOLUTION\b\s*(?P<lesson>\S*)\s*(?P<rest>.*)$")
END = re.compile(r"^\s*//\s*END SOLUTION\b\s*(?P<rest>.*)$")
PROMPT = re.compile(r"^\s*//\s*PROMPT:\s?(?P<text>.*)$")
GIVEN = re.compile(r"^\s*//\s*GIVEN:\s?(?P<code>.*)$")
# Any line that mentions a marker word: a misspelt marker must not pass as a comment.
# (a comment line that starts with BEGIN or END, or with a word before SOLUTION, or that says
# begin/end solution in any case)
MENTION = re.compile(
    r"^\s*//\s*(?:BEGIN|END)\b|^\s*//\s*\w+\s+SOLUTION\b|^\s*//.*\b(?i:begin|end)\s+(?i:solution)\b"
)
LESSON_ID = re.compile(r"^L\d\d$")
# Files whose regions copy a solution written elsewhere (the packet tracer's lanes).
# (21_wide_bvh.h: the meshes' slab and triangle tests, four lanes at a time; 22_mesh_packets.h:
# the same tests and primary rays for packets of eight rays.)
COPIES = frozenset({"12_packet.h", "21_wide_bvh.h", "22_mesh_packets.h"})


class MarkerError(ValueError):
    """Unbalanced, nested, misplaced or unknown markers: the message names file:line."""


@dataclass(frozen=True)
class Region:
    """The solution of one function of one lesson. Line numbers are 1-based; ``begin`` is the
    BEGIN line, ``end`` the END line."""

    file: str  # the header's name, e.g. "10_classic.h"
    lesson: str  # "L04"
    function: str  # "lambert_term"
    parameters: tuple[str, ...]  # the parameter names, in order
    begin: int
    end: int
    indent: str
    prompt: str  # the PROMPT lines joined, "" when none
    body: tuple[str, ...]  # the solution's lines (between the prompt or the given code and END)
    given: tuple[str, ...] = ()  # the GIVEN code, as lines of the body (indented), or ()

    @property
    def is_copy(self) -> bool:
        """A copy of a solution, not an exercise (see the module's docstring)."""
        return self.file in COPIES

    @property
    def key(self) -> tuple[str, str, str]:
        return (self.file, self.lesson, self.function)


def _signature(lines: list[str], brace: int) -> str:
    """The function signature that ends at line index `brace` (which ends with '{'): the lines
    back to the one that starts it (a line beginning at column 0 with a declaration)."""
    start = brace
    while (
        start > 0
        and lines[start][:1].isspace()
        and not lines[start - 1].lstrip().startswith("//")
        and not lines[start - 1].rstrip().endswith((";", "{", "}"))
    ):
        start -= 1
    return " ".join(line.strip() for line in lines[start : brace + 1])


def _split_top_level(text: str) -> list[str]:
    parts, depth, current = [], 0, ""
    for ch in text:
        if ch in "(<[{":
            depth += 1
        elif ch in ")>]}":
            depth -= 1
        if ch == "," and depth == 0:
            parts.append(current)
            current = ""
        else:
            current += ch
    if current.strip():
        parts.append(current)
    return parts


def parse_signature(signature: str) -> tuple[str, tuple[str, ...]]:
    """(function name, parameter names) of a C++ function signature such as
    ``inline double lambert_term(const Vec3 &N, const Vec3 &L) {``."""
    match = re.search(r"(\w+)\s*\(", signature)
    if match is None:
        raise ValueError(f"no function name in {signature!r}")
    depth, i = 1, match.end()
    while depth and i < len(signature):
        depth += {"(": 1, ")": -1}.get(signature[i], 0)
        i += 1
    inner = signature[match.end() : i - 1]
    names = []
    for parameter in _split_top_level(inner):
        declarator = parameter.split("=", 1)[0]
        found = re.findall(r"\w+", declarator)
        if found:
            names.append(found[-1])
    return match.group(1), tuple(names)


def parse(text: str, file: str, known_lessons: set[str] | None = None) -> list[Region]:
    """The regions of one file's text; MarkerError names `file`:line for every fault."""
    if known_lessons is None:
        from lessons.catalog import LESSON_IDS

        known_lessons = set(LESSON_IDS)
    lines = text.split("\n")
    regions: list[Region] = []
    open_at: int | None = None
    lesson = indent = ""
    for i, line in enumerate(lines):
        where = f"{file}:{i + 1}"
        begin, end = BEGIN.match(line), END.match(line)
        if begin:
            if open_at is not None:
                raise MarkerError(
                    f"{where}: BEGIN SOLUTION inside the region opened at line {open_at + 1} "
                    "(regions do not nest; close it with // END SOLUTION first)"
                )
            lesson = begin.group("lesson")
            if not LESSON_ID.match(lesson) or lesson not in known_lessons:
                from lessons.catalog import suggest_lesson

                hint = suggest_lesson(lesson, known_lessons)
                raise MarkerError(
                    f"{where}: unknown lesson {lesson!r} after BEGIN SOLUTION "
                    f"(expected one of L01..L{len(known_lessons):02d}){hint}"
                )
            if begin.group("rest"):
                raise MarkerError(f"{where}: unexpected text after BEGIN SOLUTION {lesson}")
            if i == 0 or not lines[i - 1].rstrip().endswith("{"):
                raise MarkerError(
                    f"{where}: BEGIN SOLUTION must be the first line of a function body "
                    "(the line before it must open the body with '{')"
                )
            open_at, indent = i, begin.group("indent")
        elif end:
            if open_at is None:
                raise MarkerError(f"{where}: END SOLUTION without a BEGIN SOLUTION before it")
            if end.group("rest"):
                raise MarkerError(f"{where}: unexpected text after END SOLUTION")
            if i + 1 >= len(lines) or lines[i + 1].strip() != "}":
                raise MarkerError(
                    f"{where}: END SOLUTION must be the last line of a function body "
                    "(the next line must be the function's closing '}')"
                )
            prompt, j = [], open_at + 1
            while j < i and (p := PROMPT.match(lines[j])):
                prompt.append(p.group("text").strip())
                j += 1
            given = []
            while j < i and (g := GIVEN.match(lines[j])):
                given.append(indent + g.group("code"))
                j += 1
            stray = next(
                (k for k in range(j, i) if GIVEN.match(lines[k]) or PROMPT.match(lines[k])), None
            )
            if stray is not None:
                raise MarkerError(
                    f"{file}:{stray + 1}: a PROMPT or GIVEN line inside the solution (they come "
                    "right after BEGIN SOLUTION: the prompt, then the given code)"
                )
            try:
                function, parameters = parse_signature(_signature(lines, open_at - 1))
            except ValueError as error:
                raise MarkerError(f"{file}:{open_at + 1}: {error}") from None
            regions.append(
                Region(
                    file=file,
                    lesson=lesson,
                    function=function,
                    parameters=parameters,
                    begin=open_at + 1,
                    end=i + 1,
                    indent=indent,
                    prompt=" ".join(prompt),
                    body=tuple(lines[j:i]),
                    given=tuple(given),
                )
            )
            open_at = None
        elif open_at is None and GIVEN.match(line):
            raise MarkerError(f"{where}: a GIVEN line outside a solution region")
        elif MENTION.search(line):
            raise MarkerError(
                f"{where}: malformed marker {line.strip()!r} (expected '// BEGIN SOLUTION Lnn' "
                "or '// END SOLUTION')"
            )
    if open_at is not None:
        raise MarkerError(
            f"{file}:{open_at + 1}: BEGIN SOLUTION {lesson} is never closed by // END SOLUTION"
        )
    seen: dict[tuple[str, str, str], Region] = {}
    for region in regions:
        if region.key in seen:
            raise MarkerError(
                f"{file}:{region.begin}: a second region of {region.lesson} in "
                f"{region.function}() (the first is at line {seen[region.key].begin})"
            )
        seen[region.key] = region
    return regions


def parse_file(path: Path) -> list[Region]:
    return parse(path.read_text(), path.name)


def find_regions(directory: Path) -> list[Region]:
    """Every region of every header and source of a directory (tracer/cpp/), in file order."""
    regions: list[Region] = []
    for path in sorted([*directory.glob("*.h"), *directory.glob("*.cpp")]):
        regions.extend(parse_file(path))
    return regions


def regions_by_lesson(directory: Path) -> dict[str, list[Region]]:
    result: dict[str, list[Region]] = {}
    for region in find_regions(directory):
        result.setdefault(region.lesson, []).append(region)
    return result
