"""The repository's text points only at itself: every file path a source file, a README or the
Makefile names exists, and nothing refers to material outside the repository (a reader of a
fresh clone has only the clone)."""

from __future__ import annotations

import re
import subprocess

import pytest

from tests.helpers import ROOT

# A path inside the repository as the text writes it: one of the top-level packages, then
# folders and a file with a suffix (globs like reference/scenes/*.toml are not single files).
NAMED_PATH = re.compile(
    r"(?<![\w./-])((?:tracer|tests|converters|reference|lessons|\.ci)/[\w./-]*\w\.(?:py|h|cpp|toml|md|json|txt))\b"
)
OUTSIDE = re.compile(r"\.\./shared|(?<![\w.])/work/")


def tracked_text_files() -> list[str]:
    out = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True)
    names = out.stdout.split() if out.returncode == 0 else []
    suffixes = (".py", ".h", ".cpp", ".md", ".toml", ".txt", ".cfg")
    return [n for n in names if n.endswith(suffixes) or n in ("Makefile", "CMakeLists.txt")]


FILES = tracked_text_files()


def test_the_repository_lists_its_files():
    assert "README.md" in FILES and "tracer/cpp/10_classic.h" in FILES


@pytest.mark.parametrize("name", FILES)
def test_named_paths_exist_and_nothing_points_outside(name):
    text = (ROOT / name).read_text(encoding="utf-8")
    if name == "tests/test_repository.py":  # this file names the patterns it looks for
        return
    missing = [p for p in NAMED_PATH.findall(text) if not (ROOT / p).exists()]
    assert not missing, f"{name} names files that do not exist: {missing}"
    outside = OUTSIDE.findall(text)
    assert not outside, f"{name} refers to material outside the repository: {outside}"


def test_the_scanner_sees_a_missing_file_and_an_outside_reference():
    """The checks above can fail: the patterns find what they are meant to find."""
    text = "see tracer/cpp/04_sphere.h and ../shared/renderers.md"
    assert NAMED_PATH.findall(text) == ["tracer/cpp/04_sphere.h"]
    assert not (ROOT / "tracer/cpp/04_sphere.h").exists()
    assert OUTSIDE.findall(text) == ["../shared"]
