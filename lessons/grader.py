"""The grader: ``lessons.grade(submission, lesson="L04")`` and ``rtlab lesson grade``.

Grading lesson nn lays only the submission's regions of lesson nn (found by the markers,
lessons/markers.py) over the solution, so that every other lesson stays the solution's and one
mistake is charged once. One probe program (lessons/cpp/probe_main.cpp) is built from that core
in a child process under limits (lessons/sandbox.py) and runs every probe of the lesson, each
in turn, printing what the student's functions return; the grader compares those values with
the ones the lesson's checks.py computed on its own. Student code is never imported here.

The result is in Gradescope's autograder format (results.json): top-level score,
execution_time, output (the diagnosis first: its first line names the broken concept in the
lecture's words), and tests[] with name, number, score, max_score, status, tags (the lesson id
and the concept), output (Markdown) and visibility. Each concept is worth CONCEPT_POINTS,
shared among its probes (partial credit per concept).
"""

from __future__ import annotations

import importlib
import json
import os
import re
import secrets
import time
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from lessons.catalog import BY_ID, get_lesson
from lessons.markers import MarkerError, Region, parse
from lessons.probe import Probe, fmt
from lessons.sandbox import (
    Build,
    Limits,
    build_extension,
    build_probe,
    run_limited,
    temporary_work,
)
from lessons.scene_checks import (
    ROOT,
    PathSceneCheck,
    Rendered,
    SceneCheck,
    Verdict,
    heat_map_path,
    judge,
    lesson_scenes,
    references,
    render_student,
)
from lessons.student import CORE, STUB_HEADER, _submitted_files, _with_include, is_given, stub_lines
from reference.metrics import heat_map

HERE = Path(__file__).resolve().parent
PROBE_MAIN = HERE / "cpp" / "probe_main.cpp"
PROBE_COMMON = HERE / "cpp" / "probe.h"
CONCEPT_POINTS = 10.0
# A probe is one call of a small function: microseconds. 2 s of CPU is a hang; 5 s of wall
# clock covers a loaded machine; 512 MiB and 64 KiB as the sandbox's defaults argue.
PROBE_LIMITS = Limits(cpu_s=2, wall_s=5.0)
# After this many probes that hung, the rest are not run (each hang costs its limit).
MAX_HANGS = 2


@dataclass
class TestResult:
    name: str
    lesson: str
    concept: str
    score: float
    max_score: float
    status: str  # "passed" or "failed"
    output: str  # Markdown
    visibility: str
    function: str = ""
    kind: str = "probe"  # probe, not_implemented, compile_error, crash, hang, flood, ...
    # For the feedback page (reports/feedback.py), in results.json's extra_data: a probe's
    # inputs and each value expected and got; a failing scene's images beside results.json.
    inputs: str = ""
    values: list[dict] = field(default_factory=list)  # label, expected, got, ok
    artifacts: dict[str, str] = field(default_factory=dict)  # role -> file name

    def extra_data(self) -> dict:
        extra: dict = {"kind": self.kind, "function": self.function}
        if self.inputs:
            extra["inputs"] = self.inputs
        if self.values:
            extra["values"] = self.values
        if self.artifacts:
            extra["artifacts"] = self.artifacts
        return extra

    def as_gradescope(self, number: str) -> dict:
        return {
            "name": self.name,
            "number": number,
            "score": round(self.score, 4),
            "max_score": round(self.max_score, 4),
            "status": self.status,
            "tags": [self.lesson, self.concept],
            "output": self.output,
            "output_format": "md",
            "visibility": self.visibility,
            "extra_data": self.extra_data(),
        }


@dataclass
class Result:
    lessons: list[str]
    tests: list[TestResult] = field(default_factory=list)
    diagnosis: str = ""
    notes: list[str] = field(default_factory=list)
    execution_time: float = 0.0

    @property
    def score(self) -> float:
        return round(sum(round(t.score, 4) for t in self.tests), 4)

    @property
    def max_score(self) -> float:
        return round(sum(round(t.max_score, 4) for t in self.tests), 4)

    def as_gradescope(self, timing: bool = True) -> dict:
        """Gradescope's results.json; without ``timing`` (a class graded in a batch) no
        execution_time, so that the file does not depend on the machine or the engine: the
        batch keeps the timings in a file of their own (grades/timings.json)."""
        output = "\n\n".join([self.diagnosis, *self.notes]).strip()
        return {
            "score": self.score,
            **({"execution_time": round(self.execution_time, 3)} if timing else {}),
            "output": output,
            "output_format": "md",
            "visibility": "visible",
            "stdout_visibility": "hidden",
            "tests": [t.as_gradescope(f"{i + 1}") for i, t in enumerate(self.tests)],
            # For the feedback and class pages (reports/): the diagnosis apart from the notes.
            "extra_data": {
                "lessons": self.lessons,
                "diagnosis": self.diagnosis,
                "notes": self.notes,
            },
        }

    def write(self, path: str | Path, timing: bool = True) -> None:
        """results.json, atomically (a temporary file beside it, renamed)."""
        from tracer.image import atomic_path

        with atomic_path(path) as tmp:
            tmp.write_text(json.dumps(self.as_gradescope(timing), indent=2) + "\n")


