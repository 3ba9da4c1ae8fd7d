"""``rtlab bench batch``: what batches on Dask cost and gain on this machine (tracer/batch.py).

- grading a class of CLASS_SIZE submissions of one lesson (made from the lesson's solution,
  its known-wrong versions in its mistakes/ folder, one that crashes and one that hangs, each
  made distinct by a comment so that no build is served by another's cache) on 1 and on 2
  workers of a LocalCluster, and serially without Dask; the scaling is the ratio;
- rendering every lesson's references (POV-Ray and Mitsuba, into a fresh cache) on 2 workers;
- the overhead Dask adds per task: a no-op task's round trip through the cluster.

Rows as reference/bench.py's (case, renderer, threads, metric, value, unit); the engine is the
"renderer". Not timed tests: figures to read, on a machine whose load the caller reports.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
import time
from pathlib import Path
from typing import Any

from lessons.catalog import get_lesson
from lessons.markers import parse
from lessons.mistakes import mistakes, write_mistake
from lessons.student import CORE

CLASS_SIZE = 40
LESSON = "L04"
#: The crashing and the hanging submissions: an edit of L04's lambert_term() (the hang costs
#: each probe's CPU limit, twice: lessons/grader.py MAX_HANGS).
LAMBERT = "    return dot(N, L);"
FAULTS = {
    "crash": "    if (N.z > -2) { volatile int *p = nullptr; *p = 1; }\n" + LAMBERT,
    "hang": "    while (N.z > -2) {\n    }\n" + LAMBERT,
    "flood": '    for (int i = 0; i < 100000000; ++i) std::printf("debug %d\\n", i);\n' + LAMBERT,
}


def _lesson_files(lesson: str) -> list[Path]:
    return [p for p in sorted([*CORE.glob("*.h"), *CORE.glob("*.cpp")])
            if any(r.lesson == lesson for r in parse(p.read_text(), p.name))]  # fmt: skip


def write_submission(out: Path, lesson: str, kind: str, tag: str = "") -> Path:
    """A submission directory: the solution's files of the lesson (`kind` "solution"), a
    known-wrong version (a mistake's name), or one that crashes, hangs or floods (L04's
    FAULTS); `tag` a comment inside the lesson's first region, which makes the sources (and
    so the build) its own without changing what it computes."""
    if kind in FAULTS and lesson != "L04":
        raise ValueError(f"{kind}: the faulty submissions edit L04's lambert_term()")
    if kind == "solution" or kind in FAULTS:
        out.mkdir(parents=True, exist_ok=True)
        for path in _lesson_files(lesson):
            (out / path.name).write_text(path.read_text())
        if kind in FAULTS:
            text = (CORE / "10_classic.h").read_text()
            assert text.count(LAMBERT) == 1
            (out / "10_classic.h").write_text(text.replace(LAMBERT, FAULTS[kind]))
    else:
        write_mistake(next(m for m in mistakes(lesson) if m.name == kind), out)
    if tag:
        first = _lesson_files(lesson)[0].name
        text = (out / first).read_text()
        marker = f"// BEGIN SOLUTION {lesson}\n"
        (out / first).write_text(text.replace(marker, marker + f"        // {tag}\n", 1))
    return out


def write_class(out: Path, lesson: str = LESSON, size: int = CLASS_SIZE) -> list[Path]:
    """`size` submissions: one crashing and one hanging (L04), the rest the solution and the
    known-wrong versions in turn, each distinct (a comment naming the student)."""
    kinds = ["crash", "hang"] if lesson == "L04" else []
    others = ["solution", *(m.name for m in mistakes(lesson))]
    kinds += [others[i % len(others)] for i in range(size - len(kinds))]
    return [write_submission(out / f"student{i:02d}-{k}", lesson, k, tag=f"student {i}")
            for i, k in enumerate(kinds)]  # fmt: skip


def noop() -> dict[str, Any]:
    return {}


def _row(case: str, engine: str, threads: int, metric: str, value: float, unit: str,
         **extra: Any) -> dict[str, Any]:  # fmt: skip
    return {"case": case, "renderer": engine, "threads": threads, "metric": metric,
            "value": value, "unit": unit} | extra  # fmt: skip


def suite_batch(scenes: bool = False) -> list[dict[str, Any]]:
    """The rows: the class graded serially, on 1 and on 2 workers (probes only unless
    `scenes`: with the scenes each submission also builds the extension and renders a dozen
    scenes, about 14 s a submission here), the references, the per-task overhead."""
    from distributed import Client, LocalCluster

    from lessons.cli import class_tasks, reference_checks
    from tracer.batch import Engine, Task, run_batch

    rows: list[dict[str, Any]] = []
    lesson = get_lesson(LESSON).id
    case = f"grade {CLASS_SIZE} x {lesson}" + ("" if scenes else " (probes)")
    with tempfile.TemporaryDirectory(prefix="rtlab-bench-batch-") as tmp:
        base = Path(tmp)
        subs = write_class(base / "subs")
        seconds: dict[int, float] = {}
        for workers in (0, 1, 2):
            out = base / f"grades-{workers}"
            tasks = class_tasks(subs, lesson, out, False, scenes)
            engine = "serial" if workers == 0 else f"dask-{workers}-workers"
            with contextlib.ExitStack() as stack:
                client = None
                if workers:  # the cluster's start timed apart: a class pays it once
                    start = time.perf_counter()
                    cluster = stack.enter_context(
                        LocalCluster(
                            n_workers=workers, threads_per_worker=1, dashboard_address=":0"
                        )
                    )
                    client = stack.enter_context(Client(cluster))
                    rows.append(_row("LocalCluster start", engine, workers, "seconds",
                                     time.perf_counter() - start, "s"))  # fmt: skip
                start = time.perf_counter()
                outcomes = run_batch(tasks, Engine(workers=0), client=client, progress=False)
                seconds[workers] = time.perf_counter() - start
            failed = sum(o.status != "ok" for o in outcomes)
            rows.append(_row(case, engine, max(workers, 1), "seconds", seconds[workers], "s",
                             submissions=len(tasks), failed=failed,
                             cluster_start_included=False))  # fmt: skip
        rows.append(_row(case, "dask 2 workers vs 1", 2, "speedup", seconds[1] / seconds[2],
                         "x"))  # fmt: skip
        # Every lesson's references into a cache of its own (nothing served from before).
        refs = base / "references"
        before = os.environ.get("RTLAB_REFERENCES")
        os.environ["RTLAB_REFERENCES"] = str(refs)
        try:
            from lessons.cli import render_reference
            from lessons.scene_checks import reference_file, reference_key

            checks = reference_checks(None)
            tasks = [Task(f"{c.lesson}-{c.name}", render_reference,
                          (c.lesson, c.name, str(refs)),
                          reference_file(c).with_suffix(".done.json"), reference_key(c))
                     for c in checks]  # fmt: skip
            start = time.perf_counter()
            outcomes = run_batch(tasks, Engine(workers=2), progress=False)
            rows.append(_row(f"references of {len(tasks)} scenes", "dask-2-workers", 2,
                             "seconds", time.perf_counter() - start, "s",
                             failed=sum(o.status != "ok" for o in outcomes)))  # fmt: skip
        finally:
            if before is None:
                os.environ.pop("RTLAB_REFERENCES", None)
            else:
                os.environ["RTLAB_REFERENCES"] = before
    # The overhead per task: no-op tasks through a running 2-worker cluster, one at a time
    # (the round trip: submit, schedule, run, result back) and 200 at once (the throughput).
    with (
        LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=":0") as cluster,
        Client(cluster) as client,
    ):
        client.submit(noop, pure=False).result()  # warm: the function's import on a worker
        n = 50
        start = time.perf_counter()
        for _ in range(n):
            client.submit(noop, pure=False).result()
        rows.append(_row("no-op task", "dask-2-workers", 2, "round trip",
                         (time.perf_counter() - start) / n * 1e3, "ms"))  # fmt: skip
        tasks = [Task(f"noop{i}", noop) for i in range(200)]
        start = time.perf_counter()
        run_batch(tasks, client=client, progress=False)
        rows.append(_row("200 no-op tasks in a batch", "dask-2-workers", 2, "per task",
                         (time.perf_counter() - start) / len(tasks) * 1e3, "ms"))  # fmt: skip
    return rows
