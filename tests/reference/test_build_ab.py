"""reference/build_ab.py: builds of the core timed against each other. The variants' specs, the
rounds' order, the summary's arithmetic and the check that every variant did the same work;
and end to end, a real second build of the core timed against the installed one."""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from reference.build_ab import (
    ABError,
    Cell,
    Variant,
    different_outputs,
    installed_core,
    order_of,
    parse_variant,
    summarize,
    workers,
)
from reference.core_build import ROOT, make_cxx, source_warnings


def test_a_builds_warnings_are_those_about_rtlab() -> None:
    """Ninja's output of a build: a warning in rtlab's sources and one about its options are
    kept; nanobind's, and Clang's note on the Xeon's CPU features (printed once a compiled file,
    a hundred lines a build there), are not."""
    output = "\n".join([
        "[1/3] Building CXX object CMakeFiles/_core.dir/tracer/cpp/bindings.cpp.o",
        "/w/tracer/cpp/12_packet.h:12:5: warning: unused variable 'x' [-Wunused-variable]",
        "clang++-19: warning: argument unused during compilation: '-mfoo'",
        "/w/.venv/lib/nanobind/src/nb_func.cpp:3:1: warning: something [-Wshadow]",
        "warning: invalid feature combination: +avx10.1-256; will be promoted to avx10.1-512"
        " [-Winvalid-feature-combination]",
        "[3/3] Linking CXX shared module _core.cpython-311-x86_64-linux-gnu.so",
    ])  # fmt: skip
    assert source_warnings(output) == (
        "/w/tracer/cpp/12_packet.h:12:5: warning: unused variable 'x' [-Wunused-variable]",
        "clang++-19: warning: argument unused during compilation: '-mfoo'",
    )


def test_a_spec_is_a_name_then_keys_with_shell_quoting() -> None:
    assert parse_variant("base") == Variant("base")
    assert parse_variant('c22 cxx=clang++-22 flags="-mtune=znver4 -DX=1" rev=HEAD~1') == Variant(
        "c22", cxx="clang++-22", flags="-mtune=znver4 -DX=1", rev="HEAD~1"
    )
    assert parse_variant("rkl cmake='-DRTLAB_MARCH=rocketlake -DX=1'").cmake == (
        "-DRTLAB_MARCH=rocketlake -DX=1"
    )
    assert parse_variant("installed").installed
    assert not parse_variant("mine").installed


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("b flag=-O2", "unknown key 'flag' (did you mean 'flags'?)"),
        ("b cxx", "'cxx' is not key=value"),
        ("cxx=g++", "expected a name first"),
        ("a/b", "a name of letters, digits"),
        ("b cxx=g++ cxx=clang++", "cxx given twice"),
        ("installed cxx=g++", "installed is make's build; it takes no keys"),
        ('b flags="-O2', "No closing quotation"),
    ],
)
def test_a_bad_spec_says_what_is_wrong(spec: str, message: str) -> None:
    with pytest.raises(ABError, match=re.escape(message)):
        parse_variant(spec)


def test_builds_here_use_the_compiler_make_used() -> None:
    # The Makefile's CORE_CXX (clang++-19) built the installed core (Debian Clang 19.1.7 ...):
    # a variant without cxx= is built as make builds it, packet_model's core too.
    from tracer import _core

    cxx = make_cxx()
    family, _, version = cxx.partition("++-")
    assert family == "clang" and _core.compiler_family == "clang"
    assert f"Clang {version}." in _core.compiler
    assert parse_variant("mine").cxx == cxx


def test_the_turns_reverse_every_other_round() -> None:
    names = ["a", "b", "c"]
    assert [order_of(r, names) for r in range(3)] == [names, names[::-1], names]