class NoChecksError(ValueError):
    """A lesson that has no checks yet."""


# --- the lessons' checks -----------------------------------------------------------------


def lessons_with_checks() -> list[str]:
    """The lessons with probes (checks.py) or scene checks (scenes/__init__.py)."""
    return [
        i
        for i, lesson in BY_ID.items()
        if (lesson.folder / "checks.py").exists()
        or (lesson.folder / "scenes" / "__init__.py").exists()
    ]


def _depends(lesson: str) -> dict[str, tuple[str, ...]]:
    if not (get_lesson(lesson).folder / "checks.py").exists():
        return {}
    return getattr(_checks(lesson), "DEPENDS", {})


def _checks(lesson: str):  # noqa: ANN202 - the lesson's checks module
    info = get_lesson(lesson)
    return importlib.import_module(f"lessons.{info.id}_{info.name}.checks")


def probe_source(lessons: list[str]) -> str:
    """The probe program's source for these lessons: lessons/cpp/probe.h, each lesson's
    probes.h (RT_PROBE(function) {...}), lessons/cpp/probe_main.cpp, one after the other, with
    #line so that an error names the file it is in."""
    own = [BY_ID[i].folder / "probes.h" for i in lessons]
    parts = [PROBE_COMMON, *(p for p in own if p.exists()), PROBE_MAIN]
    root = HERE.parent
    return "".join(f'#line 1 "{path.relative_to(root)}"\n{path.read_text()}\n' for path in parts)


def lesson_probes(lesson: str) -> list[Probe]:
    if not (get_lesson(lesson).folder / "checks.py").exists():
        return []
    probes = _checks(lesson).probes()
    concepts = set(get_lesson(lesson).concepts)
    for probe in probes:
        if probe.concept not in concepts:  # a programming error of a checks.py
            raise ValueError(f"{lesson}: probe {probe.name!r} names an unknown concept")
    return probes


# --- the core as graded: the solution with the student's regions of one lesson --------------


@dataclass
class Splice:
    files: dict[str, str]  # core file name -> its text with the student's regions
    missing: list[Region]  # regions the submission does not hold (stubbed)
    notes: list[str]
    taken: set[str] = field(default_factory=set)  # the lessons whose regions are the student's


def _lesson_regions(lesson: str | None) -> dict[str, list[Region]]:
    """The solution's regions of `lesson` (of every lesson: None), by file."""
    by_file: dict[str, list[Region]] = {}
    for path in sorted([*CORE.glob("*.h"), *CORE.glob("*.cpp")]):
        for region in parse(path.read_text(), path.name):
            if (lesson is None or region.lesson == lesson) and not region.is_copy:
                by_file.setdefault(path.name, []).append(region)
    return by_file


def _student_regions(path: Path, notes: list[str]) -> dict[tuple[str, str, str], Region]:
    try:
        text = path.read_text(errors="replace")
        return {r.key: r for r in parse(text, path.name)}
    except MarkerError as error:
        notes.append(f"Your file's markers are broken, so its code could not be found: {error}")
    except OSError as error:
        notes.append(f"{path.name}: cannot be read ({error.strerror})")
    return {}


def _extra_includes(student_text: str, solution_text: str) -> list[str]:
    have = {line.strip() for line in solution_text.splitlines()}
    return [
        line.strip()
        for line in student_text.splitlines()
        if line.startswith("#include <") and line.strip() not in have
    ]


