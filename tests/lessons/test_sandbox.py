"""The sandbox (lessons/sandbox.py) against real hostile submissions: each is built and run in
a child process under limits and answered in words: a compile error with the compiler's first
errors, an infinite loop as a hang with its limit, a segfault as a crash naming SIGSEGV, a
1 GiB allocation as out of memory, a printf flood cut at the limit, a stub as not implemented.
The solution itself passes."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from lessons.sandbox import (
    Limits,
    SubmissionError,
    build_extension,
    build_probe,
    render_in_child,
    run_probe,
)
from lessons.student import CORE, write_student_tree
from tests.helpers import ROOT

CLASSIC = (ROOT / "tracer" / "cpp" / "10_classic.h").read_text()
SOLUTION = "    return dot(N, L);\n"

# A probe: call the student's lambert_term() once and print what it returns.
MAIN = r"""
#include <cstdio>
#include "10_classic.h"
int main() {
    std::printf("lambert_term = %.17g\n", rt::lambert_term({0, 0, 1}, {0.6, 0, 0.8}));
    return 0;
}
"""

HOSTILE = {
    "compile_error": "    return dot(N, L)\n",  # the missing semicolon
    "hang": "    volatile double x = 0;\n    while (x >= 0) x = x + 1;\n    return x;\n",
    "crash": "    int *volatile p = nullptr;\n    return *p;\n",
    "memory": "    std::vector<char> big(size_t(1) << 30, 1);\n    return big[12345];\n",
    "flood": '    for (;;) std::printf("N.L is %g\\n", dot(N, L));\n',
}


def submit(tmp_path, body: str):
    text = CLASSIC.replace(SOLUTION, body)
    assert text != CLASSIC, "the injection changed nothing"
    text = text.replace("#pragma once\n", "#pragma once\n#include <cstdio>\n#include <vector>\n")
    hw = tmp_path / "hw"
    hw.mkdir()
    (hw / "10_classic.h").write_text(text)
    return hw


# Short limits, so the test is quick: a probe of one function needs milliseconds of CPU.
QUICK = Limits(cpu_s=2, wall_s=10, output_bytes=4096)


def test_the_solution_builds_and_answers(tmp_path):
    build = build_probe(submit(tmp_path, SOLUTION + "    // mine\n"), MAIN, tmp_path / "w")
    assert build.outcome.ok, build.outcome.output
    assert build.files == ["10_classic.h"]
    run = run_probe(build, [], QUICK)
    assert run.kind == "ok" and run.output == "lambert_term = 0.80000000000000004\n"


@pytest.mark.parametrize("kind", HOSTILE, ids=list(HOSTILE))
def test_a_hostile_submission_is_answered_clearly(kind, tmp_path):
    build = build_probe(submit(tmp_path, HOSTILE[kind]), MAIN, tmp_path / "w")
    if kind == "compile_error":
        assert build.outcome.kind == "compile_error" and build.binary is None
        assert "10_classic.h" in build.outcome.message and "error:" in build.outcome.message
        assert "expected ';'" in build.outcome.message
        return
    assert build.outcome.ok, build.outcome.output
    run = run_probe(build, [], QUICK)
    assert run.kind == kind, (run.kind, run.message, run.output[:500])
    expected = {
        "hang": "did not finish within 2 s of CPU",
        "crash": "crashed: SIGSEGV",
        "memory": "ran out of memory (the limit is 512 MiB)",
        "flood": "wrote more than 4 KiB of output",
    }[kind]
    assert expected in run.message
    if kind == "flood":
        assert len(run.output.encode()) == 4096 and run.output.startswith("N.L is 0.8\n")
    assert run.seconds < 10  # (QUICK's wall clock: the limit ended it, not the test's patience)


def test_a_wall_clock_hang_is_killed(tmp_path):
    """A submission that sleeps uses no CPU: the wall-clock limit must end it."""
    body = "    std::this_thread::sleep_for(std::chrono::hours(1));\n    return 0;\n"
    hw = submit(tmp_path, body)
    path = hw / "10_classic.h"
    path.write_text(path.read_text().replace("#include <cstdio>", "#include <thread>"))
    build = build_probe(hw, MAIN, tmp_path / "w")
    assert build.outcome.ok, build.outcome.output
    run = run_probe(build, [], Limits(cpu_s=2, wall_s=1.5))
    assert run.kind == "hang" and "1.5 s wall clock" in run.message


# A grader's process that runs a child which sleeps (it writes its pid first, then execs sleep,
# so the pid is the sleeper's), until the test interrupts it.
INTERRUPTED = """
import sys
from pathlib import Path
from lessons.sandbox import Limits, run_limited
pidfile = Path(sys.argv[1])
command = ["sh", "-c", f"echo $$ > {pidfile}.tmp && mv {pidfile}.tmp {pidfile} && exec sleep 600"]
try:
    run_limited(command, pidfile.parent, Limits(cpu_s=600, wall_s=600), "the probe")
