"""A student's starting tree for one lesson (``rtlab lesson student Lnn --out DIR``).

The tree is tracer/cpp/ in which the regions (lessons/markers.py) of lesson nn and of every
later lesson are replaced by their prompt and a stub; earlier lessons keep the solution, or
with ``from_dir`` the student's own code of those regions. A stub is one call,

    not_implemented("L04", "lambert_term", N, L);

declared in cpp/not_implemented.h (copied from lessons/cpp/): it throws rt::NotImplemented,
so a stub never returns a value that could pass for an answer, and the marker lines stay
around it so that the student writes between them and the grader finds what was written.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from lessons.catalog import get_lesson, later_or_equal
from lessons.markers import MarkerError, Region, parse

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
CORE = ROOT / "tracer" / "cpp"
SUPPORT = HERE / "cpp" / "not_implemented.h"
STUB_HEADER = SUPPORT.name

# The flags of CMakeLists.txt's target_compile_options that change a diagnostic, and -Werror:
# the tree must build warning-free, as the core does.
FLAGS = "-std=c++17 -Wall -Wextra -Werror -ffp-contract=off -fno-math-errno -Wno-psabi"


class StudentTreeError(ValueError):
    """The tree cannot be written (the output exists, a --from file has bad markers)."""


@dataclass
class TreeReport:
    out: Path
    lesson: str
    stubbed: list[Region] = field(default_factory=list)
    kept: list[Region] = field(default_factory=list)  # the solution, earlier lessons
    carried: list[Region] = field(default_factory=list)  # the student's own, from --from
    given: list[Region] = field(default_factory=list)  # later lessons' plain versions (GIVEN)


def stub_lines(region: Region) -> list[str]:
    """What replaces a region's body in a student tree: the prompt and one stub call."""
    args = "".join(f", {p}" for p in region.parameters)
    lines = [f"{region.indent}// BEGIN SOLUTION {region.lesson}"]
    lines += [f"{region.indent}// PROMPT: {line}" for line in _wrap(region.prompt, region.indent)]
    lines.append(f'{region.indent}not_implemented("{region.lesson}", "{region.function}"{args});')
    lines.append(f"{region.indent}// END SOLUTION")
    return lines


def given_lines(region: Region) -> list[str]:
    """What replaces a region of a later lesson that refines a plain version (GIVEN lines) in
    a tree of an earlier lesson: the prompt and the given code, which works until that lesson
    refines it."""
    lines = [f"{region.indent}// BEGIN SOLUTION {region.lesson}"]
    lines += [f"{region.indent}// PROMPT: {line}" for line in _wrap(region.prompt, region.indent)]
    lines += list(region.given)
    lines.append(f"{region.indent}// END SOLUTION")
    return lines


def is_given(own: Region, solution: Region) -> bool:
    """Whether a tree's region holds the course's given code (GIVEN lines) of `solution`'s
    region, not the student's."""
    if not solution.given:
        return False
    given = Region(**{**own.__dict__, "body": solution.given})
    return solution_lines(own) == solution_lines(given)


def _wrap(text: str, indent: str) -> list[str]:
    import textwrap

    return textwrap.wrap(text, 100 - len(indent) - len("// PROMPT: ")) if text else []


def _with_include(text: str) -> str:
    """`text` with #include "not_implemented.h" after its last project include."""
    lines = text.split("\n")
    last = max(
        (i for i, line in enumerate(lines) if line.startswith(("#include", "#pragma once"))),
        default=-1,
    )
    lines.insert(last + 1, f'#include "{STUB_HEADER}"')
    return "\n".join(lines)


def _submitted_files(directory: Path) -> dict[str, Path]:
    """The C++ files of a submission or an earlier tree: DIR/cpp/*.h or DIR/*.h."""
    found: dict[str, Path] = {}
    for base in (directory, directory / "cpp"):
        for path in sorted([*base.glob("*.h"), *base.glob("*.cpp")]):
            found[path.name] = path
    return found


def lesson_file_text(
    name: str,
    text: str,
    lesson: str,
    earlier: dict[tuple[str, str, str], Region] | None,
    report: TreeReport,
) -> str:
    """One core file as the tree for `lesson` holds it."""
    regions = parse(text, name)
    if not regions:
        return text
    hide = later_or_equal(lesson)
    lines = text.split("\n")
    stubbed = False
    # From the last region to the first, so earlier line numbers stay valid.
    for region in reversed(regions):
        body_start = region.begin  # index of the first line after BEGIN (0-based)
        if region.lesson in hide and region.lesson != lesson and region.given:
            lines[region.begin - 1 : region.end] = given_lines(region)
            report.given.append(region)
        elif region.lesson in hide:
            lines[region.begin - 1 : region.end] = stub_lines(region)
            report.stubbed.append(region)
            stubbed = True
        elif earlier is not None and region.key in earlier:
            own = earlier[region.key]
            prompt_lines = region.end - 1 - body_start - len(region.body)
            lines[body_start + prompt_lines : region.end - 1] = list(own.body)
            report.carried.append(own)
            stubbed = stubbed or any("not_implemented(" in line for line in own.body)
        else:
            report.kept.append(region)
    result = "\n".join(lines)
    return _with_include(result) if stubbed else result