def splice(submitted: dict[str, Path], lesson: str | None) -> Splice:
    """The solution's files holding lesson `lesson`'s regions, each region's body replaced by
    the submission's; a region the submission lacks becomes a stub (not handed in).

    With `lesson` None (the integration check): every lesson's regions the submission holds
    and has written (not a stub), each the student's, the rest the solution's."""
    files: dict[str, str] = {}
    missing: list[Region] = []
    notes: list[str] = []
    taken: set[str] = set()
    for name, regions in _lesson_regions(lesson).items():
        if lesson is None and name not in submitted:
            continue
        solution = (CORE / name).read_text()
        own: dict[tuple[str, str, str], Region] = {}
        student_text = ""
        if name in submitted:
            own = _student_regions(submitted[name], notes)
            student_text = submitted[name].read_text(errors="replace")
        lines = solution.split("\n")
        stubbed = False
        for region in sorted(regions, key=lambda r: r.begin, reverse=True):
            body_start = region.end - 1 - len(region.body)
            body = list(own[region.key].body) if region.key in own else []
            is_stub = any("not_implemented(" in b for b in body)
            if lesson is None and (
                region.key not in own or is_stub or is_given(own[region.key], region)
            ):
                continue  # the integration keeps the solution where the student wrote nothing
            if region.key in own:
                stubbed = stubbed or is_stub
                lines[body_start : region.end - 1] = body
                taken.add(region.lesson)
            else:
                missing.append(region)
                lines[region.begin - 1 : region.end] = stub_lines(region)
                stubbed = True
        text = "\n".join(lines)
        extra = _extra_includes(student_text, solution)
        if extra:
            first = text.index("#pragma once") + len("#pragma once")
            text = text[:first] + "\n" + "\n".join(extra) + text[first:]
        files[name] = _with_include(text) if stubbed else text
    for region in sorted(missing, key=lambda r: (r.file, r.begin)):
        notes.append(
            f"`{region.function}()` of {lesson} was not found in your `{region.file}` (not handed "
            "in, or its BEGIN/END SOLUTION lines were removed): graded as not implemented."
        )
    return Splice(files, missing, notes, taken)


# --- running the probes ------------------------------------------------------------------


def _parse_run(output: str, token: str) -> tuple[dict[int, tuple[str, str]], int | None]:
    """{index: (kind, rest)} for the probes that finished, and the index of the last one begun."""
    done: dict[int, tuple[str, str]] = {}
    last_begun: int | None = None
    for line in output.splitlines():
        at = line.find(token + " ")
        if at < 0:
            continue
        words = line[at + len(token) + 1 :].split(" ", 2)
        if len(words) < 2 or not words[1].lstrip("-").isdigit():
            continue
        kind, index = words[0], int(words[1])
        rest = words[2] if len(words) > 2 else ""
        if kind == "begin":
            last_begun = index
        else:
            done[index] = (kind, rest)
    return done, last_begun


def run_probes(build: Build, probes: list[Probe], work: Path) -> dict[int, tuple[str, str]]:
    """Run every probe; {index: (kind, detail)} with kind result / not_implemented / exception
    / crash / hang / memory / flood / not_run. A probe that crashed, hung or flooded is charged
    alone: the program is started again from the next one."""
    assert build.binary is not None
    probe_file = work / "probes.txt"
    probe_file.write_text("\n".join(p.line(i) for i, p in enumerate(probes)) + "\n")
    token = "@rtlab-" + secrets.token_hex(8)  # student code cannot print a result line
    results: dict[int, tuple[str, str]] = {}
    first, hangs = 0, 0
    while first < len(probes):
        command = [str(build.binary), str(probe_file), token, str(first)]
        outcome = run_limited(command, work, PROBE_LIMITS, "the check")
        done, last_begun = _parse_run(outcome.output, token)
        results.update(done)
        if outcome.ok:
            break
        if last_begun is None or last_begun in done:
            # It ended between probes (at exit: a static destructor, the student's atexit).
            for i in range(first, len(probes)):
                results.setdefault(i, (outcome.kind, outcome.message))
            break
        results[last_begun] = (outcome.kind, outcome.message)
        if outcome.kind in ("hang", "flood"):
            hangs += 1
        first = last_begun + 1
        if hangs >= MAX_HANGS:
            for i in range(first, len(probes)):
                results[i] = ("not_run", f"not run: {hangs} checks before it hung or flooded")
            break
    return results


def _got(rest: str) -> tuple[float, ...] | None:
    try:
        return tuple(float.fromhex(w) for w in rest.split())
    except ValueError:
        return None


WHAT = {
    "crash": "The program crashed while this check ran",
    "hang": "This check did not finish",
    "memory": "This check ran out of memory",
    "flood": "This check wrote too much output",
    "exception": "Your code threw an exception",
    "not_run": "Not run",
    "failed": "The check's program failed",
}


def _expected_text(e: object) -> str:
    if e is None:
        return "any"
    if isinstance(e, tuple):
        return f"at most {e[1]:g}"
    return fmt(float(e))  # type: ignore[arg-type]


