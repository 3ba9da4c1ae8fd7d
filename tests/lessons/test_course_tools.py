"""The course's tools around the grader: the student's self-check (`make check`, `rtlab lesson
grade --public`), the instructor's `rtlab lesson check`, and the Gradescope autograder zip run
in a temporary directory laid out like Gradescope's."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from lessons.check import check_lesson, format_table
from lessons.grader import INTEGRATION
from lessons.mistakes import Mistake, mistakes, write_mistake
from lessons.student import CORE, write_student_tree
from tests.helpers import ROOT

RTLAB = str(Path(sys.executable).parent / "rtlab")


def test_make_check_runs_only_the_public_checks(tmp_path: Path) -> None:
    tree = tmp_path / "hw04"
    write_student_tree("L04", tree)
    assert "make check" in (tree / "README.md").read_text()
    done = subprocess.run(["make", "-s", "-C", str(tree), "check", f"RTLAB={RTLAB}"],
                          capture_output=True, text=True, timeout=600)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[1].startswith("L04: not implemented: ")
    assert "public checks only" in done.stdout
    data = json.loads((tree / "check" / "results.json").read_text())
    assert data["score"] == 0 and data["tests"]
    assert {t["visibility"] for t in data["tests"]} == {"visible"}  # no hidden variant ran
    assert any(t["name"].startswith("scene ") for t in data["tests"])


def test_lesson_check_names_a_mistake_it_does_not_catch(tmp_path: Path) -> None:
    # A "mistake" that only adds a space is not caught: the check must say so.
    real = next(m for m in mistakes("L03") if m.name == "sign_of_a_minus_o")
    harmless = Mistake("L03", "harmless", "a space added", "the plane (p - a).n = 0",
                       real.file, real.function, real.old,
                       real.old.replace(", pl.normal", ",  pl.normal"))  # fmt: skip
    assert harmless.new != harmless.old
    report = check_lesson("L03", scenes=False, known_wrong=[real, harmless])
    assert report.markers.startswith("ok") and report.stub_tree == "compiles, scores 0"
    assert report.solution.startswith("full")
    assert (report.caught, report.mistakes) == (1, 2)
    assert not report.ok and len(report.failures) == 1
    assert "mistake harmless" in report.failures[0]
    assert "the plane (p - a).n = 0" in report.failures[0]
    table = format_table([report])
    assert "1/2" in table and "FAIL L03: mistake harmless" in table


def test_rtlab_lesson_check_passes_for_a_lesson() -> None:
    done = subprocess.run([RTLAB, "lesson", "check", "--lesson", "L06", "--no-scenes"],
                          capture_output=True, text=True, timeout=600)  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr
    row = next(line for line in done.stdout.splitlines() if line.startswith("L06 "))
    assert f"{len(mistakes('L06'))}/{len(mistakes('L06'))}" in row
    assert "full" in row and "compiles, scores 0" in row
    assert "1 of 1 lessons pass" in done.stdout


def _run_autograder(root: Path, submission: Path) -> dict:
    """Gradescope's steps: the submission in root/submission, run_autograder, results.json."""
    shutil.rmtree(root / "submission", ignore_errors=True)
    shutil.rmtree(root / "results", ignore_errors=True)
    shutil.copytree(submission, root / "submission")
    env = {**os.environ, "RTLAB_AUTOGRADER_ROOT": str(root), "RTLAB_PYTHON": sys.executable}
    env.pop("RTLAB_REFERENCES", None)
    done = subprocess.run(["bash", str(root / "run_autograder")], cwd=root, env=env,
                          capture_output=True, text=True, timeout=600)  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr
    return json.loads((root / "results" / "results.json").read_text())


