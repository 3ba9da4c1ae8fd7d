"""`rtlab report course` over every lesson (no known-wrong versions: their pages are
test_pages.py's): every lesson's page is written, every scene of every lesson is judged by the
grader's comparisons and the course's solution passes them all, and the index links each page.
A page kind that breaks on one lesson's scenes (a stereo pair, a path-traced scene) breaks here."""

import json

from lessons.catalog import LESSONS
from lessons.scene_checks import lesson_scenes
from tracer.cli import main


def test_the_whole_course_builds_and_the_solution_passes_every_scene(tmp_path, capsys):
    out = tmp_path / "site"
    assert main(["report", "course", "--out", str(out), "--mistakes", "0"]) == 0
    assert f"the pages of {len(LESSONS)} lessons" in capsys.readouterr().out
    index = (out / "index.html").read_text()
    for lesson in LESSONS:
        page = out / lesson.id / "index.html"
        assert f'href="{lesson.id}/index.html"' in index
        html = page.read_text()
        scenes = lesson_scenes(lesson.id)
        # The grader's verdict on the solution, once per scene, and never a failure.
        assert html.count("it passes</strong>") == len(scenes) > 0, lesson.id
        assert "it FAILS" not in html
        rows = json.loads((out / lesson.id / "metrics.json").read_text())
        assert {r["scene"] for r in rows} <= {c.name for c in scenes}
        assert rows and all(r["agrees"] for r in rows), lesson.id
