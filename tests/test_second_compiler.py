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

import shutil

from tests.core_builds import ROOT, build_core, run_tests_with

BUILD = ROOT / "build" / "clang"


def test_the_core_built_by_clang_passes_the_core_tests():
    clang = shutil.which("clang++")
    assert clang, "clang++ is missing: `make setup` installs Debian's clang package"
    so = build_core(BUILD, f"-DCMAKE_CXX_COMPILER={clang}")
    run_tests_with(
        so,
        "clang",
        "--deselect",
        "tests/tracer/test_cli_and_io.py::test_check_and_demo_verbs",
        "--ignore",
        "tests/tracer/test_viewer_browser.py",
        "tests/tracer",
    )
