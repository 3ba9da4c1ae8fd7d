"""Feedback pages (`rtlab lesson grade DIR --report OUT`, reports.feedback_page): a known-wrong
version of L04 (lessons/mistakes.py) and a submission that does not compile, graded for real
and opened in Chromium as tests/reports/test_pages.py opens the lesson pages: the diagnosis
on the first screen, every image loaded, no request leaving the machine, and the page's
numbers those of results.json."""

import json
import re
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from lessons.mistakes import mistakes, write_mistake
from reports.feedback import artifact_names, feedback_page
from tests.reports.test_pages import (
    ROOT,
    assert_offline_and_whole,
    assert_reads_on_a_phone_and_a_projector,
    assert_stands_alone,
    browser,
    images_of,
    open_page,
)
from tracer.cli import main

__all__ = ["browser"]  # the fixture, shared with test_pages.py

# The first screen: a laptop's browser window (1280 x 800 CSS pixels).
FIRST_SCREEN = 800
MISTAKE = "normal_not_turned"  # L04's mistake that changes the picture (inside_lit fails)


def _mistake(name: str):
    return next(m for m in mistakes("L04") if m.name == name)


def _grade(submission: Path, report: Path, *extra: str) -> None:
    assert main(["lesson", "grade", str(submission), "--lesson", "L04",
                 "--report", str(report), *extra]) == 0  # fmt: skip


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    """{"wrong": the known-wrong version's report, "broken": one that does not compile}."""
    tmp = tmp_path_factory.mktemp("feedback")
    write_mistake(_mistake(MISTAKE), tmp / "wrong")
    _grade(tmp / "wrong", tmp / "wrong-report", "--json", str(tmp / "elsewhere" / "results.json"))
    mistake = _mistake("two_sided_lambert")
    path = write_mistake(mistake, tmp / "broken")
    text = path.read_text()
    broken = text.replace(mistake.new, mistake.new.replace(";", "", 1), 1)
    assert broken != text  # the compile error was injected
    path.write_text(broken)
    _grade(tmp / "broken", tmp / "broken-report")
    return {"wrong": tmp / "wrong-report", "broken": tmp / "broken-report", "tmp": tmp}


def _first_screen(browser, path: Path, javascript: bool = True):
    page, requests, errors = open_page(browser, path, javascript)
    page.set_viewport_size({"width": 1280, "height": FIRST_SCREEN})
    return page, requests, errors


def test_a_known_wrong_version_says_what_to_fix_on_the_first_screen(graded, browser):
    out = graded["wrong"]
    data = json.loads((out / "results.json").read_text())
    page, requests, errors = _first_screen(browser, out / "index.html")
    assert_offline_and_whole(page, requests, errors, out)
    box = page.locator("#diagnosis").bounding_box()
    assert box is not None and box["y"] + box["height"] <= FIRST_SCREEN, box
    verdict = page.inner_text("#diagnosis .verdict")
    assert verdict.startswith("L04: wrong: the normal facing the ray (")
    assert verdict == data["extra_data"]["diagnosis"].split("\n")[0]
    # The concept's function and hint are there too, on the first screen.
    fix = page.inner_text("#diagnosis table.fix")
    assert "face_the_ray()" in fix and "Ng turned against d" in fix
    (ROOT / "out").mkdir(exist_ok=True)
    page.screenshot(path=str(ROOT / "out" / "report-feedback.png"), full_page=True)
    assert_reads_on_a_phone_and_a_projector(page)


def test_the_checks_on_the_page_are_those_of_results_json(graded, browser):
    out = graded["wrong"]
    data = json.loads((out / "results.json").read_text())
    page, requests, errors = open_page(browser, out / "index.html", javascript=False)
    assert_offline_and_whole(page, requests, errors, out)
    failed = [t for t in data["tests"] if t["status"] == "failed"]
    passed = [t for t in data["tests"] if t["status"] == "passed"]
    assert failed and passed
    assert page.locator("#failing article.check").count() == len(failed)
    assert page.locator("#passed tbody tr").count() == len(passed)
    for t in failed:
        article = page.locator(f"#check-{t['number']}")
        for v in t["extra_data"].get("values", []):
            row = article.locator(f"table.values tr[data-label='{v['label']}']")
            assert row.locator("[data-field=expected]").inner_text() == v["expected"]
            assert row.locator("[data-field=got]").inner_text() == v["got"]
    # Per concept: checks passing and points as results.json adds them up.
    for row in page.eval_on_selector_all(
        "table.concepts tbody tr",
        "els => els.map(e => [e.dataset.concept, e.querySelector('[data-field=passing]')"
        ".textContent])",
    ):
        concept, text = row
        mine = [t for t in data["tests"] if t["tags"][1] == concept]
        ok = sum(t["status"] == "passed" for t in mine)
        assert text == f"{ok} of {len(mine)}"


