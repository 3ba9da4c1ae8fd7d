"""The suite's build cache (lessons/sandbox.py cached_build, $RTLAB_BUILD_CACHE): a build whose
inputs are byte-identical to one built before takes that binary; any changed byte, another
flag or other limits build afresh; a failed build is never kept; without the variable (the
grader's own runs) nothing is cached at all."""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest

from lessons.sandbox import (
    BUILD_CACHE_ENV,
    BUILD_LIMITS,
    Limits,
    build_cache,
    build_key,
    build_probe,
    run_probe,
)
from tests.lessons.test_sandbox import MAIN, QUICK, SOLUTION, submit


def _entries(cache: Path) -> list[Path]:
    return sorted(p for p in cache.iterdir() if p.is_dir()) if cache.exists() else []


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_a_byte_identical_build_is_served_and_any_change_builds_again(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    cache = tmp_path / "cache"
    monkeypatch.setenv(BUILD_CACHE_ENV, str(cache))
    assert build_cache() == cache
    (tmp_path / "a").mkdir()
    sub = submit(tmp_path / "a", SOLUTION + "    // cached once\n")
    first = build_probe(sub, MAIN, tmp_path / "w1")
    assert first.outcome.ok, first.outcome.message
    assert len(_entries(cache)) == 1 and not (_entries(cache)[0] / "hits").exists()
    again = build_probe(sub, MAIN, tmp_path / "w2")
    assert again.outcome.ok and again.binary == tmp_path / "w2" / "probe"
    assert _digest(again.binary) == _digest(first.binary)  # the same program, in its own work
    assert (_entries(cache)[0] / "hits").read_text().count("\n") == 1
    assert run_probe(again, [], QUICK).output.strip() == "lambert_term = 0.80000000000000004"
    assert again.files == first.files == ["10_classic.h"]
    # One changed byte of a source (a comment), another flag: each is a build of its own.
    (tmp_path / "b").mkdir()
    changed = submit(tmp_path / "b", SOLUTION + "    // cached twice\n")
    assert build_probe(changed, MAIN, tmp_path / "w3").outcome.ok
    assert build_probe(sub, MAIN, tmp_path / "w4", optimisation="-O2").outcome.ok
    assert len(_entries(cache)) == 3
    assert sum((e / "hits").exists() for e in _entries(cache)) == 1


def test_a_failed_build_is_not_kept(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    cache = tmp_path / "cache"
    monkeypatch.setenv(BUILD_CACHE_ENV, str(cache))
    sub = submit(tmp_path, "    return dot(N, L)\n")  # the missing semicolon
    for work in ("w1", "w2"):  # both compile and fail: nothing was kept to serve the second
        build = build_probe(sub, MAIN, tmp_path / work)
        assert build.outcome.kind == "compile_error" and build.binary is None
        assert "expected ';'" in build.outcome.message
    (entry,) = _entries(cache)
    assert sorted(p.name for p in entry.iterdir()) == ["lock"]


def test_the_key_holds_the_limits_and_the_compiler_command(tmp_path: Path) -> None:
    source = tmp_path / "cpp" / "x.h"
    source.parent.mkdir()
    source.write_text("int x;\n")
    base = build_key(["c++", "-O1"], [source], tmp_path, BUILD_LIMITS)
    assert base == build_key(["c++", "-O1"], [source], tmp_path, BUILD_LIMITS)
    assert base != build_key(["c++", "-O2"], [source], tmp_path, BUILD_LIMITS)
    assert base != build_key(["c++", "-O1"], [source], tmp_path, Limits(cpu_s=119))
    source.write_text("int y;\n")
    assert base != build_key(["c++", "-O1"], [source], tmp_path, BUILD_LIMITS)


def test_without_the_variable_nothing_is_cached(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    session = build_cache()  # the session's (tests/conftest.py)
    assert session is not None and session.is_dir()
    # A static of its own: a program no other test of the session builds.
    marked = "    static volatile int uncached_marker = 4242;\n    (void)uncached_marker;\n"
    sub = submit(tmp_path, marked + SOLUTION)
    monkeypatch.delenv(BUILD_CACHE_ENV)
    assert build_cache() is None
    assert build_probe(sub, MAIN, tmp_path / "w1").outcome.ok
    assert sorted(p.name for p in (tmp_path / "w1").iterdir()) == ["cpp", "main.cpp", "probe"]
    # The same build with the session's cache again: compiled, not served (nothing was kept).
    monkeypatch.setenv(BUILD_CACHE_ENV, str(session))
    build = build_probe(sub, MAIN, tmp_path / "w2")
    assert build.outcome.ok and build.binary is not None
    ours = _digest(build.binary)
    (entry,) = [
        e for e in _entries(session) if (e / "probe").exists() and _digest(e / "probe") == ours
    ]
    assert not (entry / "hits").exists()
