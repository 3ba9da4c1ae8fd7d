"""Other builds of the core for the tests: built with CMake and ninja into a folder of build/
(ninja rebuilds only what changed since the last run), checked to compile without a warning of
ours, and a set of tests run against each in a child process that loads it as tracer._core
(tests/with_core.py). tests/test_second_compiler.py builds with the compiler the .venv build was
not made with, tests/test_instruction_sets.py for AVX2 and for SSE2 alone (with CMake's default
compiler, c++)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from reference.core_build import ROOT, BuildError
from reference.core_build import build_core as _build

__all__ = ["ROOT", "build_core", "run_tests_with"]


def build_core(build: Path, *options: str) -> Path:
    """Configure and build the core into `build` with extra CMake `options` (-D...); the
    extension's path. Fails with the build's own output on an error or a warning of ours: the
    core builds without a warning of -Wall -Wextra, so it must in every build."""
    try:
        made = _build(build, *options)
    except BuildError as error:
        raise AssertionError(str(error)) from error
    assert not made.warnings, "\n".join(made.warnings)
    return made.so


def run_tests_with(so: Path, expected: str, *tests: str) -> None:
    """Run pytest on `tests` (paths and options) with `so` as tracer._core, which must be the
    build tests/with_core.py calls `expected`; fails with pytest's output."""
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "tests.with_core",
            str(so),
            expected,
            "-q",
            "-p",
            "no:cacheprovider",
            "-p",
            "no:xdist",
            *tests,
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        env={**os.environ, "OPENBLAS_NUM_THREADS": "1"},
    )
    assert run.returncode == 0, run.stdout[-6000:] + run.stderr[-3000:]
    assert " passed" in run.stdout.splitlines()[-1], run.stdout[-2000:]
