"""The batch layer (tracer/batch.py) on a real LocalCluster: results that do not depend on the
engine, faults that fail their own task, a worker killed mid-batch, an interrupted batch run
again. Probes only (--no-scenes): the point is the batch machinery, and a submission's probes
build in about a second (a scene check's extension and renders take 14)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import cloudpickle
import pytest
from distributed import Client, LocalCluster

from lessons.cli import class_summary, class_tasks
from reference.bench_batch import write_submission
from tracer.batch import Engine, Task, run_batch, summary

# The workers unpickle this module's task functions by value (they cannot import tests.*).
cloudpickle.register_pickle_by_value(sys.modules[__name__])


@pytest.fixture(scope="module")
def client():
    """Two worker processes, one thread each, as `--workers 2` starts them; once per module
    (a cluster starts in about 2 s)."""
    with (
        LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=":0") as cluster,
        Client(cluster) as c,
    ):
        yield c


@pytest.fixture(scope="module")
def subs(tmp_path_factory) -> Path:
    base = tmp_path_factory.mktemp("subs")
    for kind in ("solution", "two_sided_lambert", "light_direction_reversed", "crash",
                 "flood", "hang"):  # fmt: skip
        write_submission(base / kind, "L04", kind)
    return base


def _grade(subs: Path, names: list[str], out: Path, engine: Engine | None = None, client=None):
    tasks = class_tasks([subs / n for n in names], "L04", out, False, False)
    return run_batch(tasks, engine, client=client, progress=False)


def _files(out: Path) -> dict[str, bytes]:
    return {str(p.relative_to(out)): p.read_bytes() for p in sorted(out.rglob("results.json"))}


def test_results_do_not_depend_on_the_engine(tmp_path: Path, subs: Path, client) -> None:
    names = ["solution", "two_sided_lambert", "light_direction_reversed", "crash"]
    made = {}
    for engine in ("serial", "1 worker", "2 workers"):
        out = tmp_path / engine
        if engine == "serial":
            outcomes = _grade(subs, names, out, Engine(workers=0))
        elif engine == "1 worker":
            with (
                LocalCluster(n_workers=1, threads_per_worker=1, dashboard_address=":0") as one,
                Client(one) as c1,
            ):
                outcomes = _grade(subs, names, out, client=c1)
        else:
            outcomes = _grade(subs, names, out, client=client)
        assert [o.status for o in outcomes] == ["ok", "ok", "ok", "failed"], summary(outcomes)
        summ = json.dumps(class_summary("L04", outcomes), indent=1).encode()
        made[engine] = _files(out) | {"summary": summ}
        assert len(made[engine]) == len(names) + 1
    assert made["serial"] == made["1 worker"] == made["2 workers"]
    # And they are what one submission's grading says (timing aside).
    solution = json.loads(made["serial"]["solution/results.json"])
    assert "execution_time" not in solution
    assert solution["score"] == pytest.approx(50.0, abs=1e-3)


def test_a_crash_a_flood_and_a_hang_each_fail_their_own_task(
    tmp_path: Path, subs: Path, client
) -> None:
    names = ["crash", "solution", "flood", "hang"]
    outcomes = _grade(subs, names, tmp_path / "g", client=client)
    got = {o.name: o for o in outcomes}
    assert got["solution"].status == "ok"
    for kind, said in (("crash", "SIGSEGV"), ("flood", "more than 64 KiB"),
                       ("hang", "did not finish within")):  # fmt: skip
        assert got[kind].status == "failed", got[kind]
        assert got[kind].reason.startswith(f"{kind} in "), got[kind].reason
        data = json.loads((tmp_path / "g" / kind / "results.json").read_text())
        assert any(said in t["output"] for t in data["tests"]), kind
    text = summary(outcomes, "submissions")
    assert "4 submissions: 1 done, 3 failed, 0 errors" in text
    assert all(f"failed: {k}: {k} in" in text for k in ("crash", "flood", "hang"))
    # Run again, everything is skipped, and the summary still names what failed and why.
    again = summary(_grade(subs, names, tmp_path / "g", client=client), "submissions")
    assert "0 done, 0 failed, 0 errors, 4 skipped" in again
    assert all(f"failed (an earlier run): {k}: {k} in" in again for k in ("crash", "flood", "hang"))
    assert "solution" not in again


def test_a_worker_killed_mid_batch_loses_nothing(tmp_path: Path, subs: Path, client) -> None:
    names = ["hang", "solution", "two_sided_lambert", "light_direction_reversed", "flood"]
    pids = client.run(os.getpid)
    result: list = []
    thread = threading.Thread(
        target=lambda: result.append(_grade(subs, names, tmp_path / "g", client=client))
    )
    thread.start()
    victim = None
    deadline = time.monotonic() + 60
    while victim is None and time.monotonic() < deadline:
        # The worker grading the hanging submission (a few seconds of probes): kill it while
        # its task runs, with its probe program's children.
        for worker, keys in client.processing().items():
            if any(str(k).startswith("rtlab-hang-") for k in keys) and worker in pids:
                time.sleep(1.0)  # well inside the task (it costs two probes' 2 s CPU limits)
                victim = pids[worker]
                os.kill(victim, signal.SIGKILL)
                break
        time.sleep(0.05)
    assert victim is not None, "the hanging submission's task never ran"
    thread.join(timeout=120)
    assert not thread.is_alive()
    outcomes = result[0]
    assert {o.name: o.status for o in outcomes} == {
        "hang": "failed", "solution": "ok", "two_sided_lambert": "ok",
        "light_direction_reversed": "ok", "flood": "failed",
    }  # fmt: skip
    assert all((tmp_path / "g" / n / "results.json").exists() for n in names)
    assert victim not in client.run(os.getpid).values()  # the nanny started a new one
    hang = next(o for o in outcomes if o.name == "hang")
    assert not hang.worker.endswith(f":{victim}")  # run again, by another process


def test_an_interrupted_batch_run_again_skips_what_finished(tmp_path: Path, subs: Path) -> None:
    names = ["solution", "two_sided_lambert", "light_direction_reversed", "crash", "hang"]
    out = tmp_path / "g"
    command = [sys.executable, "-m", "tracer.cli", "lesson", "grade",
               *(str(subs / n) for n in names), "--lesson", "L04", "--out", str(out),
               "--no-scenes", "--workers", "0"]  # fmt: skip
    child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and len(list(out.glob("*/.rtlab-done.json"))) < 2:
        time.sleep(0.05)
    child.send_signal(signal.SIGINT)
    child.communicate(timeout=60)
    assert child.returncode != 0  # interrupted
    before = {p.parent.name: p.stat().st_mtime_ns for p in out.glob("*/results.json")}
    finished = {p.parent.name for p in out.glob("*/.rtlab-done.json")}
    assert 2 <= len(finished) < len(names), finished
    outcomes = _grade(subs, names, out, Engine(workers=0))
    ran = {o.name for o in outcomes if o.status != "skipped"}
    assert {o.name for o in outcomes if o.status == "skipped"} == finished
    assert ran == set(names) - finished
    for name in finished:  # not written again
        assert (out / name / "results.json").stat().st_mtime_ns == before[name]
    assert all((out / n / "results.json").exists() for n in names)


# A serial batch whose first task's interrupt is swallowed: SIGINT raised (raise_signal runs
# the handler at once) inside a __del__, where Python prints "Exception ignored" and goes on.
SWALLOWED = """
import signal
from tracer import interrupt
from tracer.batch import Engine, Task, run_batch