def test_a_failing_scene_shows_the_images_and_marks_the_failing_pixels(graded, browser):
    out = graded["wrong"]
    data = json.loads((out / "results.json").read_text())
    scene = next(t for t in data["tests"] if t["name"].startswith("scene inside_lit"))
    files = scene["extra_data"]["artifacts"]
    assert set(files) == {"yours", "heat:povray", "heat:mitsuba", "reference:povray",
                          "reference:mitsuba", "failing:povray", "failing:mitsuba"}  # fmt: skip
    page, requests, errors = open_page(browser, out / "index.html")
    assert_offline_and_whole(page, requests, errors, out)
    shown = page.eval_on_selector_all(
        f"#check-{scene['number']} img", "els => els.map(e => e.getAttribute('src'))"
    )
    assert set(shown) == set(files.values())  # each image the grader wrote, and loaded
    # The marked image's magenta pixels are the pixels results.json says are over tolerance.
    for name in ("povray", "mitsuba"):
        label = {"povray": "POV-Ray", "mitsuba": "Mitsuba"}[name]
        said = re.search(rf"against {label}: \*\*differs\*\*: (\d+) of (\d+) pixels",
                         scene["output"])  # fmt: skip
        assert said, scene["output"]
        marked = np.asarray(Image.open(out / files[f"failing:{name}"]).convert("RGB"))
        magenta = np.all(marked == (255, 0, 255), axis=-1)
        assert int(magenta.sum()) == int(said.group(1))
        assert magenta.size == int(said.group(2))
    # --json elsewhere still gets results.json and the heat maps beside it.
    elsewhere = graded["tmp"] / "elsewhere"
    assert json.loads((elsewhere / "results.json").read_text())["tests"] == data["tests"]
    assert (elsewhere / files["heat:povray"]).is_file()


def test_a_submission_that_does_not_compile_shows_the_compiler_first(graded, browser):
    out = graded["broken"]
    data = json.loads((out / "results.json").read_text())
    assert data["score"] == 0
    page, requests, errors = _first_screen(browser, out / "index.html")
    assert_offline_and_whole(page, requests, errors, out)
    box = page.locator("#diagnosis").bounding_box()
    assert box is not None and box["y"] + box["height"] <= FIRST_SCREEN, box
    assert page.inner_text("#diagnosis .verdict").startswith("L04: your code does not compile")
    compiler = page.inner_text("#diagnosis pre")
    assert "error:" in compiler and _mistake("two_sided_lambert").file in compiler
    # Every check failed the same way: said once per lesson, not once per check.
    articles = page.locator("#failing article.check")
    assert articles.count() <= 2  # L04's checks and the integration check
    names = page.locator("#failing ul.names li").count()
    alone = page.locator("#failing article.check:not(:has(ul.names))").count()
    assert names > 20 and names + alone == len(data["tests"])
    assert images_of(page) == []  # nothing rendered
    page.screenshot(path=str(ROOT / "out" / "report-feedback-compile-error.png"), full_page=True)


def test_feedback_page_from_results_json_alone(graded, browser, tmp_path):
    from reports import feedback_page

    path = feedback_page(graded["wrong"] / "results.json", tmp_path / "again")
    assert sorted(p.name for p in path.parent.iterdir()) == sorted(
        p.name for p in graded["wrong"].iterdir()
    )
    page, requests, errors = open_page(browser, path)
    assert_offline_and_whole(page, requests, errors, tmp_path / "again")
    assert page.locator("#failing article.check").count() > 0


def test_a_failed_grading_leaves_the_old_page(graded, tmp_path, monkeypatch):
    import shutil

    import lessons.grader

    out = tmp_path / "report"
    shutil.copytree(graded["wrong"], out)
    before = {p.name: p.read_bytes() for p in out.iterdir()}

    def broken(*args, **kwargs):
        raise RuntimeError("injected: the grader fails")

    monkeypatch.setattr(lessons.grader, "grade", broken)
    with pytest.raises(RuntimeError, match="injected"):  # the failure happened
        _grade(graded["tmp"] / "wrong", out)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report"]  # no stage left


def test_a_single_file_feedback_page_stands_alone(graded, browser, tmp_path):
    """`--single-file`'s page (reports.feedback_page(..., inline=True)) mailed alone: every
    image inlined; the image files stay beside results.json, which names them."""
    source = graded["wrong"] / "results.json"
    path = feedback_page(source, tmp_path / "page", inline=True)
    files = artifact_names(json.loads(source.read_text()))
    assert files and all((path.parent / name).is_file() for name in files)
    assert_stands_alone(browser, path, tmp_path)


def test_single_file_needs_a_report(tmp_path, capsys):
    assert main(["lesson", "grade", str(tmp_path), "--lesson", "L04", "--single-file"]) == 2
    assert "--report" in capsys.readouterr().err


def test_a_crash_is_named_on_the_first_screen(tmp_path, browser):
    """A submission whose lambert_term() writes through a null pointer: the page says which
    function crashed and how, on the first screen, and the check shows the crash text."""
    mistake = _mistake("two_sided_lambert")
    path = write_mistake(mistake, tmp_path / "sub")
    text = path.read_text()
    crashing = text.replace(mistake.new, "volatile int *nowhere = nullptr; *nowhere = 1; "
                            + mistake.new, 1)  # fmt: skip
    assert crashing != text  # the crash was injected
    path.write_text(crashing)
    _grade(tmp_path / "sub", tmp_path / "report", "--no-scenes")
    page, requests, errors = _first_screen(browser, tmp_path / "report" / "index.html")
    assert_offline_and_whole(page, requests, errors, tmp_path / "report")
    box = page.locator("#diagnosis").bounding_box()
    assert box is not None and box["y"] + box["height"] <= FIRST_SCREEN, box
    diagnosis = page.inner_text("#diagnosis")
    assert "crashed" in diagnosis and "lambert_term()" in diagnosis
    assert "SIGSEGV (in lambert_term())" in page.inner_text("#failing")  # the check says how
    page.screenshot(path=str(ROOT / "out" / "report-feedback-crash.png"), full_page=True)
