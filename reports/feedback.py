"""A graded submission's feedback page (``rtlab lesson grade DIR --report OUT``,
``reports.feedback_page(result, out)``): OUT/index.html beside OUT/results.json and the
grader's images of the scenes that differ.

The page is made from results.json alone (Gradescope's format, with the grader's extra_data:
the diagnosis, each probe's inputs and values, each failing scene's images), so an instructor
can make it again from a results.json a student handed in. First the verdict and what to fix
(the diagnosis, the concepts failing with their functions and hints), then per check: the
concept, the inputs, what was expected and what came, for a scene the student's image beside
each reference with the heat map and the failing pixels marked, and build errors or crash
text where there was one.
"""

from __future__ import annotations

import json
import re
import shutil
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from lessons.catalog import BY_ID

# What the test's kind says, for a check that failed without a wrong value.
KIND_TITLES = {
    "compile_error": "does not compile",
    "not_implemented": "not implemented",
    "crash": "crashed",
    "hang": "did not finish",
    "memory": "ran out of memory",
    "flood": "wrote too much output",
    "exception": "threw an exception",
    "not_run": "not run",
    "empty": "nothing to grade",
    "grader_error": "the grader failed",
}
LESSON_LINE = re.compile(r"^(L\d\d|integration)\b")


@dataclass
class Check:
    """One test of results.json, read back."""

    number: str
    name: str
    lesson: str
    concept: str
    score: float
    max_score: float
    passed: bool
    output: str
    visibility: str
    kind: str
    function: str
    inputs: str
    values: list[dict[str, Any]]
    artifacts: dict[str, str]

    @property
    def anchor(self) -> str:
        return f"check-{self.number}"

    @property
    def hint(self) -> str:
        found = re.search(r"^Hint: (.*)$", self.output, re.M)
        return found.group(1).rstrip(".") if found else ""

    @property
    def is_scene(self) -> bool:
        return self.name.startswith("scene ")


@dataclass
class ConceptRow:
    lesson: str
    concept: str
    checks: list[Check] = field(default_factory=list)

    @property
    def failing(self) -> list[Check]:
        return [c for c in self.checks if not c.passed]

    @property
    def score(self) -> float:
        return sum(c.score for c in self.checks)

    @property
    def max_score(self) -> float:
        return sum(c.max_score for c in self.checks)

    @property
    def functions(self) -> list[str]:
        return sorted({c.function for c in self.failing if c.function})


@dataclass
class Group:
    """Failing checks that failed the same way (a compile error fails every check with the
    same text): shown once, with the checks' names."""

    first: Check
    checks: list[Check]


def read_checks(data: dict[str, Any]) -> list[Check]:
    checks = []
    for i, t in enumerate(data.get("tests", [])):
        extra = t.get("extra_data") or {}
        tags = [*(t.get("tags") or []), "", ""]
        checks.append(
            Check(
                number=str(t.get("number", i + 1)),
                name=t.get("name", f"check {i + 1}"),
                lesson=tags[0],
                concept=tags[1],
                score=float(t.get("score", 0)),
                max_score=float(t.get("max_score", 0)),
                passed=t.get("status") == "passed",
                output=t.get("output", ""),
                visibility=t.get("visibility", "visible"),
                kind=extra.get("kind", "scene" if t.get("name", "").startswith("scene ") else ""),
                function=extra.get("function", ""),
                inputs=extra.get("inputs", ""),
                values=list(extra.get("values", [])),
                artifacts=dict(extra.get("artifacts", {})),
            )
        )
    return checks


def concept_rows(checks: list[Check]) -> list[ConceptRow]:
    """Per lesson, per concept in the catalog's order (then any other, as met)."""
    rows: dict[tuple[str, str], ConceptRow] = {}
    for lesson in dict.fromkeys(c.lesson for c in checks):
        info = BY_ID.get(lesson)
        for concept in info.concepts if info else ():
            rows[(lesson, concept)] = ConceptRow(lesson, concept)
    for c in checks:
        rows.setdefault((c.lesson, c.concept), ConceptRow(c.lesson, c.concept)).checks.append(c)
    return [r for r in rows.values() if r.checks]


def split_blocks(text: str) -> list[str]:
    """Markdown's paragraphs (blank-line separated), a fenced block kept whole."""
    blocks, current, fenced = [], [], False
    for line in text.split("\n"):
        if line.lstrip().startswith("```"):
            fenced = not fenced
        if not line.strip() and not fenced:
            if current:
                blocks.append("\n".join(current))
                current = []
            continue
        current.append(line)
    if current:
        blocks.append("\n".join(current))
    return blocks


def diagnosis_summary(diagnosis: str) -> tuple[str, str]:
    """(the first line, the rest of the summary) of the grader's diagnosis, without its
    "First failing check, ..." details (the page shows every failing check below)."""
    kept, skipping = [], False
    for block in split_blocks(diagnosis):
        if block.startswith("First failing check"):
            skipping = True
            continue
        if LESSON_LINE.match(block):
            skipping = False
        if not skipping:
            kept.append(block)
    if not kept:
        return "", ""
    return kept[0], "\n\n".join(kept[1:])