except KeyboardInterrupt:
    sys.exit(3)
"""


def test_an_interrupted_grader_leaves_no_child_running(tmp_path):
    """Ctrl-C reaches the grader, not the student's child (a session of its own): the grader
    must kill the child's group before it gives up, or the child runs on to its limits."""
    pidfile = tmp_path / "child.pid"
    grader = subprocess.Popen(
        [sys.executable, "-c", INTERRUPTED, str(pidfile)], cwd=ROOT, env=os.environ
    )
    deadline = time.monotonic() + 30
    while not pidfile.exists():
        assert grader.poll() is None, "the grader ended before its child started"
        assert time.monotonic() < deadline, "the child never wrote its pid"
        time.sleep(0.05)
    child = int(pidfile.read_text())
    os.kill(child, 0)  # the child runs (raises if not): the check below could fail
    grader.send_signal(signal.SIGINT)
    assert grader.wait(timeout=30) == 3  # the interrupt came out as KeyboardInterrupt
    # The grader waits for the child it killed, so it is gone; one left running was handed to
    # init and is still there (a zombie, "Z", would be a killed one nobody reaped yet).
    stat = Path(f"/proc/{child}/stat")
    alive = stat.exists() and stat.read_text().split()[2] != "Z"
    if alive:
        os.kill(child, signal.SIGKILL)
    assert not alive, "the interrupted grader left its child running"


def test_a_stub_is_not_implemented(tmp_path):
    tree = tmp_path / "tree"
    write_student_tree("L04", tree)
    build = build_probe(tree, MAIN, tmp_path / "w")
    assert build.outcome.ok, build.outcome.output
    run = run_probe(build, [], QUICK)
    assert run.kind == "not_implemented"
    assert "not implemented: lambert_term (lesson L04)" in run.message


def test_a_submission_without_core_files_is_refused(tmp_path):
    (tmp_path / "hw").mkdir()
    (tmp_path / "hw" / "essay.txt").write_text("I did not write any C++")
    with pytest.raises(SubmissionError, match="no C\\+\\+ file named as in tracer/cpp/"):
        build_probe(tmp_path / "hw", MAIN, tmp_path / "w")


def reference_digest(scene) -> str:
    """What the project's own build (tracer._core) renders, one ray at a time."""
    import hashlib

    from tracer.render import render_with_stats
    from tracer.scene import load_scene

    result = render_with_stats(load_scene(scene), threads=2, progress=False, packets=False)
    return hashlib.sha256(result.image.tobytes()).hexdigest()


def test_an_extension_built_from_a_tree_renders_or_says_not_implemented(tmp_path):
    """One real build each way. An L08 tree holds the solution of every lesson the scene
    needs: its extension, built by the sandbox and loaded only in a child process, renders
    the Lambert scene bit for bit as the project's build does (-ffp-contract=off: no fused
    multiply-add, so -O1 against -O3 changes no rounding). An L04 tree's render reaches a stub
    (trace() of L07 comes first): exit status 86 and the function's name, never a signal."""
    scene = ROOT / "reference" / "scenes" / "lambert.toml"
    write_student_tree("L08", tmp_path / "tree08")
    # Every sphere and every offset ray origin calls L13's robust quadratic and offset, which
    # trees before L13 hold in their textbook form (GIVEN lines): bit for bit needs them solved
    # (test_a_tree_before_l13_renders_with_the_textbook_forms renders the tree as written).
    for name in ("02_ray.h", "05_sphere.h"):
        shutil.copyfile(CORE / name, tmp_path / "tree08" / "cpp" / name)
    build = build_extension(tmp_path / "tree08", tmp_path / "w08")
    assert build.outcome.ok, build.outcome.message
    run = render_in_child(build, scene)
    assert run.kind == "ok", (run.message, run.output[-2000:])
    assert f"image sha256 {reference_digest(scene)} " in run.output

    write_student_tree("L04", tmp_path / "tree04")
    build = build_extension(tmp_path / "tree04", tmp_path / "w04")
    assert build.outcome.ok, build.outcome.message
    run = render_in_child(build, scene)
    assert run.kind == "not_implemented" and run.returncode == 86, (run.message, run.output)
    assert "not implemented: trace (lesson L07)" in run.message
    assert "image sha256" not in run.output