def _probe_test(probe: Probe, points: float, kind: str, detail: str) -> TestResult:
    head = f"**Inputs**: {probe.inputs_text}\n\n"
    values: list[dict] = []

    def failed(text: str, why: str) -> TestResult:
        return TestResult(
            probe.name, probe.lesson, probe.concept, 0.0, points, "failed", text,
            probe.visibility, probe.function, why, probe.inputs_text, values,
        )  # fmt: skip

    if kind == "result":
        got = _got(detail)
        wrong = (
            ["the probe printed something that is not a number"]
            if got is None
            else probe.compare(got)
        )
        if got is not None and len(got) == len(probe.expected):
            values = [
                {"label": lab, "expected": _expected_text(e), "got": fmt(g),
                 "ok": not any(w.startswith(f"{lab}: ") for w in wrong)}
                for lab, e, g in zip(probe.labels, probe.expected, got, strict=True)
            ]  # fmt: skip
        if not wrong:
            return TestResult(
                probe.name,
                probe.lesson,
                probe.concept,
                points,
                points,
                "passed",
                head + "Passed.",
                probe.visibility,
                probe.function,
                inputs=probe.inputs_text,
                values=values,
            )
        expected = ", ".join(
            f"{lab} = {_expected_text(e)}"
            for lab, e in zip(probe.labels, probe.expected, strict=True)
        )
        text = (
            head
            + f"`{probe.function}()` returned a wrong value ({probe.concept}):\n\n"
            + "\n".join(f"- {w}" for w in wrong)
            + f"\n\nExpected: {expected}.\n\nHint: {probe.hint}."
        )
        return failed(text, "probe")
    if kind == "not_implemented":
        text = head + f"{detail.strip().removeprefix('rtlab: ')}."
    else:
        text = head + f"{WHAT.get(kind, kind)}: {detail.strip()} (in `{probe.function}()`)."
    return failed(text, kind)


# --- the diagnosis -----------------------------------------------------------------------


def diagnose(lesson: str, tests: list[TestResult], depends: dict[str, tuple[str, ...]]) -> str:
    """The first line names the broken concept in the lecture's words; the next lines say what
    else failed and the first failing check's inputs."""
    info = get_lesson(lesson)
    mine = [t for t in tests if t.lesson == lesson]
    failed = [t for t in mine if t.status == "failed"]
    if not mine:
        return f"{lesson}: no checks ran."
    if not failed:
        return f"{lesson} ({info.title}): all {len(mine)} checks pass."
    kinds = {t.kind for t in failed}
    if kinds == {"compile_error"}:
        return f"{lesson}: {failed[0].output[0].lower()}{failed[0].output[1:]}"
    if "not_implemented" in kinds and all(t.kind == "not_implemented" for t in mine):
        functions = sorted({t.function for t in mine if t.function})
        return (
            f"{lesson}: not implemented: {', '.join(f + '()' for f in functions)} "
            "(write them between their BEGIN SOLUTION and END SOLUTION lines)."
        )
    stubs = sorted({t.function for t in failed if t.kind == "not_implemented" and t.function})
    stub_line = f"Not implemented yet: {', '.join(f + '()' for f in stubs)}." if stubs else ""
    written = [t for t in failed if t.kind != "not_implemented"]
    if not written:
        return f"{lesson}: not implemented: {', '.join(f + '()' for f in stubs)} (the rest pass)."
    fraction: dict[str, float] = {}
    for concept in info.concepts:
        of = [t for t in mine if t.concept == concept and t.kind != "not_implemented"]
        if of:
            fraction[concept] = sum(t.status == "failed" for t in of) / len(of)
    broken = [c for c in info.concepts if fraction.get(c, 0) > 0]
    # A concept whose probes call code of another broken concept may fail because of it. Only
    # a failing probe shows that the other concept's own code is broken: a scene runs every
    # concept of the lesson at once, so its failure under one concept may come from another
    # (shadow acne, where the ray starts, darkens a scene of objects blocking light).
    probed = {c for c in broken if any(t.concept == c and t.kind != "scene" for t in written)}
    root = [c for c in broken if not any(d in probed for d in depends.get(c, ()))] or broken
    concept = max(root, key=lambda c: (fraction[c], -info.concepts.index(c)))
    of = [t for t in written if t.concept == concept]
    first = of[0]
    total = sum(t.concept == concept for t in mine)
    lines = [f"{lesson}: wrong: {concept} ({len(of)} of {total} checks fail)."]
    if first.kind not in ("probe", "scene"):
        what = WHAT.get(first.kind, first.kind).lower()
        lines[0] = f"{lesson}: {concept}: {what} ({first.name})."
    others = [c for c in broken if c != concept]
    if others:
        follows = [c for c in others if concept in depends.get(c, ())]
        lines.append(
            "Also failing: "
            + "; ".join(f"{c}{' (may follow from it)' if c in follows else ''}" for c in others)
            + "."
        )
    if stub_line:
        lines.append(stub_line)
    lines.append(f"First failing check, {first.name}:\n\n{first.output}")
    return "\n\n".join(lines)


# --- grading -----------------------------------------------------------------------------


