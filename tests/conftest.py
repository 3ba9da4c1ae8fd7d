"""Fixtures shared by the tests (helpers to import are in tests/helpers.py)."""

from __future__ import annotations

import os
import shutil
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


@pytest.fixture
def tmp_scene(tmp_path):
    """Write TOML text to a file and return its path."""

    def write(text: str, name: str = "scene.toml"):
        path = tmp_path / name
        path.write_text(text)
        return path

    return write
