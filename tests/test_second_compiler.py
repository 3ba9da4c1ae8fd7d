"""The core built by a second compiler passes the core's tests (tests/tracer) as the first one's
build does. `make` builds the core with Clang 19 (the Makefile's CORE_CXX, for speed); this test
builds it with GCC (g++), or with Clang where the .venv build is GCC's (a core built by `pip
install -e .` alone takes the system's default compiler). Code whose behaviour the standard leaves
undefined can still do what was meant under one compiler and something else under the other, and
neither the tests nor the sanitizers (`make sanitize`) notice. It happened: Vec3::operator[] read
component i as (&x)[i], and Debian's Clang 14 (and Clang 19) compiled the triangle test into one
that returned t = NaN, so every mesh went unseen (103 tests of tests/tracer failed under Clang
while GCC's build passed them).

The build goes to build/second-compiler-gcc (or -clang: a CMake cache made for one compiler
cannot be reused for another; ninja rebuilds only what changed), and the tests run in a
child process that loads it as tracer._core (tests/with_core.py, as `make sanitize` loads its
build). Left out there: the browser tests and the demo verb, which start processes of their own
(those run the .venv build, not this one), and nothing of the core is in them that the other tests
do not reach."""

import shutil

from tests.core_builds import ROOT, build_core, run_tests_with
from tracer import _core


def test_the_core_built_by_the_other_compiler_passes_the_core_tests():
    if _core.compiler_family == "clang":
        other, expected, package = shutil.which("g++"), "gcc", "g++"
    else:
        other = shutil.which("clang++-19") or shutil.which("clang++")
        expected, package = "clang", "clang-19"
    assert other, f"no {expected} compiler: `make setup` installs Debian's {package} package"
    so = build_core(ROOT / "build" / f"second-compiler-{expected}", f"-DCMAKE_CXX_COMPILER={other}")
    run_tests_with(
        so,
        expected,
        "--deselect",
        "tests/tracer/test_cli_and_io.py::test_check_and_demo_verbs",
        "--ignore",
        "tests/tracer/test_viewer_browser.py",
        "tests/tracer",
    )