def _failed_all(
    lesson: str,
    probes: list[Probe],
    kind: str,
    text: str,
    scenes: Sequence[SceneCheck] = (),
) -> list[TestResult]:
    points = _points(probes, scenes)
    tests = [
        TestResult(
            p.name,
            lesson,
            p.concept,
            0.0,
            points[i],
            "failed",
            text,
            p.visibility,
            p.function,
            kind,
        )
        for i, p in enumerate(probes)
    ]
    tests += [
        TestResult(
            _scene_name(c),
            lesson,
            c.concept,
            0.0,
            points[len(probes) + i],
            "failed",
            text,
            c.visibility,
            "",
            kind,
        )
        for i, c in enumerate(scenes)
    ]
    return tests


def _points(probes: list[Probe], scenes: Sequence[SceneCheck] = ()) -> list[float]:
    """Each concept is worth CONCEPT_POINTS, shared among all its checks (probes and scenes):
    the share of each check in the order [*probes, *scenes]. Scores are written to 4 decimals
    (TestResult.to_dict), so the shares are whole ten-thousandths whose sum is the concept's
    points exactly, the remainder going one unit each to the first checks: six checks of one
    concept get 1.6667 four times and 1.6666 twice, 10 in all, where six of 10/6 rounded each
    summed to 10.0002 and a full score read 50.0002 of 50.0002."""
    unit = 10_000
    checks = [c.concept for c in [*probes, *scenes]]
    counts = {concept: checks.count(concept) for concept in checks}
    seen: dict[str, int] = {}
    shares = []
    for concept in checks:
        k = seen.get(concept, 0)
        seen[concept] = k + 1
        base, extra = divmod(round(CONCEPT_POINTS * unit), counts[concept])
        shares.append((base + (1 if k < extra else 0)) / unit)
    return shares


def _scene_name(check: SceneCheck) -> str:
    return f"scene {check.name}: {check.title}"


def _scene_test(
    check: SceneCheck,
    points: float,
    rendered: Rendered,
    artifacts: Path | None,
    lesson: str | None = None,
) -> TestResult:
    """One scene check's result: every comparison's line, and for an image that differs, a
    heat map of |difference| written to `artifacts` (beside results.json) when given."""
    lesson = lesson or check.lesson
    where = check.scene_path.relative_to(ROOT) if check.scene_path.is_relative_to(ROOT) else ""
    head = f"**Scene**: {check.title} (`{where}`)\n\n"

    def result(status: str, text: str, kind: str, function: str = "") -> TestResult:
        score = points if status == "passed" else 0.0
        return TestResult(_scene_name(check), lesson, check.concept, score, points, status,
                          head + text, check.visibility, function, kind)  # fmt: skip

    if rendered.kind != "ok":
        if rendered.kind == "not_implemented":
            found = re.search(r"not implemented: (\w+)", rendered.message)
            text = rendered.message.strip().removeprefix("the render: ").removeprefix("rtlab: ")
            return result("failed", text + ".", "not_implemented", found.group(1) if found else "")
        what = WHAT.get(rendered.kind, rendered.kind)
        return result("failed", f"{what} while the scene rendered: {rendered.message}.",
                      rendered.kind)  # fmt: skip
    try:
        refs = references(check, render=os.environ.get("RTLAB_REFERENCES_ONLY") != "1")
        verdict = judge(check, rendered, refs)
    except Exception as error:  # the grader's own fault (no references): said, never a crash
        return result("failed", f"The grader could not compare this scene: {error!r}.",
                      "grader_error")  # fmt: skip
    lines = [f"- {line}" for line in verdict.lines]
    files: dict[str, str] = {}
    if artifacts is not None:
        for name, (reference, ours) in verdict.heat_maps.items():
            path = heat_map_path(artifacts, check, name)
            try:
                heat_map(reference, ours, path)
                lines.append(f"- heat map of |difference| against {name}: `{path.name}`")
                files[f"heat:{name}"] = path.name
            except Exception as error:  # a heat map that cannot be written loses only itself
                lines.append(f"- (no heat map: {error})")
        try:
            files.update(_scene_images(check, verdict, refs, artifacts))
        except Exception as error:  # the images are for the feedback page: lost alone
            lines.append(f"- (no images: {error})")
        if any(not k.startswith("heat:") for k in files):
            named = ", ".join(f"`{f}`" for k, f in files.items() if not k.startswith("heat:"))
            lines.append(f"- your image, the references' and the failing pixels marked: {named}")
    body = "\n".join(lines)
    if verdict.ok:
        return result("passed", "Passed.\n\n" + body, "scene")
    test = result("failed", f"Your image differs ({check.concept}):\n\n{body}\n\n"
                  f"Hint: {check.hint}.", "scene")  # fmt: skip
    test.artifacts = files
    return test


