"""Student trees (rtlab lesson student): the regions of the lesson and every later one hold a
stub and no solution; earlier lessons keep the solution or, with --from, the student's own
code; every header compiles warning-free; a stub reports "not implemented" when called, in the
calling thread and in a worker thread; the tree is written atomically."""

from __future__ import annotations

import subprocess
import sys

import pytest

from lessons.catalog import LESSON_IDS, later_or_equal
from lessons.markers import find_regions, parse
from lessons.student import FLAGS, StudentTreeError, solution_lines, write_student_tree
from tests.helpers import ROOT

CPP = ROOT / "tracer" / "cpp"
REGIONS = find_regions(CPP)
MARKED = sorted({r.lesson for r in REGIONS})


def distinctive_lines(lesson: str) -> dict[tuple[str, str], list[str]]:
    """Per region of `lesson` or later: its solution's code lines that appear nowhere in the
    core outside those regions (so finding one in a tree means the solution leaked)."""
    hidden = [r for r in REGIONS if r.lesson in later_or_equal(lesson)]
    elsewhere = []
    for path in sorted([*CPP.glob("*.h"), *CPP.glob("*.cpp")]):
        lines = path.read_text().split("\n")
        for r in (r for r in hidden if r.file == path.name):
            lines[r.begin - 1 : r.end] = [""] * (r.end - r.begin + 1)
        elsewhere += [line.strip() for line in lines]
    others = set(elsewhere)
    return {
        (r.file, r.function): [line for line in solution_lines(r) if line not in others]
        for r in hidden
    }


def tree_text(out) -> str:
    return "\n".join(p.read_text() for p in sorted((out / "cpp").iterdir()))


@pytest.mark.parametrize("lesson", MARKED)
def test_a_tree_holds_no_solution_of_its_lesson_or_later(lesson, tmp_path):
    out = tmp_path / "hw"
    report = write_student_tree(lesson, out)
    text = tree_text(out)
    lines = {line.strip() for line in text.split("\n")}
    expected = distinctive_lines(lesson)
    # The grep below is not vacuous: almost every region has lines found nowhere else. (Short
    # bodies such as reflect()'s one line still count: "return d - 2 * dot(d, N) * N;".)
    assert sum(bool(v) for v in expected.values()) >= len(expected) - 2, expected
    leaked = {k: [x for x in v if x in lines] for k, v in expected.items()}
    assert not any(leaked.values()), f"{lesson} tree leaks solution lines: {leaked}"
    stubbed = {(r.file, r.function) for r in report.stubbed}
    # A later lesson's region with GIVEN lines holds that plain code (L13's textbook forms in
    # every tree before L13), its lesson's own tree a stub.
    given = {(r.file, r.function) for r in report.given}
    assert all(r.given and r.lesson != lesson for r in report.given)
    assert stubbed | given == set(expected) and not stubbed & given
    assert bool(given) == (lesson != "L13")
    for file, function in stubbed:
        assert f'"{function}"' in (out / "cpp" / file).read_text()
    # Earlier lessons keep the solution, every line of it.
    for r in REGIONS:
        if r.lesson not in later_or_equal(lesson):
            assert all(line in lines for line in solution_lines(r)), r.function


def test_the_solution_grep_can_fail(tmp_path):
    """Put one solution line of L04 back into an L04 tree: the grep above must see it."""
    out = tmp_path / "hw"
    write_student_tree("L04", out)
    (line,) = distinctive_lines("L04")[("10_classic.h", "lambert_term")]
    assert line == "return dot(N, L);"
    assert line not in {x.strip() for x in tree_text(out).split("\n")}
    path = out / "cpp" / "10_classic.h"
    path.write_text(path.read_text().replace('not_implemented("L04", "lambert_term", N, L);', line))
    assert line in {x.strip() for x in tree_text(out).split("\n")}


