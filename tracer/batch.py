"""One thin batch layer over ``dask.distributed``, shared by the batch verbs (``rtlab lesson
grade DIRS --out``, ``rtlab lesson references --all``, ``rtlab study stiff --workers``,
``rtlab bench convergence --workers``, ``rtlab bench batch``).

A batch is a list of :class:`Task`: one unit of work each (one submission, one scene's
references, one study family), carrying what it needs (a module-level function, which Dask
pickles by name, and small arguments: paths, names, numbers; never a live object), writing its
outputs atomically, and recording that it finished in a *done file* keyed by what went in
(:func:`digest`). A task whose done file holds its key is skipped, so an interrupted batch run
again does only what did not finish, and a retried task writes the same bytes again.

The engine (:class:`Engine`) is one of

- ``--workers N``: a ``LocalCluster`` of N worker processes (default one per core), one thread
  each: a task renders or compiles with its own threads or child processes;
- ``--scheduler ADDRESS``: an existing Dask cluster (``dask scheduler`` / ``dask worker``, or
  dask-jobqueue's ``SLURMCluster``: README "Batches on a cluster"); paths must then be on a file
  system the workers share;
- ``--workers 0``: serially in this process, without Dask (what the tests compare Dask with).

Faults are Dask's to handle: an exception in a task is retried (``retries``) and then reported;
a worker that dies (killed, out of memory) loses nothing, since the scheduler runs its tasks
again on another worker (up to ``distributed.scheduler.allowed-failures`` times, then the task
is reported as having killed its workers). A task's own verdict (a submission that crashed,
hung or flooded its output) is its result: ``{"status": "failed", "reason": ...}``, and the
batch goes on. The summary at the end lists what failed and why.
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import json
import os
import secrets
import socket
import sys
import time
import traceback
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tracer import interrupt

#: What a done file is called when a task names only its output directory.
DONE = ".rtlab-done.json"


class BatchError(ValueError):
    """Bad input to a batch: a --workers that is not a count, both --workers and --scheduler,
    two tasks of the same name."""


@dataclass(frozen=True)
class Engine:
    """Where a batch runs: ``workers`` processes of a LocalCluster (None: one per core; 0:
    serially in this process, no Dask) or an existing cluster's ``scheduler`` address."""

    workers: int | None = None
    scheduler: str | None = None

    @property
    def serial(self) -> bool:
        return self.scheduler is None and self.workers == 0

    def describe(self) -> str:
        if self.scheduler is not None:
            return f"the Dask scheduler at {self.scheduler}"
        if self.serial:
            return "this process (serially, without Dask)"
        n = self.workers or os.cpu_count() or 1
        return f"a local Dask cluster of {n} worker process{'es' if n != 1 else ''}"


@dataclass(frozen=True)
class Task:
    """One unit of work. ``function(*args)`` runs on a worker and returns a small JSON-able
    dict; its ``"status"`` is ``"ok"`` (the default) or ``"failed"`` (the unit's own fault,
    with a ``"reason"``: its outputs still written). ``done`` is the done file; ``key`` the
    digest of what went in (with ``done`` holding the same key, the task is skipped)."""

    name: str
    function: Callable[..., dict[str, Any]]
    args: tuple[Any, ...] = ()
    done: Path | None = None
    key: str = ""


@dataclass
class Outcome:
    """What became of one task: ``status`` ok, failed (its own verdict), error (it raised, or
    killed its workers, after Dask's retries) or skipped (finished by an earlier run)."""

    name: str
    status: str
    reason: str = ""
    data: dict[str, Any] = field(default_factory=dict)
    seconds: float = 0.0
    worker: str = ""


def digest(*parts: object, files: Iterable[Path] = ()) -> str:
    """A task's key: the digest of its arguments (their JSON) and the bytes of its input files
    (names and contents, in sorted order)."""
    h = hashlib.sha256(json.dumps([str(p) for p in parts]).encode())
    for path in sorted(Path(p) for p in files):
        h.update(b"\0" + path.name.encode() + b"\0" + path.read_bytes())
    return h.hexdigest()[:32]


def sources_digest(root: Path, patterns: Sequence[str]) -> str:
    """The digest of the source files under ``root`` matching ``patterns`` (their paths and
    bytes): part of a task's key, so that a change to the code that computes a result runs
    the task again (and of the lesson references' key: lessons/scene_checks.py)."""
    h = hashlib.sha256()
    for pattern in patterns:
        for path in sorted(root.glob(pattern)):
            if path.is_file() and "__pycache__" not in path.parts:
                h.update(str(path.relative_to(root)).encode() + b"\0" + path.read_bytes())
    return h.hexdigest()


def write_atomic(path: Path, text: str) -> None:
    """``text`` into ``path`` through a temporary file beside it, renamed over it."""
    from tracer.image import atomic_path

    with atomic_path(path) as tmp:
        tmp.write_text(text)


