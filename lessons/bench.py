"""``rtlab bench grading``: how long grading one lesson of one submission takes, build included
(issue 9 asks under 60 s on a 2-core machine). A benchmark, not a test: rows in reference/bench.py's
format (case, renderer, threads, metric, value, unit, repeats).

Rows: the whole grade of one lesson (a known-wrong version, so that failing scenes write their
heat maps), with and without the integration check; its parts measured alone (the probe build,
the extension build, both at once as the grader runs them); and the first rendering of a
lesson's references by POV-Ray and Mitsuba, which the cache then saves.
"""

from __future__ import annotations

import os
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

LESSONS = ("L04", "L07")


def _row(case: str, renderer: str, value: float, repeats: int = 1) -> dict[str, Any]:
    return {"case": case, "renderer": renderer, "threads": 2, "metric": "seconds",
            "value": value, "unit": "s", "repeats": repeats}  # fmt: skip


def _submission(lesson: str, out: Path) -> Path:
    import shutil

    from lessons.mistakes import mistakes, write_mistake
    from lessons.student import CORE

    wrong = mistakes(lesson)
    if wrong:
        write_mistake(wrong[0], out)
    else:
        shutil.copytree(CORE, out)
    return out


def suite_grading(repeats: int = 1) -> list[dict[str, Any]]:
    from lessons.grader import grade, probe_source, splice
    from lessons.sandbox import build_extension, build_probe, nanobind_object
    from lessons.scene_checks import lesson_scenes, references

    nanobind_object()  # built once per machine: not part of a submission's grade
    rows = []
    with tempfile.TemporaryDirectory(prefix="rtlab-bench-") as tmp:
        work = Path(tmp)
        for lesson in LESSONS:
            sub = _submission(lesson, work / f"sub-{lesson}")
            for integration in (False, True):

                def one(
                    sub: Path = sub, lesson: str = lesson, integration: bool = integration
                ) -> float:
                    start = time.perf_counter()
                    grade(sub, lesson=lesson, integration=integration, artifacts=work)
                    return time.perf_counter() - start

                best = min(one() for _ in range(repeats))
                case = f"grade {lesson}" + (" + integration" if integration else "")
                rows.append(_row(case, "rtlab-grader", best, repeats))
        # The parts, alone and at once, for L04's splice.
        from lessons.student import _submitted_files

        spliced = splice(_submitted_files(work / "sub-L04"), "L04")
        own = work / "own"
        own.mkdir()
        for name, text in spliced.files.items():
            (own / name).write_text(text)
        from lessons.student import STUB_HEADER, SUPPORT

        (own / STUB_HEADER).write_text(SUPPORT.read_text())

        def timed(fn: Any, *args: Any) -> float:
            start = time.perf_counter()
            fn(*args)
            return time.perf_counter() - start

        rows.append(_row("L04 probe build", "rtlab-grader",
                         timed(build_probe, own, probe_source(["L04"]), work / "p1")))  # fmt: skip
        rows.append(_row("L04 extension build", "rtlab-grader",
                         timed(build_extension, own, work / "e1")))  # fmt: skip
        start = time.perf_counter()
        with ThreadPoolExecutor(2) as pool:
            jobs = [pool.submit(build_probe, own, probe_source(["L04"]), work / "p2"),
                    pool.submit(build_extension, own, work / "e2")]  # fmt: skip
            for job in jobs:
                job.result()
        rows.append(_row("L04 both builds at once", "rtlab-grader", time.perf_counter() - start))
        # The references' first rendering (what the cache saves every later grade).
        previous = os.environ.get("RTLAB_REFERENCES")
        os.environ["RTLAB_REFERENCES"] = str(work / "references")
        try:
            start = time.perf_counter()
            for check in lesson_scenes("L04"):
                references(check)
            rows.append(_row("L04 references (POV-Ray + Mitsuba)", "rtlab-grader",
                             time.perf_counter() - start))  # fmt: skip
        finally:
            if previous is None:
                os.environ.pop("RTLAB_REFERENCES", None)
            else:
                os.environ["RTLAB_REFERENCES"] = previous
    return rows