def compile_header(directory, header: str, tmp_path) -> subprocess.CompletedProcess:
    source = tmp_path / "only.cpp"
    source.write_text(f'#include "{header}"\n')
    return subprocess.run(
        ["c++", *FLAGS.split(), "-fsyntax-only", f"-I{directory}", str(source)],
        capture_output=True,
        text=True,
    )


@pytest.mark.parametrize("lesson", ["L02", "L04", "L07"])
def test_every_header_of_a_tree_compiles_warning_free(lesson, tmp_path):
    out = tmp_path / "hw"
    write_student_tree(lesson, out)
    for header in sorted((out / "cpp").glob("*.h")):
        result = compile_header(out / "cpp", header.name, tmp_path)
        assert result.returncode == 0, f"{lesson} {header.name}:\n{result.stderr}"


def test_the_trees_makefile_checks_the_headers(tmp_path):
    out = tmp_path / "hw"
    write_student_tree("L04", out)
    done = subprocess.run(["make", "-C", str(out)], capture_output=True, text=True)
    assert done.returncode == 0 and "every header" in done.stdout, done.stderr
    # ... and can fail: a syntax error in one header.
    path = out / "cpp" / "06_plane.h"
    text = path.read_text()
    broken = text.replace("double denom = ", "double denom = undeclared_name + ")
    assert broken != text, "the injection found nothing to change"
    path.write_text(broken)
    failed = subprocess.run(["make", "-C", str(out)], capture_output=True, text=True)
    assert failed.returncode != 0 and "06_plane.h does not compile" in failed.stderr


PROBE = r"""
#include <cstdio>
#include <thread>
#include "10_classic.h"
int main(int argc, char **) {
    rt::Vec3 N{0, 0, 1}, L{0, 0, 1};
    if (argc == 1) {  // in the calling thread: the exception is caught like any other
        try {
            double v = rt::lambert_term(N, L);
            std::printf("returned %g\n", v);
        } catch (const rt::NotImplemented &e) {
            std::printf("caught: %s\n", e.what());
        }
        return 0;
    }
    // in a worker thread, where nothing catches it (the render's threads)
    std::thread t([&] { std::printf("returned %g\n", rt::lambert_term(N, L)); });
    t.join();
    return 0;
}
"""


def test_a_stub_reports_not_implemented_and_never_returns(tmp_path):
    out = tmp_path / "hw"
    write_student_tree("L04", out)
    (tmp_path / "probe.cpp").write_text(PROBE)
    binary = tmp_path / "probe"
    built = subprocess.run(
        [
            "c++",
            *FLAGS.split(),
            "-O1",
            f"-I{out / 'cpp'}",
            str(tmp_path / "probe.cpp"),
            "-o",
            str(binary),
            "-pthread",
        ],
        capture_output=True,
        text=True,
    )
    assert built.returncode == 0, built.stderr
    caught = subprocess.run([str(binary)], capture_output=True, text=True, timeout=30)
    assert caught.returncode == 0
    assert caught.stdout.startswith("caught: not implemented: lambert_term (lesson L04)")
    thread = subprocess.run([str(binary), "thread"], capture_output=True, text=True, timeout=30)
    # Not a crash (no signal): status 86 and the message, never a value.
    assert thread.returncode == 86, (thread.returncode, thread.stderr)
    assert "rtlab: not implemented: lambert_term (lesson L04)" in thread.stderr
    assert "returned" not in thread.stdout


def test_from_carries_the_students_own_earlier_code(tmp_path):
    hw04 = tmp_path / "hw04"
    write_student_tree("L04", hw04)
    # The student writes lambert_term their own way (a different line from the solution's).
    path = hw04 / "cpp" / "10_classic.h"
    own = "return N.x * L.x + N.y * L.y + N.z * L.z; // mine"
    path.write_text(path.read_text().replace('not_implemented("L04", "lambert_term", N, L);', own))
    hw05 = tmp_path / "hw05"
    report = write_student_tree("L05", hw05, from_dir=hw04)
    text = (hw05 / "cpp" / "10_classic.h").read_text()
    assert own in text and "return dot(N, L);" not in text
    (region,) = [r for r in parse(text, "10_classic.h") if r.function == "lambert_term"]
    assert region.body[-1].strip() == own
    assert any(r.function == "lambert_term" for r in report.carried)
    # What the student did not write yet stays a stub; L05's own functions are stubs.
    assert 'not_implemented("L04", "ambient_term"' in text
    assert 'not_implemented("L05", "in_shadow"' in text
    assert compile_header(hw05 / "cpp", "10_classic.h", tmp_path).returncode == 0