# The failing pixels marked on the student's image: the image darkened and greyed (so the
# marks stand out on any colour), each pixel over tolerance in magenta.
MARK_COLOUR = (1.0, 0.0, 1.0)


def _scene_images(
    check: SceneCheck, verdict: Verdict, refs: dict, artifacts: Path
) -> dict[str, str]:
    """For a scene that differs, beside results.json: the student's image (`...-yours.png`),
    each differing reference's (`...-povray-reference.png`) and, for the per-pixel rule, the
    student's image with the pixels that fail against that reference marked
    (`...-povray-failing.png`): those over its tolerance for the per-pixel rule, a path
    scene's failing blocks (its rule is statistical, per block) otherwise."""
    from reference.metrics import FLOAT32_SLACK, MITSUBA_TOLERANCE, over_tolerance
    from tracer.image import save_image

    files: dict[str, str] = {}
    for name, (reference, ours) in verdict.heat_maps.items():
        ours = np.asarray(ours, np.float32)[..., :3]
        if "yours" not in files:
            path = heat_map_path(artifacts, check, "yours")
            save_image(path, np.nan_to_num(ours, nan=0.0, posinf=1.0, neginf=0.0))
            files["yours"] = path.name
        path = heat_map_path(artifacts, check, f"{name}-reference")
        save_image(path, np.asarray(reference, np.float32)[..., :3])
        files[f"reference:{name}"] = path.name
        if name in verdict.failing:
            mask = verdict.failing[name]
        elif isinstance(check, PathSceneCheck) or name not in ("povray", "mitsuba"):
            continue
        else:
            bound = refs["povray_bound"] + FLOAT32_SLACK if name == "povray" else MITSUBA_TOLERANCE
            mask = over_tolerance(reference, ours, bound)
        grey = np.nan_to_num(ours, nan=0.0, posinf=1.0, neginf=0.0).mean(-1, keepdims=True)
        marked = np.repeat(0.25 * np.clip(grey, 0, 1), 3, axis=-1)
        marked[mask] = MARK_COLOUR
        path = heat_map_path(artifacts, check, f"{name}-failing")
        save_image(path, marked)
        files[f"failing:{name}"] = path.name
    return files


def _compile_text(build: Build) -> str:
    text = build.outcome.message
    if build.outcome.kind == "compile_error":
        text = (
            "Your code does not compile; the compiler's first errors:\n\n```\n"
            + (text.split("\n", 1)[1] if "\n" in text else text)
            + "\n```"
        )
    return text


def _write_submission(work: Path, spliced: Splice) -> Path:
    own = work / "submission"
    own.mkdir()
    for name, text in spliced.files.items():
        (own / name).write_text(text)
    (own / STUB_HEADER).write_text((HERE / "cpp" / STUB_HEADER).read_text())
    return own


def grade_lesson(
    submitted: dict[str, Path],
    lesson: str,
    *,
    public: bool = False,
    scenes: bool = True,
    artifacts: Path | None = None,
) -> tuple[list[TestResult], str, list[str]]:
    """Grade one lesson: its probes and its scene checks (only the visible ones: `public`; no
    scenes: `scenes` False), from one splice of the student's regions of the lesson. The probe
    program and the extension are built at the same time (two child processes: the machine's
    two cores), each once, serving all the lesson's checks of their kind."""
    probes = [p for p in lesson_probes(lesson) if not public or p.visibility == "visible"]
    checks = lesson_scenes(lesson) if scenes else []
    checks = [c for c in checks if not public or c.visibility == "visible"]
    depends = _depends(lesson)
    spliced = splice(submitted, lesson)
    points = _points(probes, checks)
    with temporary_work() as tmp:
        work = Path(tmp)
        own = _write_submission(work, spliced)
        with ThreadPoolExecutor(max_workers=2) as pool:
            probe_job = (
                pool.submit(build_probe, own, probe_source([lesson]), work / "build")
                if probes
                else None
            )
            ext_job = pool.submit(build_extension, own, work / "ext") if checks else None
            probe_build = probe_job.result() if probe_job else None
            ext_build = ext_job.result() if ext_job else None
        broken = next((b for b in (probe_build, ext_build) if b and not b.outcome.ok), None)
        if broken is not None:
            tests = _failed_all(lesson, probes, broken.outcome.kind, _compile_text(broken),
                                checks)  # fmt: skip
            return tests, diagnose(lesson, tests, depends), spliced.notes
        ran = run_probes(probe_build, probes, work / "build") if probe_build else {}
        rendered = render_student(ext_build, checks, work / "renders") if ext_build else []
        tests = [
            _probe_test(p, points[i], *ran.get(i, ("not_run", "not run")))
            for i, p in enumerate(probes)
        ]
        tests += [
            _scene_test(c, share, r, artifacts)
            for c, share, r in zip(checks, points[len(probes) :], rendered, strict=True)
        ]
    return tests, diagnose(lesson, tests, depends), spliced.notes