def _earlier_regions(from_dir: Path) -> dict[tuple[str, str, str], Region]:
    if not from_dir.is_dir():
        raise StudentTreeError(f"{from_dir}: --from expects the directory of an earlier tree")
    regions: dict[tuple[str, str, str], Region] = {}
    for name, path in _submitted_files(from_dir).items():
        try:
            for region in parse(path.read_text(errors="replace"), str(path)):
                regions[(name, region.lesson, region.function)] = region
        except MarkerError as error:
            raise StudentTreeError(f"--from: {error}") from None
    return regions


MAKEFILE = """\
# `make`: every header compiles on its own with the core's warning flags.
# `make check`: the public checks of lesson {id} on your code (rtlab lesson grade --public).
CXX ?= c++
FLAGS := {flags}
HEADERS := $(sort $(wildcard cpp/*.h))
RTLAB ?= rtlab

.PHONY: all build check
all: build
build:
\t@for h in $(HEADERS); do \\
\t  echo '#include "'$$(basename $$h)'"' | $(CXX) $(FLAGS) -Icpp -fsyntax-only -x c++ - \\
\t    || {{ echo "make: $$h does not compile" >&2; exit 1; }}; \\
\tdone; echo "make: every header of cpp/ compiles"
check: build
\t$(RTLAB) lesson grade . --lesson {id} --public --json check/results.json
"""

README = """\
# {id}: {title}

Your starting tree for lesson {id} of the course (slide "{slide}"). You write: {writes}.
The lesson's text is `lesson.md`.

## What is here

`cpp/` is the course's ray tracer, one header per idea of the lecture. The functions you write
hold a stub between two marker lines:

    // BEGIN SOLUTION {id}
    // PROMPT: what the function must do
    not_implemented("{id}", "the_function", ...);
    // END SOLUTION

Replace the stub with your code, between the markers (keep the two marker lines: the grader
finds your code by them). Until then calling the function reports "not implemented" with its
lesson and name. Functions of later lessons are stubbed too; earlier lessons hold
{earlier}.

## Build

    make        # every header compiles on its own, warning-free (-Wall -Wextra -Werror)

## Check yourself

    make check  # the public checks of {id}: rtlab lesson grade . --lesson {id} --public

It builds your code in a sandbox and runs the lesson's public checks: probes of your functions
(the inputs, what was expected, what came) and small scenes compared with POV-Ray's and
Mitsuba's images (where the pixels differ, and a heat map in `check/`). Its first line names the
concept that is wrong. The final grade adds hidden variants (other values, other scenes) of the
same checks, so code that passes for the right reason passes them too.

## Hand in

The files of `cpp/` you edited (any subset; their names as they are here). The grader lays them
over the course's own core, builds it and checks the concepts of lesson {id}:
{concepts}
"""


def write_student_tree(
    lesson: str, out: Path, from_dir: Path | None = None, core: Path = CORE
) -> TreeReport:
    """Write the tree for `lesson` to `out` (which must not exist or be empty), atomically:
    it is built in a temporary directory beside `out` and renamed into place, so a failure
    leaves no half tree."""
    info = get_lesson(lesson)
    out = Path(out)
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise StudentTreeError(f"{out}: exists and is not empty; choose a new --out directory")
    earlier = _earlier_regions(Path(from_dir)) if from_dir is not None else None
    report = TreeReport(out=out, lesson=lesson)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
    try:
        (tmp / "cpp").mkdir()
        for path in sorted([*core.glob("*.h"), *core.glob("*.cpp")]):
            text = lesson_file_text(path.name, path.read_text(), lesson, earlier, report)
            (tmp / "cpp" / path.name).write_text(text)
        shutil.copyfile(SUPPORT, tmp / "cpp" / STUB_HEADER)
        if info.text_path.exists():
            shutil.copyfile(info.text_path, tmp / "lesson.md")
        (tmp / "Makefile").write_text(MAKEFILE.format(flags=FLAGS, id=info.id))
        earlier_text = (
            "your own code, carried from " + str(from_dir)
            if from_dir is not None
            else "the course's solution"
        )
        concepts = "\n".join(f"- {c}" for c in info.concepts)
        (tmp / "README.md").write_text(
            README.format(
                id=info.id,
                title=info.title,
                slide=info.slide,
                writes=info.writes,
                earlier=earlier_text,
                concepts=concepts,
            )
        )
        if out.exists():
            out.rmdir()  # empty (checked above)
        os.replace(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return report


def solution_lines(region: Region) -> list[str]:
    """The code lines of a region's solution (stripped, comments and blank lines left out)."""
    return [
        line.strip() for line in region.body if line.strip() and not line.strip().startswith("//")
    ]
