"""Fixtures shared by the tests (helpers to import are in tests/helpers.py)."""

from __future__ import annotations

import pytest


@pytest.fixture
def tmp_scene(tmp_path):
    """Write TOML text to a file and return its path."""

    def write(text: str, name: str = "scene.toml"):
        path = tmp_path / name
        path.write_text(text)
        return path

    return write
