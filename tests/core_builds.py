"""Other builds of the core for the tests: built with CMake and ninja into a folder of build/
(ninja rebuilds only what changed since the last run), checked to compile without a warning of
ours, and a set of tests run against each in a child process that loads it as tracer._core
(tests/with_core.py). tests/test_second_compiler.py builds with the compiler the .venv build was
not made with, tests/test_instruction_sets.py for AVX2 and for SSE2 alone (with CMake's default
compiler, c++)."""

from __future__ import annotations

import glob
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
VENV_BIN = Path(sys.executable).parent


def build_core(build: Path, *options: str) -> Path:
    """Configure and build the core into `build` with extra CMake `options` (-D...); the
    extension's path. Fails with the build's own output on an error or a warning of ours."""
    nanobind = subprocess.run(
        [sys.executable, "-m", "nanobind", "--cmake_dir"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    configure = [
        str(VENV_BIN / "cmake"),
        "-S",
        str(ROOT),
        "-B",
        str(build),
        "-G",
        "Ninja",
        f"-DCMAKE_MAKE_PROGRAM={VENV_BIN / 'ninja'}",
        "-DCMAKE_BUILD_TYPE=Release",
        f"-DPython_EXECUTABLE={sys.executable}",
        f"-Dnanobind_DIR={nanobind}",
        *options,
    ]
    configured = subprocess.run(configure, capture_output=True, text=True)
    assert configured.returncode == 0, configured.stdout[-4000:] + configured.stderr[-4000:]
    built = subprocess.run(
        [str(VENV_BIN / "cmake"), "--build", str(build)], capture_output=True, text=True
    )
    assert built.returncode == 0, built.stdout[-4000:] + built.stderr[-4000:]
    # The core builds without a warning of -Wall -Wextra; so it must in every build (nanobind's
    # own sources are not ours, and ninja names each file it compiles).
    ours = [
        line for line in built.stdout.splitlines() if "warning:" in line and "nanobind" not in line
    ]
    assert not ours, "\n".join(ours)
    (so,) = glob.glob(str(build / "_core.*.so"))
    return Path(so)


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
