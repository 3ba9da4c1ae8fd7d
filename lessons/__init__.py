"""The course's lessons (lessons/README.md). ``lessons.grade(submission, lesson="L04")`` grades
a submission (lessons/grader.py)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from pathlib import Path

    from lessons.grader import Result


def grade(submission: str | Path, lesson: str | None = None, **options: Any) -> Result:
    """Grade a submission directory on `lesson`, or on every lesson its files touch; options:
    public, scenes, integration, artifacts (lessons.grader.grade)."""
    from lessons.grader import grade as grade_

    return grade_(submission, lesson, **options)