def test_each_round_is_a_ratio_within_that_round() -> None:
    # Round by round: b is 2x, then 1.25x, then 1x as fast as a; the machine's speed drifts
    # 2x between rounds, which the ratios do not see and the medians of times do.
    cell = Cell("ex25", 1, {"a": [0.2, 0.1, 0.1], "b": [0.1, 0.08, 0.1]}, {})
    a, b = summarize([cell], ["a", "b"])
    assert (a["variant"], a["speed_vs_first"], a["speed_min"], a["speed_max"]) == ("a", 1, 1, 1)
    assert b["speed_vs_first"] == pytest.approx(1.25)
    assert (b["speed_min"], b["speed_max"]) == pytest.approx((1.0, 2.0))
    assert a["seconds"] == 0.1 and b["seconds"] == 0.1  # medians of the times
    assert b["rounds"] == [0.1, 0.08, 0.1]


def test_outputs_must_be_the_same_bits_in_every_variant() -> None:
    same = Cell("ex25", 1, {}, {"a": {"d1"}, "b": {"d1"}})
    assert different_outputs([same], "a") == []
    other = Cell("ex25", 2, {}, {"a": {"d1"}, "b": {"d2"}})
    assert different_outputs([same, other], "a") == ["ex25, 2 thread(s): b differs from a"]
    varies = Cell("cornell-64", 1, {}, {"a": {"d1", "d3"}, "b": {"unsteady"}})
    assert different_outputs([varies], "a") == [
        "cornell-64, 1 thread(s): a's output varies",
        "cornell-64, 1 thread(s): b's output varies",
    ]


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "reference.build_ab", *args],
        capture_output=True, text=True, cwd=ROOT, timeout=600,
    )  # fmt: skip


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--variant", "installed"], "expected two or more, each its own name"),
        (
            ["--variant", "a", "--variant", "b rev=no-such-commit"],
            "rev=no-such-commit: not a commit",
        ),
        (["--variant", "a", "--variant", "a"], "expected two or more, each its own name"),
        (
            ["--variant", "installed", "--variant", "b", "--cases", "ex52"],
            "unknown case 'ex52' (did you mean 'ex25'?)",
        ),
        (["--variant", "installed", "--variant", "b", "--rounds", "0"], "--rounds: expected"),
        (
            ["--variant", "installed", "--variant", "b cxx=no-such-c++"],
            "compiler no-such-c++ is not on PATH",
        ),
        (
            ["--variant", "installed", "--variant", "b rev=no-such-commit"],
            "rev=no-such-commit: not a commit",
        ),
    ],
)
def test_usage_errors_stop_before_any_build(args: list[str], message: str) -> None:
    done = _run(*args)
    assert done.returncode == 2, done.stdout + done.stderr
    assert message in done.stderr
    assert "Traceback" not in done.stderr


def test_a_failing_case_names_its_variant() -> None:
    # A real worker with the installed core, asked for a case it does not have.
    so = installed_core()
    with workers([(Variant("mine"), so)]) as (worker,):
        assert worker.compiler  # the core's own name for its compiler
        with pytest.raises(ABError, match="variant mine: ABError: unknown case 'ex52'"):
            worker.ask({"case": "ex52", "threads": 1, "repeats": 1, "size": None})
        # The worker survives a failed request and answers the next one.
        answer = worker.ask({"case": "ex25", "threads": 1, "repeats": 2, "size": [64, 32]})
        assert answer["seconds"] > 0 and len(answer["digest"]) == 16


#: A build of the last commit's files (git archive), tuned for no particular processor: the
#: end-to-end tests' variant (both, so that the second finds it built).
HEAD_GENERIC = "head rev=HEAD flags=-mtune=generic"


def _cpp_is_head() -> bool:
    """Whether the checkout's C++ and CMakeLists are the last commit's (always so in CI's fresh
    clone; a developer's uncommitted change makes the installed core another program)."""
    return (
        subprocess.run(
            [
                "git",
                "-C",
                str(ROOT),
                "diff",
                "--quiet",
                "HEAD",
                "--",
                "tracer/cpp",
                "CMakeLists.txt",
            ]
        ).returncode
        == 0
    )