class Swallows:
    def __del__(self):
        signal.raise_signal(signal.SIGINT)

def first():
    Swallows()  # collected at once
    return {}

ran = []
interrupt.install()
try:
    run_batch([Task("first", first), Task("second", lambda: ran.append(1) or {})],
              Engine(workers=0), progress=False)
    print("not interrupted")
except interrupt.Interrupted as exc:
    print("interrupted by", exc.signum, "; the second task ran" if ran else "; nothing more ran")
"""


def test_an_interrupt_swallowed_by_a_task_still_stops_a_serial_batch() -> None:
    """The test above failed once in CI's way (the grade exited 0 after SIGINT; not seen again
    in 63 runs). A signal whose exception is lost in a finaliser is the one way found to get
    there: it must still stop the batch before its next task (tracer/interrupt.py)."""
    run = subprocess.run([sys.executable, "-c", SWALLOWED], capture_output=True, text=True,
                         cwd=Path(__file__).parents[2], timeout=60)  # fmt: skip
    assert "Exception ignored" in run.stderr, run.stderr  # the interrupt was swallowed once
    assert run.stdout.strip() == f"interrupted by {int(signal.SIGINT)} ; nothing more ran"


ATTEMPTS: list[str] = []


def flaky(log: str, fail: bool) -> dict:
    with open(log, "a") as f:
        f.write("x")
    if fail:
        raise RuntimeError("the task's own fault")
    return {"value": 1}


@pytest.mark.parametrize("engine", ["serial", "dask"])
def test_a_task_that_raises_is_retried_then_reported(tmp_path: Path, client, engine) -> None:
    tasks = [Task("bad", flaky, (str(tmp_path / "bad.log"), True)),
             Task("good", flaky, (str(tmp_path / "good.log"), False))]  # fmt: skip
    if engine == "serial":
        outcomes = run_batch(tasks, Engine(workers=0), retries=1, progress=False)
    else:
        outcomes = run_batch(tasks, client=client, retries=1, progress=False)
    bad, good = outcomes
    assert (bad.status, good.status) == ("error", "ok")
    assert bad.reason == "RuntimeError: the task's own fault"
    assert (tmp_path / "bad.log").read_text() == "xx"  # run, then retried once
    assert (tmp_path / "good.log").read_text() == "x"
    assert "error: bad: RuntimeError: the task's own fault" in summary(outcomes)


def test_the_cli_grades_a_class_and_keeps_one_submission_as_before(
    tmp_path: Path, subs: Path
) -> None:
    base = [sys.executable, "-m", "tracer.cli", "lesson", "grade"]
    done = subprocess.run(
        [*base, str(subs / "solution"), str(subs / "two_sided_lambert"), "--lesson", "L04",
         "--out", str(tmp_path / "g"), "--no-scenes", "--workers", "0"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    data = json.loads((tmp_path / "g" / "summary.json").read_text())
    assert [r["name"] for r in data["submissions"]] == ["solution", "two_sided_lambert"]
    assert data["submissions"][1]["diagnosis"].startswith("L04: wrong: diffuse")
    assert "two_sided_lambert" in (tmp_path / "g" / "summary.txt").read_text()
    timings = json.loads((tmp_path / "g" / "timings.json").read_text())
    assert set(timings["tasks"]) == {"solution", "two_sided_lambert"}
    # One submission without --out: as before (results.json with its execution_time).
    one = subprocess.run(
        [*base, str(subs / "solution"), "--lesson", "L04", "--no-scenes", "--json",
         str(tmp_path / "r.json")], capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert one.returncode == 0, one.stderr
    assert "execution_time" in json.loads((tmp_path / "r.json").read_text())
    # Several without --out: a clear error.
    two = subprocess.run([*base, str(subs / "solution"), str(subs / "crash")],
                         capture_output=True, text=True, timeout=60)  # fmt: skip
    assert two.returncode == 2 and "give --out GRADES" in two.stderr


def test_the_study_on_dask_writes_what_its_process_pool_writes(tmp_path: Path, client) -> None:
    from study.run import run

    run(tmp_path / "jobs", quick=True, family="scaling", jobs=1)
    engine = Engine(scheduler=client.scheduler.address)
    run(tmp_path / "dask", quick=True, family="scaling", engine=engine)
    for name in ("breakdown.json", "failures.json"):
        assert (tmp_path / "jobs" / name).read_bytes() == (tmp_path / "dask" / name).read_bytes()

    def untimed(where: str) -> list:  # the rows' time_per_ray_s is a measured time
        rows = json.loads((tmp_path / where / "rows.json").read_text())
        return [r for r in rows if r["metric"] != "time_per_ray_s"]

    assert untimed("jobs") == untimed("dask") and untimed("jobs")
    shard = tmp_path / "dask" / "shards" / "scaling-quick.json"
    made = shard.stat().st_mtime_ns
    run(tmp_path / "dask", quick=True, family="scaling", engine=engine)  # run again: skipped
    assert shard.stat().st_mtime_ns == made
    assert untimed("jobs") == untimed("dask")


def test_convergence_on_dask_times_a_case_per_task_under_its_machines_lock(client) -> None:
    from reference.convergence import batched

    tiny = {"width": 8, "height": 8, "sweep": (4,), "reference_spp": 64, "repeats": 1,
            "renderers": ("rtlab",)}  # fmt: skip
    cases = (("a", "path", tiny), ("b", "path", tiny | {"sweep": (4, 8)}))
    made = dict(batched(Engine(scheduler=client.scheduler.address), cases))
    assert [r["spp"] for r in made["a"]] == [4] and [r["spp"] for r in made["b"]] == [4, 8]
    row = made["b"][1]
    assert row["renderer"] == "rtlab" and row["seconds"] > 0 and row["value"] > 0
    assert row["host"] and row["case"] == "cornell_box-8x8"


def test_the_references_batch_renders_each_scene_once(tmp_path: Path, client, monkeypatch):
    from lessons.cli import cmd_references, reference_checks
    from lessons.scene_checks import reference_file

    monkeypatch.setenv("RTLAB_REFERENCES", str(tmp_path / "refs"))
    engine = Engine(scheduler=client.scheduler.address)
    checks = reference_checks("L04")
    assert len(checks) >= 2
    assert cmd_references("L04", False, engine) == 0
    files = [reference_file(c) for c in checks]
    assert all(f.is_file() and f.is_relative_to(tmp_path / "refs") for f in files)
    made = [f.stat().st_mtime_ns for f in files]
    assert cmd_references("L04", False, engine) == 0  # finished before: skipped
    assert [f.stat().st_mtime_ns for f in files] == made
    assert cmd_references(None, False, engine) == 2  # neither --all nor --lesson