def finished(task: Task) -> dict[str, Any] | None:
    """The recorded result of a task that finished before with the same key, or None."""
    if task.done is None or not task.key:
        return None
    try:
        record = json.loads(task.done.read_text())
    except (OSError, ValueError):
        return None
    return record if record.get("key") == task.key else None


def execute(task: Task) -> dict[str, Any]:
    """Run one task where it is (a worker, or this process): skip it when its done file holds
    its key; otherwise call its function, then write the done file (after the outputs: a done
    file is only ever beside finished outputs). Returns the record, plus (not recorded) the
    seconds it took and the worker's host and process."""
    start = time.perf_counter()
    record = finished(task)
    ran = record is None
    if record is None:
        data = dict(task.function(*task.args))
        status = data.pop("status", "ok")
        reason = data.pop("reason", "")
        record = {"key": task.key, "name": task.name, "status": status, "reason": reason,
                  "data": data}  # fmt: skip
        if task.done is not None and task.key:
            write_atomic(task.done, json.dumps(record, indent=1, sort_keys=True) + "\n")
    where = f"{socket.gethostname()}:{os.getpid()}"
    return record | {"ran": ran, "seconds": time.perf_counter() - start, "worker": where}


def _outcome(task: Task, record: dict[str, Any]) -> Outcome:
    status = record["status"] if record.get("ran", True) else "skipped"
    return Outcome(task.name, status, record.get("reason", ""), record.get("data", {}),
                   record.get("seconds", 0.0), record.get("worker", ""))  # fmt: skip


def _error(task: Task, error: BaseException) -> Outcome:
    name = type(error).__name__
    text = str(error).strip().splitlines()
    return Outcome(task.name, "error", f"{name}: {text[0] if text else ''}".rstrip(": "))


class _Progress:
    """tqdm's bar over the tasks, its postfix the counts of done, failed and running."""

    def __init__(self, total: int, desc: str, enabled: bool | None) -> None:
        from tqdm import tqdm

        # enabled None: tqdm's own rule, a bar only on a terminal.
        disable = None if enabled is None else not enabled
        self.bar = tqdm(total=total, desc=desc, unit="task", disable=disable, file=sys.stderr)
        self.counts = {"done": 0, "failed": 0, "skipped": 0}
        self.running = 0

    def add(self, outcome: Outcome) -> None:
        key = {"ok": "done", "skipped": "skipped"}.get(outcome.status, "failed")
        self.counts[key] += 1
        self.bar.update(1)
        self.show()

    def show(self) -> None:
        self.bar.set_postfix(self.counts | {"running": self.running}, refresh=True)

    def close(self) -> None:
        self.bar.close()


@contextlib.contextmanager
def client_for(engine: Engine) -> Iterator[Any]:
    """A ``distributed.Client`` for the engine (None for the serial one): a LocalCluster of
    processes, one thread each, closed at the end, or the given scheduler's."""
    if engine.serial:
        yield None
        return
    from distributed import Client, LocalCluster

    if engine.scheduler is not None:
        with Client(engine.scheduler) as client:
            yield client
        return
    n = engine.workers or os.cpu_count() or 1
    # processes: each task compiles and renders with its own threads and child processes, and
    # a worker that dies takes only its own task; the dashboard on a free port, never 8787
    # (a second cluster on the machine, or a scheduler the user started, may hold it).
    with (
        LocalCluster(
            n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0"
        ) as cluster,
        Client(cluster) as client,
    ):
        yield client


def run_batch(
    tasks: Sequence[Task],
    engine: Engine | None = None,
    *,
    client: Any = None,
    retries: int = 1,
    desc: str = "batch",
    progress: bool | None = None,
) -> list[Outcome]:
    """Run the tasks on the engine (or on a ``client`` already connected); the outcomes in the
    tasks' order, whatever order they finished in. Tasks finished before are skipped without
    being sent. ``retries``: how often Dask runs a task again that raised (its own errors; a
    lost worker's tasks are run again by the scheduler regardless)."""
    names = [t.name for t in tasks]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise BatchError(f"two tasks named {twice[0]!r}: each task's name must be its own")
    outcomes: dict[str, Outcome] = {}
    todo = []
    for task in tasks:
        record = finished(task)
        if record is not None:
            outcomes[task.name] = _outcome(task, record | {"ran": False})
        else:
            todo.append(task)
    bar = _Progress(len(tasks), desc, progress)
    for outcome in outcomes.values():
        bar.add(outcome)
    try:
        if todo and client is None and (engine is None or engine.serial):
            for task in todo:
                interrupt.raise_if_interrupted()  # one swallowed on the way (tracer/interrupt.py)
                outcomes[task.name] = _serial(task, retries, bar)
        elif todo:
            with contextlib.ExitStack() as stack:
                if client is None:
                    assert engine is not None
                    client = stack.enter_context(client_for(engine))
                outcomes.update(_distributed(client, todo, retries, bar))
    finally:
        bar.close()
    return [outcomes[t.name] for t in tasks]


