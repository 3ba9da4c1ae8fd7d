"""Fixtures shared by the tests (helpers to import are in tests/helpers.py)."""

from __future__ import annotations

import os
import shutil
import sys
import tempfile

import pytest

from lessons.sandbox import BUILD_CACHE_ENV

# One build cache for the whole session (lessons/sandbox.py cached_build): made by the process
# that starts the session, before pytest-xdist starts its workers (they and every child the
# tests start inherit the variable), removed when the session ends. Each session builds every
# distinct submission once, a fresh one included; a cache left by an earlier run is never used.
_OWN_CACHE: list[str] = []


def pytest_configure(config: pytest.Config) -> None:
    if hasattr(config, "workerinput") or os.environ.get(BUILD_CACHE_ENV):
        return  # a worker (the variable is its controller's), or the caller gave one
    _OWN_CACHE.append(tempfile.mkdtemp(prefix="rtlab-test-builds-"))
    os.environ[BUILD_CACHE_ENV] = _OWN_CACHE[0]


def pytest_unconfigure(config: pytest.Config) -> None:
    for path in _OWN_CACHE:
        shutil.rmtree(path, ignore_errors=True)
        os.environ.pop(BUILD_CACHE_ENV, None)
    _OWN_CACHE.clear()


# Modules whose module-scoped fixtures cost many seconds (tests/reports: grades, a site, a
# browser: 8 to 35 s each; tests/study: the quick study, 20-35 s; tests/batch: one LocalCluster;
# the executed notebook, 10 s): under `--dist loadgroup` (the Makefile's) each runs whole on one
# worker, so that its fixtures are set up once, not once per worker; every other test is its own
# unit, handed to whichever worker is free (at most three waiting on each). pytest-xdist 3.8's
# own loadgroup marks a group by renaming the test's nodeid, which pytest 9 no longer lets it do
# (every test stays alone), so the units are given here, by module.
GROUPED = (
    "tests/reports/",
    "tests/study/",
    "tests/batch/",
    "tests/tracer/test_notebook.py",
    # Its two runs share one build folder (build/ab/head), which two workers would each
    # configure and build at once.
    "tests/reference/test_build_ab.py",
)


@pytest.hookimpl(optionalhook=True)  # pytest-xdist's hook: `-p no:xdist` runs have none
def pytest_xdist_make_scheduler(config: pytest.Config, log: object) -> object | None:
    if config.getvalue("dist") != "loadgroup":
        return None
    from xdist.scheduler import LoadScopeScheduling

    class CostlyModulesWhole(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            module = nodeid.split("::", 1)[0]
            return module if module.startswith(GROUPED) else nodeid

    return CostlyModulesWhole(config, log)


@pytest.fixture
def tmp_scene(tmp_path):
    """Write TOML text to a file and return its path."""

    def write(text: str, name: str = "scene.toml"):
        path = tmp_path / name
        path.write_text(text)
        return path

    return write


@pytest.fixture
def lost_interrupt():
    """A SIGINT received and lost, as a real Ctrl-C is when it lands in a finaliser: the CLI's
    handler (tracer/interrupt.py, installed here) raised Interrupted inside a __del__, where
    Python passes it to sys.unraisablehook and goes on. Checked to have happened; the handlers
    are put back afterwards."""
    import signal

    from tracer import interrupt

    class LosesTheInterrupt:
        def __del__(self):
            signal.raise_signal(signal.SIGINT)  # the handler raises Interrupted in here

    previous = interrupt.install()
    lost: list[type[BaseException] | None] = []
    hook = sys.unraisablehook
    sys.unraisablehook = lambda unraisable: lost.append(unraisable.exc_type)
    try:
        LosesTheInterrupt()  # made and dropped: its __del__ runs at once
    finally:
        sys.unraisablehook = hook
    try:
        assert lost == [interrupt.Interrupted], lost  # raised, and lost in the finaliser
        yield
    finally:
        interrupt.restore(previous)