def test_a_tree_before_l13_renders_with_the_textbook_forms(tmp_path):
    """L13 refines code that every sphere and every shadow ray runs (the quadratic's roots, the
    offset of a new ray's origin): a tree of an earlier lesson holds their textbook forms (the
    regions' GIVEN lines), never a stub, so that an L08 tree renders the shadows scene. Its
    image is the project's within a few pixels: on this unit-scale scene the textbook roots
    differ from the robust ones by a few ulps of t, which moves no pixel's colour by more than
    rounding, and a fixed epsilon of 1e-4 (against the error bound, ~1e-15 here) can only flip
    a shadow ray that grazes a blocker's silhouette; each flipped pixel changes the image's sum
    by at most 3 (three channels in [0, 1]): 3 flips, a sum within 9."""
    from lessons.markers import find_regions
    from tracer.render import render_with_stats
    from tracer.scene import load_scene

    scene = ROOT / "reference" / "scenes" / "shadows.toml"
    report = write_student_tree("L08", tmp_path / "tree08")
    refined = {r.function for r in find_regions(CORE) if r.lesson == "L13" and r.given}
    assert {r.function for r in report.given} == refined == {
        "offset_ray_origin", "quadratic_roots", "sphere_discriminant"
    }  # fmt: skip
    text = (tmp_path / "tree08" / "cpp" / "05_sphere.h").read_text()
    assert "b * b - a * (dot(f, f) - r2)" in text and "(b * inv_a) * d" not in text
    # The given code is the course's, not the student's: grading the tree takes L08 alone.
    from lessons.grader import touched_lessons
    from lessons.student import _submitted_files

    assert touched_lessons(_submitted_files(tmp_path / "tree08")) == ["L08"]
    build = build_extension(tmp_path / "tree08", tmp_path / "w08")
    assert build.outcome.ok, build.outcome.message
    run = render_in_child(build, scene)
    assert run.kind == "ok", (run.message, run.output[-2000:])
    got = float(run.output.rsplit(" sum ", 1)[1].split()[0])
    want = render_with_stats(load_scene(scene), threads=2, progress=False, packets=False)
    assert abs(got - float(want.image.sum(dtype="float64"))) <= 9


def test_the_limits_fit_a_small_machine(tmp_path, monkeypatch):
    """Gradescope's default machine has 768 MB: each child gets at most half of it (384 MiB),
    so two children at once leave the grader room, and a student's allocation that 512 MiB
    would allow ends as the child's own "memory" outcome, never as the container's OOM killer
    taking the grader. The build (about 300 MiB of address space) still fits."""
    from lessons.sandbox import MEMORY_FLOOR, address_space, memory_available

    assert address_space(Limits(), available=768 << 20) == 384 << 20
    assert address_space(Limits(), available=64 << 30) == Limits().memory_bytes
    assert address_space(Limits(), available=256 << 20) == MEMORY_FLOOR
    assert 0 < memory_available() <= os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    monkeypatch.setenv("RTLAB_SANDBOX_MEMORY", "768M")
    assert memory_available() == 768 << 20
    body = "    std::vector<char> big(size_t(400) << 20, 1);\n    return big[12345];\n"
    build = build_probe(submit(tmp_path, body), MAIN, tmp_path / "w")
    assert build.outcome.ok, build.outcome.message
    run = run_probe(build, [], QUICK)
    assert run.kind == "memory" and "(the limit is 384 MiB)" in run.message, run.message
    monkeypatch.delenv("RTLAB_SANDBOX_MEMORY")
    run = run_probe(build, [], QUICK)  # the same program under 512 MiB: the injection mattered
    assert run.kind == "ok", (run.kind, run.message)


def test_two_threads_building_nanobind_into_an_empty_cache_both_get_it(tmp_path, monkeypatch):
    """A grader builds a submission's probes and extension on two threads; with a cold cache
    both wanted nanobind's object at once, compiled it into one pid-named partial file, and the
    second rename found it gone (seen in a fresh clone's run). Now the second waits for the
    first's object: both succeed, one compile."""
    from concurrent.futures import ThreadPoolExecutor

    from lessons import sandbox

    compiles = []
    real = sandbox.run_limited

    def counted(command, *args, **kwargs):  # the real compile, counted
        compiles.append(command)
        return real(command, *args, **kwargs)

    monkeypatch.setattr(sandbox, "run_limited", counted)
    cache = tmp_path / "nanobind"
    with ThreadPoolExecutor(max_workers=2) as pool:
        got = list(pool.map(lambda _: sandbox.nanobind_object(cache), range(2)))
    assert got == [cache / "nb_combined.o"] * 2
    # Both threads asked before either had finished a compile of seconds: without the lock
    # both compiled (into the same file); with it the second took the first's object.
    assert len(compiles) == 1
    assert got[0].stat().st_size > 0
    assert [p.name for p in cache.glob("nb_combined*")] == ["nb_combined.o"]  # no partials left