def test_the_autograder_zip_grades_in_gradescopes_layout(tmp_path: Path) -> None:
    from lessons.autograder import build_zip

    out = tmp_path / "autograder.zip"
    names = build_zip("L04", out)
    assert not [p for p in tmp_path.iterdir() if p != out]  # written atomically: nothing else
    with zipfile.ZipFile(out) as archive:
        listed = set(archive.namelist())
        assert {"setup.sh", "run_autograder", "requirements.txt"} <= listed
        assert archive.getinfo("run_autograder").external_attr >> 16 & 0o111
        assert set(names) <= listed and any(n.startswith("references/L04/") for n in names)
        assert any(n.startswith(f"references/{INTEGRATION}/") for n in names)
        # Gradescope unpacks it into /autograder/source; here a temporary /autograder.
        root = tmp_path / "autograder"
        archive.extractall(root / "source")
    source = root / "source"
    shutil.copyfile(source / "run_autograder", root / "run_autograder")  # as Gradescope does
    # The unpacked sources run, not this checkout's: a mark in a scene's title must show.
    scenes = source / "lessons" / "L04_lambert" / "scenes" / "__init__.py"
    text = scenes.read_text()
    assert "a white sphere under an orange light" in text
    scenes.write_text(text.replace("a white sphere under", "(unpacked) a white sphere under"))
    # setup.sh's last step (the rest installs system packages): the solution's extension.
    env = {**os.environ, "RTLAB_AUTOGRADER_ROOT": str(root)}
    done = subprocess.run([sys.executable, "lessons/autograder.py", "setup"], cwd=source,
                          env=env, capture_output=True, text=True, timeout=600)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert list((source / "tracer").glob("_core*.so"))

    solution = tmp_path / "solution"
    shutil.copytree(CORE, solution)
    data = _run_autograder(root, solution)
    assert data["score"] > 0 and all(t["status"] == "passed" for t in data["tests"])
    assert any("(unpacked) a white sphere" in t["output"] for t in data["tests"])
    assert data["tests"][-1]["tags"][0] == INTEGRATION

    mistake = next(m for m in mistakes("L04") if m.name == "normal_not_turned")
    write_mistake(mistake, tmp_path / "wrong")
    data = _run_autograder(root, tmp_path / "wrong")
    assert data["output"].startswith(f"L04: wrong: {mistake.concept} (")
    failed = [t for t in data["tests"] if t["status"] == "failed"]
    assert any(t["name"].startswith("scene inside_lit") for t in failed)
    assert 0 < data["score"] < sum(t["max_score"] for t in data["tests"])
    assert str(ROOT) not in json.dumps(data)  # nothing of this checkout leaks into it


@pytest.mark.parametrize(
    ("lesson", "wrong"), [("L12", "roulette_without_reweighting"), ("L13", "textbook_discriminant")]
)
def test_the_autograder_carries_the_references_of_path_traced_and_stiff_scenes(
    tmp_path: Path, lesson: str, wrong: str
) -> None:
    """Every scene's references go into the zip, a path-traced scene's (Mitsuba's mean and
    variance) too: unpacked, with no renderer allowed (RTLAB_REFERENCES_ONLY), it grades the
    solution full and names a known-wrong version's concept from a failing scene."""
    from lessons.autograder import build_zip
    from lessons.scene_checks import PathSceneCheck, lesson_scenes

    out = tmp_path / "autograder.zip"
    names = build_zip(lesson, out)
    scenes = lesson_scenes(lesson)
    with zipfile.ZipFile(out) as archive:
        for check in scenes:
            (arc,) = [n for n in names if n.startswith(f"references/{lesson}/{check.name}-")]
            with archive.open(arc) as f, np.load(f) as data:
                want = "path_mean" if isinstance(check, PathSceneCheck) else "povray"
                assert want in data.files, (arc, data.files)
        archive.extractall(tmp_path / "autograder" / "source")
    root = tmp_path / "autograder"
    source = root / "source"
    shutil.copyfile(source / "run_autograder", root / "run_autograder")
    env = {**os.environ, "RTLAB_AUTOGRADER_ROOT": str(root)}
    done = subprocess.run([sys.executable, "lessons/autograder.py", "setup"], cwd=source,
                          env=env, capture_output=True, text=True, timeout=600)  # fmt: skip
    assert done.returncode == 0, done.stderr
    solution = tmp_path / "solution"
    shutil.copytree(CORE, solution)
    data = _run_autograder(root, solution)
    assert all(t["status"] == "passed" for t in data["tests"]), data["output"]
    assert sum(t["name"].startswith("scene ") for t in data["tests"]) == len(scenes) + 1
    mistake = next(m for m in mistakes(lesson) if m.name == wrong)
    write_mistake(mistake, tmp_path / "wrong")
    data = _run_autograder(root, tmp_path / "wrong")
    assert data["output"].startswith(f"{lesson}: wrong: {mistake.concept} (")
    failed = [t for t in data["tests"] if t["status"] == "failed"]
    assert any(t["name"].startswith("scene ") and mistake.concept in t["tags"] for t in failed)
