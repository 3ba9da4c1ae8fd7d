"""The core built by a second compiler, Clang, passes the core's tests (tests/tracer) as GCC's
build does. GCC is the compiler `make` uses; code whose behaviour the standard leaves undefined
can still do what was meant under GCC and something else under Clang, and neither the tests
nor the sanitizers (`make sanitize`) notice. It happened: Vec3::operator[] read component i as
(&x)[i], and Debian's Clang 14 (and Clang 19) compiled the triangle test into one that returned
t = NaN, so every mesh went unseen (103 tests of tests/tracer failed under Clang).

The build goes to build/clang (ninja rebuilds only what changed), and the tests run in a child
process that loads it as tracer._core (tests/with_core.py, as `make sanitize` loads its build).
Left out there: the browser tests and the demo verb, which start processes of their own (those
run the .venv build, not this one), and nothing of the core is in them that the other tests do
not reach."""

import glob
import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BUILD = ROOT / "build" / "clang"
VENV_BIN = Path(sys.executable).parent


def test_the_core_built_by_clang_passes_the_core_tests():
    clang = shutil.which("clang++")
    assert clang, "clang++ is missing: `make setup` installs Debian's clang package"
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
        str(BUILD),
        "-G",
        "Ninja",
        f"-DCMAKE_MAKE_PROGRAM={VENV_BIN / 'ninja'}",
        f"-DCMAKE_CXX_COMPILER={clang}",
        "-DCMAKE_BUILD_TYPE=Release",
        f"-DPython_EXECUTABLE={sys.executable}",
        f"-Dnanobind_DIR={nanobind}",
    ]
    subprocess.run(configure, capture_output=True, text=True, check=True)
    built = subprocess.run(
        [str(VENV_BIN / "cmake"), "--build", str(BUILD)], capture_output=True, text=True
    )
    assert built.returncode == 0, built.stdout[-4000:] + built.stderr[-4000:]
    # The core builds without a warning under GCC's -Wall -Wextra; so it must under Clang's
    # (nanobind's own sources are not ours, and ninja names each file it compiles).
    ours = [
        line for line in built.stdout.splitlines() if "warning:" in line and "nanobind" not in line
    ]
    assert not ours, "\n".join(ours)
    (so,) = glob.glob(str(BUILD / "_core.*.so"))
    tests = [
        "-q",
        "-p",
        "no:cacheprovider",
        "-p",
        "no:xdist",
        "--deselect",
        "tests/tracer/test_cli_and_io.py::test_check_and_demo_verbs",
        "--ignore",
        "tests/tracer/test_viewer_browser.py",
        "tests/tracer",
    ]
    run = subprocess.run(
        [sys.executable, "-m", "tests.with_core", so, "clang", *tests],
        cwd=ROOT,
        capture_output=True,
        text=True,
        env={**os.environ, "OPENBLAS_NUM_THREADS": "1"},
    )
    assert run.returncode == 0, run.stdout[-6000:] + run.stderr[-3000:]
    assert " passed" in run.stdout.splitlines()[-1], run.stdout[-2000:]