def grouped_failures(checks: list[Check]) -> list[Group]:
    groups: dict[tuple[str, str, str], Group] = {}
    out = []
    for c in checks:
        if c.passed:
            continue
        if c.kind in ("probe", "scene") or c.values or c.artifacts:
            out.append(Group(c, [c]))
            continue
        # The output without its first paragraph (the probe's inputs, the scene's title).
        blocks = split_blocks(c.output)
        key = (c.lesson, c.kind, "\n\n".join(blocks[1:]) if len(blocks) > 1 else c.output)
        if key in groups:
            groups[key].checks.append(c)
        else:
            groups[key] = Group(c, [c])
            out.append(groups[key])
    return out


def _data(result: Any) -> dict[str, Any]:
    if isinstance(result, dict):
        return result
    if isinstance(result, (str, Path)):
        return json.loads(Path(result).read_text())
    return result.as_gradescope()  # a lessons.grader.Result


def feedback_html(data: dict[str, Any], *, title: str = "", command: str = "",
                  images: set[str] | None = None) -> str:  # fmt: skip
    """The page's HTML for one results.json; ``images``: the image files that exist beside it
    (an image the grader named but that is missing is left out, never a broken link)."""
    from reports.site import SCALE, environment, markdown_html

    extra = data.get("extra_data") or {}
    checks = read_checks(data)
    diagnosis = extra.get("diagnosis") or data.get("output", "")
    first, rest = diagnosis_summary(diagnosis)
    lessons = extra.get("lessons") or list(dict.fromkeys(c.lesson for c in checks))
    rows = concept_rows(checks)
    failing_rows = [r for r in rows if r.failing]
    score = float(data.get("score", sum(c.score for c in checks)))
    max_score = sum(c.max_score for c in checks)
    names = ", ".join(f"{i} ({BY_ID[i].title})" if i in BY_ID else i for i in lessons)

    def has(name: str) -> bool:
        return images is None or name in images

    env = environment()
    env.filters["md"] = markdown_html
    env.filters["points"] = lambda v: f"{v:.4g}"
    return env.get_template("feedback.html").render(
        title=title or f"Feedback: {names}",
        lessons=names,
        first=first,
        rest=rest,
        notes=extra.get("notes", []),
        checks=checks,
        rows=rows,
        failing_rows=failing_rows,
        # A build that failed fails every check the same way: the table would say it 20 times.
        fix_table=any(c.kind not in ("compile_error", "empty") for c in checks if not c.passed),
        groups=grouped_failures(checks),
        passed=[c for c in checks if c.passed],
        score=score,
        max_score=max_score,
        passing=sum(c.passed for c in checks),
        has=has,
        scale=SCALE,
        kind_titles=KIND_TITLES,
        command=command,
        made=time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
    )


def artifact_names(data: dict[str, Any]) -> set[str]:
    return {name for c in read_checks(data) for name in c.artifacts.values()}


def feedback_page(
    result: Any,
    out: str | Path,
    *,
    artifacts: str | Path | None = None,
    title: str = "",
    command: str = "",
    inline: bool = False,
) -> Path:
    """Write ``out/index.html`` for one graded submission: ``result`` a lessons.grader.Result,
    results.json's dict, or the path of a results.json. The grader's images are read from
    ``artifacts`` (default: ``out``, where `rtlab lesson grade --report` has the grader write
    them) and copied into ``out`` when elsewhere; a Result or a dict is also written as
    ``out/results.json``, so the page sits beside its results. Each file atomically.
    ``inline`` (``--single-file``): the images inlined into the page as data: URIs, a page to
    mail; the image files stay beside results.json, which names them."""
    from tracer.image import atomic_path

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    data = _data(result)
    source = Path(artifacts) if artifacts is not None else out
    if isinstance(result, (str, Path)) and artifacts is None:
        source = Path(result).parent
    present = set()
    for name in sorted(artifact_names(data)):
        if Path(name).name != name:  # results.json names files beside it, never a path
            continue
        if (source / name).is_file():
            if source.resolve() != out.resolve():
                with atomic_path(out / name) as tmp:
                    shutil.copyfile(source / name, tmp)
            present.add(name)
    beside = out / "results.json"
    if not isinstance(result, (str, Path)) or Path(result).resolve() != beside.resolve():
        with atomic_path(beside) as tmp:
            tmp.write_text(json.dumps(data, indent=2) + "\n")
    page = feedback_html(data, title=title, command=command, images=present)
    if inline:
        from reports.site import inline_images

        page, _ = inline_images(page, out)
    with atomic_path(out / "index.html") as tmp:
        tmp.write_text(page)
    return out / "index.html"