INTEGRATION = "integration"
INTEGRATION_CONCEPT = "all your lessons together: the simple ray tracing algorithm"
# The lecture's Ex 25 scene (tracer/scenes/ex25.toml: spheres, a plane, two lights, shadows,
# Phong highlights and the reflection chain), small: 81 x 61 pixels.
INTEGRATION_SCENE = SceneCheck(
    INTEGRATION,
    "ex25",
    INTEGRATION_CONCEPT,
    "the lecture's Ex 25 scene, rendered with all your lessons together",
    path=ROOT / "tracer" / "scenes" / "ex25.toml",
    size=(81, 61),
    hint="each lesson's checks above say which part is wrong",
)


def integration_test(
    submitted: dict[str, Path], artifacts: Path | None, graded: Sequence[str] = ()
) -> TestResult | None:
    """The final check: every region the submission holds and has written (of every lesson),
    the student's, together on the Ex 25 scene, against POV-Ray and Mitsuba. It is worth no
    points: a mistake it shows is charged once, by its own lesson's checks; it shows whether
    the student's whole tracer makes the lecture's picture. None when no region was written,
    or none of the `graded` lessons' (a stub tree: the course's code alone would pass, and say
    nothing of the student's)."""
    spliced = splice(submitted, None)
    if not spliced.files or not spliced.taken:
        return None
    if graded and not spliced.taken & set(graded):
        return None
    with temporary_work() as tmp:
        work = Path(tmp)
        build = build_extension(_write_submission(work, spliced), work / "ext")
        if not build.outcome.ok:
            rendered = Rendered(build.outcome.kind, _compile_text(build))
        else:
            rendered = render_student(build, [INTEGRATION_SCENE], work / "renders")[0]
        test = _scene_test(INTEGRATION_SCENE, 0.0, rendered, artifacts)
    yours = ", ".join(sorted(spliced.taken))
    test.output += (
        f"\n\nYour code of {yours} together, the course's solution elsewhere. (Worth no "
        "points: each mistake it shows is charged once, by its lesson's checks.)"
    )
    return test


def touched_lessons(submitted: dict[str, Path]) -> list[str]:
    """The lessons with checks whose regions in the submitted files differ from the solution's
    (a stub counts only when nothing else differs: the earliest stubbed lesson); with nothing
    different, every lesson with checks whose regions the files hold."""
    from lessons.student import solution_lines

    graded = lessons_with_checks()
    solution = {}
    for path in sorted([*CORE.glob("*.h"), *CORE.glob("*.cpp")]):
        for r in parse(path.read_text(), path.name):
            solution[r.key] = r
    differ, stubbed, present = set(), set(), set()
    for name, path in submitted.items():
        try:
            regions = parse(path.read_text(errors="replace"), name)
        except (MarkerError, OSError):
            regions = []
            present.update(r.lesson for r in solution.values() if r.file == name)
            differ.update(r.lesson for r in solution.values() if r.file == name)
        for r in regions:
            if r.is_copy or r.key not in solution:
                continue
            present.add(r.lesson)
            if solution_lines(r) != solution_lines(solution[r.key]) and not is_given(
                r, solution[r.key]
            ):
                if any("not_implemented(" in b for b in r.body):
                    stubbed.add(r.lesson)
                else:
                    differ.add(r.lesson)
    order = [i for i in BY_ID if i in graded]
    chosen = [i for i in order if i in differ]
    if not chosen:
        chosen = [i for i in order if i in stubbed][:1]
    if not chosen:
        chosen = [i for i in order if i in present]
    return chosen


