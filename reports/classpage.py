"""The class page (``rtlab report class GRADES --out DIR``): over a directory of results.json
files, one per student (GRADES/<student>/results.json, at any depth), a student-by-concept
matrix, the most frequent diagnoses (their first lines), the score distribution (a matplotlib
histogram, DIR/scores.png) and a link to each student's feedback page where one is beside the
results.json (`rtlab lesson grade --report`). Written atomically (DIR replaced whole)."""

from __future__ import annotations

import json
import os
import re
import time
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from lessons.catalog import BY_ID
from reports.feedback import LESSON_LINE, ConceptRow, concept_rows, read_checks, split_blocks

# A diagnosis's count of failing checks differs from student to student for the same mistake
# ("(5 of 6 checks fail)"): the class page counts diagnoses without it.
COUNT = re.compile(r" \(\d+ of \d+ checks fail\)(?=\.$)")
# The histogram's bins: tenths of the full score, the last bin closed (full marks in it).
BINS = 10


class ClassReportError(ValueError):
    """A grades directory without results, or a results.json that cannot be read."""


@dataclass
class Student:
    name: str  # the results.json's directory, relative to GRADES
    results: Path
    data: dict[str, Any]
    rows: dict[tuple[str, str], ConceptRow]
    score: float
    max_score: float
    diagnoses: list[str]  # first lines, one per lesson graded
    feedback: str  # the feedback page's link from the class page, or ""

    @property
    def share(self) -> float:
        return self.score / self.max_score if self.max_score > 0 else 0.0


def first_lines(diagnosis: str) -> list[str]:
    """Each graded lesson's first line of the grader's diagnosis."""
    lines = [b.split("\n", 1)[0] for b in split_blocks(diagnosis) if LESSON_LINE.match(b)]
    return lines or ([diagnosis.split("\n", 1)[0]] if diagnosis.strip() else [])


def diagnosis_key(line: str) -> str:
    return COUNT.sub("", line)


def read_student(results: Path, grades: Path, out: Path) -> Student:
    try:
        data = json.loads(results.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise ClassReportError(f"{results}: cannot be read as results.json ({error})") from None
    if not isinstance(data, dict) or not isinstance(data.get("tests"), list):
        raise ClassReportError(
            f"{results}: expected Gradescope's results.json (an object with a 'tests' list)"
        )
    checks = read_checks(data)
    rows = {(r.lesson, r.concept): r for r in concept_rows(checks)}
    diagnosis = (data.get("extra_data") or {}).get("diagnosis") or data.get("output", "")
    page = results.parent / "index.html"
    name = results.parent.relative_to(grades).as_posix()
    return Student(
        name=name if name != "." else results.parent.resolve().name,
        results=results,
        data=data,
        rows=rows,
        score=float(data.get("score", sum(c.score for c in checks))),
        max_score=sum(c.max_score for c in checks),
        diagnoses=first_lines(diagnosis),
        feedback=Path(os.path.relpath(page, out)).as_posix() if page.is_file() else "",
    )


def read_class(grades: Path, out: Path) -> list[Student]:
    grades = Path(grades)
    if not grades.is_dir():
        raise ClassReportError(f"{grades}: not a directory (expected one of results.json files)")
    found = sorted(grades.rglob("results.json"))
    if not found:
        raise ClassReportError(
            f"{grades}: no results.json in it (expected GRADES/<student>/results.json, as "
            "`rtlab lesson grade DIR --report GRADES/<student>` writes)"
        )
    return [read_student(p, grades, out) for p in found]


def columns(students: list[Student]) -> list[tuple[str, str]]:
    """The (lesson, concept) pairs any student was graded on: lessons in the lecture's order,
    concepts in the catalog's, the integration check last."""
    seen = {key for s in students for key in s.rows}
    order = [(i, c) for i, lesson in BY_ID.items() for c in lesson.concepts]
    return [k for k in order if k in seen] + sorted(k for k in seen if k not in order)


def bin_of(share: float) -> int:
    """The histogram's bin of a share of the full marks. results.json rounds each check's
    points to 4 decimals, so a share reads off by up to (checks x 5e-5) / max_score: 27 checks
    of L04's 50 points, 3e-5 (full marks read as 1.0000000000000002, 90% as 0.8999996). The
    share rounded to 1e-4 (0.01%) first is the share the points make, then binned (full marks
    in the last bin)."""
    pct = min(max(round(100 * share, 2), 0.0), 100.0)
    return min(int(pct // (100 / BINS)), BINS - 1)


def histogram(students: list[Student], path: Path) -> list[int]:
    """scores.png: the number of students per tenth of the full score; returns the counts."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from tracer.image import atomic_path

    counts = np.zeros(BINS, dtype=int)
    for s in students:
        counts[bin_of(s.share)] += 1
    edges = np.linspace(0, 100, BINS + 1)
    fig, ax = plt.subplots(figsize=(6, 3.2), dpi=100)
    ax.bar(edges[:-1], counts, width=100 / BINS, align="edge", color="#3b6ea5",
           edgecolor="white")  # fmt: skip
    ax.set_xlabel("score, % of the full marks")
    ax.set_ylabel("students")
    ax.set_xlim(0, 100)
    ax.yaxis.get_major_locator().set_params(integer=True)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)
    return [int(c) for c in counts]


def render_class(students: list[Student], directory: Path, *, command: str = "",
                 inline: bool = False) -> Path:  # fmt: skip
    """``inline``: scores.png inlined as a data: URI and not kept (a page to mail; its links
    to the feedback pages still need those pages where the links say)."""
    from reports.site import environment, inline_images

    cols = columns(students)
    counts = histogram(students, directory / "scores.png")
    diagnoses = Counter(diagnosis_key(line) for s in students for line in s.diagnoses)
    failing = {
        key: sum(1 for s in students if key in s.rows and s.rows[key].failing) for key in cols
    }
    graded = {key: sum(1 for s in students if key in s.rows) for key in cols}
    env = environment()
    env.filters["points"] = lambda v: f"{v:.4g}"
    html = env.get_template("class.html").render(
        students=students,
        cols=cols,
        failing=failing,
        graded=graded,
        diagnoses=diagnoses.most_common(),
        bins=[(100 * i // BINS, 100 * (i + 1) // BINS, n) for i, n in enumerate(counts)],
        mean=sum(100 * s.share for s in students) / len(students),
        command=command,
        made=time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
    )
    if inline:
        html, used = inline_images(html, directory)
        for path in used:
            path.unlink()
    (directory / "index.html").write_text(html)
    return directory / "index.html"


def write_class_page(grades: str | Path, out: str | Path, *, command: str = "",
                     inline: bool = False) -> Path:  # fmt: skip
    """``out/index.html`` and ``out/scores.png`` over ``grades``; ``out`` replaced whole."""
    from reports.site import staged

    out = Path(out)
    students = read_class(Path(grades), out)  # bad input found before anything is written
    with staged(out) as stage:
        render_class(students, stage, command=command, inline=inline)
    return out / "index.html"
