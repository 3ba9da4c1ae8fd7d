"""``rtlab bench report``: how long ``rtlab report course`` takes (issue 10 asks under five
minutes on this 2-core machine with the references cached). A benchmark, not a test: rows in
reference/bench.py's format (case, renderer, threads, metric, value, unit, repeats).

Two runs of the whole course into a temporary directory, one after the other: the first as the
caches are found (the grader's references in build/lesson-references, the known-wrong versions'
builds in build/report-mistakes; how many builds it made is in the row), the second with both
caches full, which is the figure the issue asks for. Each lesson's share of the second run is a
row of its own, split into its scenes (rtlab rendering and judging, the references timed again)
and its known-wrong versions (built or taken from the cache, rendered in a child process).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path
from typing import Any


def _row(case: str, value: float, **extra: Any) -> dict[str, Any]:
    return {"case": case, "renderer": "rtlab-report", "threads": 2, "metric": "seconds",
            "value": value, "unit": "s", "repeats": 1, **extra}  # fmt: skip


def suite_report() -> list[dict[str, Any]]:
    from lessons.catalog import LESSONS
    from reports.lesson import DEFAULT_MISTAKES, LessonPage, build_lesson_page
    from reports.site import write_course_site

    rows = []
    ids = [lesson.id for lesson in LESSONS]
    with tempfile.TemporaryDirectory(prefix="rtlab-bench-report-") as tmp:
        for run in ("first run, caches as found", "caches full"):
            pages: list[LessonPage] = []

            def build(lesson: str, pages: list[LessonPage] = pages) -> LessonPage:
                page = build_lesson_page(lesson, mistake_cap=DEFAULT_MISTAKES,
                                         command="rtlab bench report")  # fmt: skip
                pages.append(page)
                return page

            start = time.perf_counter()
            write_course_site(Path(tmp) / "site", build, ids, command="rtlab bench report")
            seconds = time.perf_counter() - start
            built = sum(not m.cached for p in pages for m in p.mistakes_shown)
            shown = sum(len(p.mistakes_shown) for p in pages)
            rows.append(_row(f"report course ({run})", seconds, builds=built, mistakes=shown,
                             scenes=sum(len(p.scenes) for p in pages)))  # fmt: skip
        for page in pages:  # the second run's
            rows.append(_row(f"report {page.lesson.id}: scenes", page.scene_seconds,
                             scenes=len(page.scenes)))  # fmt: skip
            rows.append(_row(f"report {page.lesson.id}: known-wrong versions",
                             page.mistake_seconds, mistakes=len(page.mistakes_shown)))  # fmt: skip
    return rows