def grade(
    submission: str | Path,
    lesson: str | None = None,
    *,
    public: bool = False,
    scenes: bool = True,
    integration: bool = True,
    artifacts: str | Path | None = None,
) -> Result:
    """Grade a submission directory (C++ files named as in tracer/cpp/, in DIR or DIR/cpp) on
    one lesson, or on every lesson its files touch, then (`integration`) all the student's
    lessons together on one scene. `public`: only the visible checks (a student's self-check);
    `scenes` False: probes only; `artifacts`: a directory for the heat maps of failing scenes
    (the CLI gives the one results.json is written to). Never raises for a bad submission:
    the Result says what is wrong."""
    start = time.monotonic()
    submission = Path(submission)
    out = Path(artifacts) if artifacts is not None else None
    if lesson is not None:
        get_lesson(lesson)  # an unknown id is the caller's error: UnknownLessonError
        if lesson not in lessons_with_checks():
            raise NoChecksError(
                f"{lesson}: no checks yet; graded lessons: {', '.join(lessons_with_checks())}"
            )
    result = Result(lessons=[lesson] if lesson else [])
    submitted = (
        {n: p for n, p in _submitted_files(submission).items() if (CORE / n).exists()}
        if submission.is_dir()
        else {}
    )

    def visible(each: str) -> tuple[list[Probe], list[SceneCheck]]:
        probes = [p for p in lesson_probes(each) if not public or p.visibility == "visible"]
        checks = [c for c in (lesson_scenes(each) if scenes else [])
                  if not public or c.visibility == "visible"]  # fmt: skip
        return probes, checks

    if not submitted:
        what = (
            "is not a directory"
            if not submission.is_dir()
            else "holds no C++ file named as in tracer/cpp/ (e.g. 10_classic.h)"
        )
        lessons_ = [lesson] if lesson else lessons_with_checks()[:1]
        result.lessons = lessons_
        for each in lessons_:
            probes, checks = visible(each)
            result.tests += _failed_all(
                each, probes, "empty", f"Nothing to grade: the submission {what}.", checks
            )
        result.diagnosis = (
            f"{', '.join(lessons_)}: nothing to grade: the submission `{submission.name}` {what}."
        )
        result.execution_time = time.monotonic() - start
        return result
    result.lessons = [lesson] if lesson else touched_lessons(submitted)
    diagnoses = []
    for each in result.lessons:
        try:
            tests, diagnosis, notes = grade_lesson(
                submitted, each, public=public, scenes=scenes, artifacts=out
            )
        except Exception as error:  # the grader's own fault: still a result, never a crash
            probes, checks = visible(each)
            tests = _failed_all(
                each, probes, "grader_error", f"The grader failed: {error!r}", checks
            )
            diagnosis, notes = f"{each}: the grader failed: {error!r}", []
        result.tests += tests
        result.notes += notes
        diagnoses.append(diagnosis)
    if integration and scenes:
        try:
            test = integration_test(submitted, out, result.lessons)
        except Exception as error:  # the grader's own fault: said, never a crash
            result.notes.append(f"The integration check could not run: {error!r}")
            test = None
        if test is not None:
            result.tests.append(test)
            if test.status == "failed":
                result.notes.append(
                    f"Integration: your lessons together do not render the Ex 25 scene as "
                    f"POV-Ray and Mitsuba do (see the check {test.name!r})."
                )
    broken = [d for d in diagnoses if "all " not in d.split("\n", 1)[0]]
    result.diagnosis = "\n\n".join(broken + [d for d in diagnoses if d not in broken])
    result.execution_time = time.monotonic() - start
    return result


# --- a class in a batch (rtlab lesson grade DIRS --out GRADES; tracer/batch.py) --------------

#: The kinds of a check's failure that are the submission's faults rather than wrong answers:
#: a batch counts its task as failed (with its results.json written all the same).
FAULTS = ("crash", "hang", "flood", "memory", "compile_error", "grader_error", "empty")
#: What a graded result depends on besides the submission: the grader, the lessons' checks
#: and scenes, the core the submission is laid over, the references' runners and converters.
GRADER_SOURCES = ("lessons/**/*.py", "lessons/**/*.h", "lessons/**/*.cpp", "lessons/**/*.json",
                  "lessons/**/*.toml", "tracer/cpp/*", "tracer/scenes/ex25.toml",
                  "reference/*.py", "converters/*.py")  # fmt: skip


def grade_into(
    submission: str, lesson: str | None, out: str, public: bool = False, scenes: bool = True
) -> dict:
    """One submission of a class: graded into the directory ``out`` (results.json without
    timing, the heat maps of failing scenes beside it), which replaces the old one whole only
    when grading finished. Returns what the class summary needs: the score, the diagnosis's
    first line, the faults; ``status`` "failed" when the submission crashed, hung, flooded,
    ran out of memory or did not compile (its results.json says so, as for one submission)."""
    from reports.site import staged

    target = Path(out)
    with staged(target) as stage:
        result = grade(Path(submission), lesson, public=public, scenes=scenes, artifacts=stage)
        result.write(stage / "results.json", timing=False)
    faults: dict[str, int] = {}
    for t in result.tests:
        if t.kind in FAULTS and t.status == "failed":
            faults[t.kind] = faults.get(t.kind, 0) + 1
    first = result.diagnosis.split("\n", 1)[0]
    data = {
        "score": result.score,
        "max_score": result.max_score,
        "passed": sum(t.status == "passed" for t in result.tests),
        "checks": len(result.tests),
        "lessons": result.lessons,
        "diagnosis": first,
        "faults": faults,
    }
    if faults:
        said = ", ".join(f"{k} in {n} check{'s' if n > 1 else ''}" for k, n in faults.items())
        data |= {"status": "failed", "reason": f"{said}: {first}"}
    return data
