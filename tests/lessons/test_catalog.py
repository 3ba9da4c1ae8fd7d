"""The lesson catalogue and its texts (rtlab lesson list / show): the 13 lessons in the
lecture's order; every lesson with solution regions has its text, naming what the student
writes; unknown ids are refused with the near spelling and exit status 2."""

from __future__ import annotations

import re

import pytest

from lessons.catalog import LESSON_IDS, LESSONS, UnknownLessonError, get_lesson, suggest_lesson
from lessons.markers import find_regions
from tests.helpers import ROOT
from tracer.cli import main

REGIONS = find_regions(ROOT / "tracer" / "cpp")


def test_thirteen_lessons_in_order():
    assert tuple(f"L{n:02d}" for n in range(1, 14)) == LESSON_IDS
    assert all(lesson.concepts and lesson.title and lesson.slide for lesson in LESSONS)
    assert len({lesson.name for lesson in LESSONS}) == 13


@pytest.mark.parametrize("lesson", sorted({r.lesson for r in REGIONS}))
def test_a_marked_lesson_has_its_text_naming_what_the_student_writes(lesson):
    info = get_lesson(lesson)
    text = info.text_path.read_text()
    assert text.startswith(f"# {lesson}: {info.title}\n")
    for heading in ("## The idea", "## What you write", "## Pitfalls", "## How it is checked"):
        assert heading in text, f"{info.text_path.name} lacks {heading}"
    assert re.search(r'[Ss]lides? "', text), "the text cites no slide"
    for r in (r for r in REGIONS if r.lesson == lesson and not r.is_copy):
        assert f"`{r.function}()`" in text, f"{lesson}'s text does not name {r.function}()"


def test_list_prints_every_lesson_in_order(capsys):
    assert main(["lesson", "list"]) == 0
    out = capsys.readouterr().out
    positions = [out.index(f"{i}  ") for i in LESSON_IDS]
    assert positions == sorted(positions)
    assert "diffuse (Lambertian) reflection N.L" in out


def test_show_prints_the_text(capsys):
    assert main(["lesson", "show", "L05"]) == 0
    assert capsys.readouterr().out == get_lesson("L05").text_path.read_text()


@pytest.mark.parametrize(
    ("typed", "meant"), [("L4", "L04"), ("l05", "L05"), ("4", "L04"), ("lambrt", "L04")]
)
def test_unknown_ids_suggest_the_near_spelling_and_exit_2(typed, meant, capsys):
    assert main(["lesson", "show", typed]) == 2
    assert f"unknown lesson {typed!r} (did you mean {meant}?)" in capsys.readouterr().err
    with pytest.raises(UnknownLessonError):
        get_lesson(typed)


def test_a_far_spelling_gets_no_suggestion():
    assert suggest_lesson("ray tracing") == ""