def test_a_tree_is_written_atomically(tmp_path, monkeypatch):
    """A failure half way leaves no directory at all; an existing tree is never overwritten."""
    import lessons.student as student

    out = tmp_path / "hw"
    calls = {"n": 0}
    real = student.lesson_file_text

    def failing(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 5:
            raise OSError("disk full")
        return real(*args, **kwargs)

    monkeypatch.setattr(student, "lesson_file_text", failing)
    with pytest.raises(OSError, match="disk full"):
        write_student_tree("L04", out)
    assert calls["n"] == 5  # the failure was injected half way through the files
    assert not out.exists() and list(tmp_path.iterdir()) == []
    monkeypatch.undo()
    write_student_tree("L04", out)
    before = (out / "cpp" / "10_classic.h").read_text()
    with pytest.raises(StudentTreeError, match="exists and is not empty"):
        write_student_tree("L05", out)
    assert (out / "cpp" / "10_classic.h").read_text() == before


def test_the_cli_writes_a_tree_and_refuses_unknown_lessons(tmp_path):
    run = [sys.executable, "-m", "tracer.cli", "lesson"]
    done = subprocess.run(
        [*run, "student", "L03", "--out", str(tmp_path / "hw")],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert done.returncode == 0, done.stderr
    assert "you write plane_t(), intersect_plane()" in done.stdout
    bad = subprocess.run(
        [*run, "student", "L3", "--out", str(tmp_path / "x")],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert bad.returncode == 2 and "did you mean L03?" in bad.stderr
    assert not (tmp_path / "x").exists()
    assert set(MARKED) <= set(LESSON_IDS)


def test_a_trees_extension_source_compiles_against_nanobind(tmp_path):
    """bindings.cpp, the extension's one translation unit, with every stub of an L02 tree (the
    most stubs), compiles warning-free: the tree builds the extension, not only the headers."""
    out = tmp_path / "hw"
    write_student_tree("L02", out)
    nanobind = subprocess.run(
        [sys.executable, "-m", "nanobind", "--include_dir"], capture_output=True, text=True
    ).stdout.strip()
    import sysconfig

    includes = [
        f"-I{nanobind}",
        f"-I{nanobind}/../ext/robin_map/include",
        f"-I{sysconfig.get_paths()['include']}",
    ]
    result = subprocess.run(
        ["c++", *FLAGS.split(), "-fsyntax-only", *includes, str(out / "cpp" / "bindings.cpp")],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 0, result.stderr


def test_from_refuses_an_earlier_tree_with_broken_markers(tmp_path):
    """A student who deleted an END SOLUTION line is told the file and the line, and no tree
    is written."""
    hw04 = tmp_path / "hw04"
    write_student_tree("L04", hw04)
    path = hw04 / "cpp" / "10_classic.h"
    lines = path.read_text().split("\n")
    first_end = lines.index("    // END SOLUTION")
    del lines[first_end]
    path.write_text("\n".join(lines))
    with pytest.raises(StudentTreeError) as error:
        write_student_tree("L05", tmp_path / "hw05", from_dir=hw04)
    assert f"{path}:" in str(error.value) and "inside the region opened at line" in str(error.value)
    assert not (tmp_path / "hw05").exists()
    with pytest.raises(StudentTreeError, match="--from expects the directory"):
        write_student_tree("L05", tmp_path / "hw05", from_dir=tmp_path / "missing")