def test_a_commit_built_afresh_against_the_installed_core(tmp_path: Path) -> None:
    """A real build of the last commit's files, tuned for no particular processor, against
    make's build of the same source: both render Ex 25 to the same bits (tuning changes the
    schedule, not one IEEE operation: the build forbids contraction into fused multiply-adds),
    so the tool times them, and its rows agree with its own round times."""
    out = tmp_path / "ab.json"
    same_source = _cpp_is_head()
    done = _run(
        "--variant", "installed", "--variant", HEAD_GENERIC, "--cases", "ex25",
        "--threads", "1", "2", "--size", "96", "64", "--rounds", "2", "--repeats", "1",
        "--json", str(out), *([] if same_source else ["--allow-different"]),
    )  # fmt: skip
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    if same_source:
        assert "output differs" not in done.stdout
    commit = subprocess.run(
        ["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True, text=True, check=True
    ).stdout.strip()
    assert "-mtune=generic, commit HEAD" in done.stdout
    assert (ROOT / "build" / "ab" / "head" / "src.commit").read_text() == commit
    rows = json.loads(out.read_text())
    assert [(r["case"], r["threads"], r["variant"]) for r in rows] == [
        ("ex25", 1, "installed"),
        ("ex25", 1, "head"),
        ("ex25", 2, "installed"),
        ("ex25", 2, "head"),
    ]
    for base, other in (rows[0:2], rows[2:4]):
        assert base["speed_vs_first"] == 1.0
        ratios = sorted(b / t for b, t in zip(base["rounds"], other["rounds"], strict=True))
        assert other["speed_min"] == pytest.approx(ratios[0])
        assert other["speed_max"] == pytest.approx(ratios[-1])
        assert other["flags"] == "-mtune=generic" and other["rev"] == "HEAD"
        assert other["compiler"].startswith("Debian Clang")
    configured = ROOT / "build" / "ab" / "head" / "build" / "rtlab-options.json"
    configuration = json.loads(configured.read_text())
    assert "-DCMAKE_CXX_FLAGS=-mtune=generic" in configuration
    # The exported source is part of it, so that the same name later given to this checkout's
    # files is configured afresh (CMake refuses a build folder made from another source).
    assert f"source={ROOT / 'build' / 'ab' / 'head' / 'src'}" in configuration


def test_a_worker_that_dies_is_named_with_its_error(tmp_path: Path) -> None:
    not_a_core = tmp_path / "_core.so"
    not_a_core.write_text("not an extension")
    dies = r"(?s)the worker of variant broken stopped \(exit 1\):.*ImportError"
    with pytest.raises(ABError, match=dies), workers([(Variant("broken"), not_a_core)]):
        pass


def _workers_running() -> list[str]:
    found = []
    for cmdline in Path("/proc").glob("[0-9]*/cmdline"):
        try:
            words = cmdline.read_bytes().split(b"\0")
        except OSError:  # the process ended while we looked
            continue
        if b"reference.build_ab" in words and b"--worker" in words:
            found.append(cmdline.parent.name)
    return found


def test_ctrl_c_stops_the_workers_and_writes_nothing(tmp_path: Path) -> None:
    """Interrupted in its rounds, the tool stops its workers, says so and writes no rows (the
    same build of this checkout as above, so ninja has nothing to do when both run)."""
    out = tmp_path / "ab.json"
    assert _workers_running() == []
    run = subprocess.Popen(
        [sys.executable, "-m", "reference.build_ab", "--variant", "installed",
         "--variant", HEAD_GENERIC, "--cases", "ex25", "--size", "96", "64",
         "--rounds", "100000", "--repeats", "1", "--allow-different", "--json", str(out)],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    assert run.stdout is not None
    try:
        for line in run.stdout:  # the rounds have begun once the first is reported
            if line.startswith("round 1 of"):
                break
        else:
            pytest.fail(f"no round reported: {run.wait()} {run.stderr.read()[-3000:]}")  # type: ignore[union-attr]
        assert len(_workers_running()) == 2  # the two variants' workers
        run.send_signal(signal.SIGINT)
        code = run.wait(timeout=60)
    finally:
        if run.poll() is None:
            run.kill()
    assert run.stderr is not None
    assert code == 130, run.stderr.read()[-3000:]
    assert "build_ab: interrupted; no rows written" in run.stderr.read()
    assert not out.exists() and list(tmp_path.iterdir()) == []  # nor a temporary file
    assert _workers_running() == []