def _serial(task: Task, retries: int, bar: _Progress) -> Outcome:
    bar.running = 1
    bar.show()
    for attempt in range(retries + 1):
        try:
            outcome = _outcome(task, execute(task))
            break
        except Exception as error:  # as Dask: retried, then reported
            if attempt == retries:
                outcome = _error(task, error)
                outcome.data["traceback"] = traceback.format_exc()
    bar.running = 0
    bar.add(outcome)
    return outcome


def _distributed(client: Any, todo: list[Task], retries: int, bar: _Progress) -> dict[str, Outcome]:
    from distributed import wait

    run = secrets.token_hex(4)
    futures = {
        client.submit(
            execute, task, key=f"rtlab-{task.name}-{run}", retries=retries, pure=False
        ): task
        for task in todo
    }
    outcomes: dict[str, Outcome] = {}
    pending = set(futures)
    try:
        while pending:
            try:
                done, pending = wait(pending, timeout=0.5, return_when="FIRST_COMPLETED")
            except TimeoutError:  # none finished in the half second: count the running ones
                done = set()
            for future in done:
                task = futures[future]
                if future.status == "finished":
                    outcomes[task.name] = _outcome(task, future.result())
                else:  # its own exception after the retries, or KilledWorker
                    error = future.exception()
                    outcomes[task.name] = _error(task, error)
                bar.add(outcomes[task.name])
            bar.running = _running(client, {f.key for f in pending})
            bar.show()
    except BaseException:  # interrupted: nothing more is sent; the done files say what finished
        client.cancel(list(pending))
        raise
    return outcomes


def _running(client: Any, keys: set[str]) -> int:
    """The pending tasks a worker is processing, at most one per worker thread (the scheduler
    assigns a few ahead of the threads)."""
    try:
        processing = client.processing()
        threads = sum(client.nthreads().values())
    except Exception:  # a scheduler that is going away: no count rather than no batch
        return 0
    return min(threads, sum(1 for ks in processing.values() for k in ks if k in keys))


def summary(outcomes: Sequence[Outcome], what: str = "tasks") -> str:
    """The lines printed at the end: the counts, then each task that failed and why."""
    count = {s: sum(o.status == s for o in outcomes) for s in ("ok", "failed", "error", "skipped")}
    lines = [
        f"rtlab: {len(outcomes)} {what}: {count['ok']} done, {count['failed']} failed, "
        f"{count['error']} errors, {count['skipped']} skipped (finished before)"
    ]
    for o in outcomes:
        if o.status in ("failed", "error"):
            lines.append(f"  {o.status}: {o.name}: {o.reason}")
        elif o.status == "skipped" and o.reason:  # its verdict from the run that finished it
            lines.append(f"  failed (an earlier run): {o.name}: {o.reason}")
    return "\n".join(lines)


def write_timings(path: Path, outcomes: Sequence[Outcome], engine: Engine) -> None:
    """The tasks' seconds and workers, in a file of their own (the results files hold no
    timing, so they do not depend on the engine); merged with an earlier run's for the tasks
    this run skipped."""
    try:
        old = json.loads(path.read_text()).get("tasks", {})
    except (OSError, ValueError, AttributeError):
        old = {}
    tasks = dict(old)
    for o in outcomes:
        if o.status != "skipped" or o.name not in tasks:
            tasks[o.name] = {"status": o.status, "seconds": round(o.seconds, 3),
                             "worker": o.worker}  # fmt: skip
    data = {"engine": engine.describe(), "tasks": dict(sorted(tasks.items()))}
    write_atomic(path, json.dumps(data, indent=1) + "\n")


# --- the verbs' flags ----------------------------------------------------------------------


def add_engine_arguments(
    parser: argparse.ArgumentParser, default_serial: bool = False, zero: str = ""
) -> None:
    """``--workers N`` and ``--scheduler ADDRESS`` (one or the other); ``default_serial``: no
    flag means 0 (the verb's own way without Dask, which ``zero`` says)."""
    group = parser.add_mutually_exclusive_group()
    zero = zero or "serially in this process, without Dask"
    default = "0" if default_serial else "one per core"
    group.add_argument(
        "--workers",
        type=_count,
        default=0 if default_serial else None,
        metavar="N",
        help=f"a local Dask cluster of N worker processes (default {default}; 0: {zero})",
    )
    group.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="an existing Dask cluster's scheduler, e.g. tcp://host:8786 (its workers must "
        "see the same paths)",
    )


def _count(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected a number of workers") from None
    if n < 0:
        raise argparse.ArgumentTypeError(f"{n}: expected 0 (serial) or more workers")
    return n


def engine_from(args: argparse.Namespace) -> Engine:
    return Engine(
        workers=getattr(args, "workers", None), scheduler=getattr(args, "scheduler", None)
    )
