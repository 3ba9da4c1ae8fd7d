"""The class page (`rtlab report class GRADES --out DIR`) over real grader runs: known-wrong
versions of L04 (lessons/mistakes.py) graded by `rtlab lesson grade --report` (and one by
--json alone, no feedback page), one submission that does not compile, and the solution; the
page's counts checked against the results.json files and in Chromium."""

import json
import shutil
from collections import Counter
from pathlib import Path

import pytest

from lessons.mistakes import mistakes, write_mistake
from lessons.student import CORE
from tests.reports.test_pages import (
    ROOT,
    assert_offline_and_whole,
    assert_reads_on_a_phone_and_a_projector,
    assert_stands_alone,
    browser,
    open_page,
)
from tracer.cli import main

__all__ = ["browser"]  # the fixture, shared with test_pages.py

# Two mistakes of the same concept (one diagnosis counted twice), two others; probes only
# (--no-scenes: one build each), the scene checks' pages are tests/reports/test_feedback.py's.
WRONG = {
    "ann": "normal_not_turned",
    "bob": "shading_normal_not_turned",
    "cy": "directional_sign",
    "dee": "light_colour_twice",  # graded with --json only: no feedback page to link
}


def _grade(submission: Path, *flags: str) -> None:
    assert main(["lesson", "grade", str(submission), "--lesson", "L04", "--no-scenes",
                 *flags]) == 0  # fmt: skip


@pytest.fixture(scope="module")
def grades(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("class")
    grades = tmp / "grades"
    by_name = {m.name: m for m in mistakes("L04")}
    for student, name in WRONG.items():
        write_mistake(by_name[name], tmp / "sub" / student)
        if student == "dee":
            _grade(tmp / "sub" / student, "--json", str(grades / student / "results.json"))
        else:
            _grade(tmp / "sub" / student, "--report", str(grades / student))
    # eve's code does not compile (a semicolon gone); fay hands in the solution.
    path = write_mistake(by_name["two_sided_lambert"], tmp / "sub" / "eve")
    text = path.read_text()
    path.write_text(text.replace("return std::fabs(dot(N, L));", "return dot(N, L)"))
    assert path.read_text() != text  # the compile error was injected
    _grade(tmp / "sub" / "eve", "--report", str(grades / "eve"))
    shutil.copytree(CORE, tmp / "sub" / "fay")
    _grade(tmp / "sub" / "fay", "--report", str(grades / "fay"))
    out = tmp / "class"
    assert main(["report", "class", str(grades), "--out", str(out)]) == 0
    return grades, out


def _results(grades: Path) -> dict[str, dict]:
    return {p.parent.name: json.loads(p.read_text()) for p in grades.glob("*/results.json")}


def test_the_class_page_counts_what_the_results_say(grades, browser):
    grades, out = grades
    results = _results(grades)
    assert sorted(results) == ["ann", "bob", "cy", "dee", "eve", "fay"]
    page, requests, errors = open_page(browser, out / "index.html")
    # The feedback pages are in grades/, beside the page's directory: the page's own site is
    # its parent here (class/ and grades/ side by side).
    assert_offline_and_whole(page, requests, errors, out.parent)
    (ROOT / "out").mkdir(exist_ok=True)
    page.screenshot(path=str(ROOT / "out" / "report-class.png"), full_page=True)
    assert_reads_on_a_phone_and_a_projector(page)
    rows = page.locator("table.matrix tbody tr")
    assert rows.count() == len(results)
    # Each cell: the failing checks of that student and concept, as results.json has them.
    cells = page.eval_on_selector_all(
        "table.matrix tbody td[data-failing]",
        "els => els.map(e => [e.closest('tr').dataset.student, e.dataset.concept,"
        " +e.dataset.failing])",
    )
    assert cells
    for student, concept, shown in cells:
        tests = [t for t in results[student]["tests"] if t["tags"][1] == concept]
        assert shown == sum(t["status"] == "failed" for t in tests), (student, concept)
    for student, data in results.items():
        score = page.locator(f"tr[data-student='{student}'] [data-field=score]")
        assert float(score.get_attribute("data-value")) == data["score"]
    # The footer: how many students fail each concept.
    footer = dict(page.eval_on_selector_all(
        "table.matrix tfoot td[data-concept]",
        "els => els.map(e => [e.dataset.concept, e.textContent])",
    ))  # fmt: skip
    for concept, text in footer.items():
        failing = sum(
            any(t["tags"][1] == concept and t["status"] == "failed" for t in d["tests"])
            for d in results.values()
        )
        assert text.startswith(f"{failing} of ")
    # ann and bob, and eve, whose code does not compile (every check fails).
    assert footer["the normal facing the ray"].startswith("3 of 6")


def test_the_most_frequent_diagnoses_are_the_mistakes_concepts(grades, browser):
    grades, out = grades
    by_name = {m.name: m for m in mistakes("L04")}
    # Counted from what each student's mistake breaks (the mistakes' data), not the page's code.
    expected = Counter(f"L04: wrong: {by_name[n].concept}." for n in WRONG.values())
    expected["L04: your code does not compile; the compiler's first errors:"] += 1
    expected[next(iter(_results(grades)["fay"]["extra_data"]["diagnosis"].splitlines()))] += 1
    page, _, _ = open_page(browser, out / "index.html")
    shown = page.eval_on_selector_all(
        "table.diagnoses tbody tr",
        "els => els.map(e => [e.querySelector('th').textContent,"
        " +e.querySelector('td').textContent])",
    )
    assert dict(shown) == dict(expected)
    assert shown[0] == ["L04: wrong: the normal facing the ray.", 2]  # the most frequent first


def test_the_histogram_and_the_links(grades, browser):
    grades, out = grades
    results = _results(grades)
    assert (out / "scores.png").is_file()
    page, _, _ = open_page(browser, out / "index.html")
    counts = page.eval_on_selector_all(
        "table.bins tbody td[data-field=count]", "els => els.map(e => +e.textContent)"
    )
    shares = [d["score"] / sum(t["max_score"] for t in d["tests"]) for d in results.values()]
    expected = [0] * 10
    for s in shares:  # results.json's 4-decimal rounding: full marks read as 1 + 2e-16
        expected[min(int(round(s, 4) * 10), 9)] += 1
    assert counts == expected
    assert sum(counts) == len(results)  # full marks (fay) counted, in the last bin
    assert counts[0] == 1 and counts[9] == 2  # eve (0); cy (93%) and fay (full marks)
    links = dict(page.eval_on_selector_all(
        "table.matrix tbody th a",
        "els => els.map(e => [e.textContent, e.getAttribute('href')])",
    ))  # fmt: skip
    assert sorted(links) == ["ann", "bob", "cy", "eve", "fay"]  # not dee: --json only
    for student, href in links.items():
        assert (out / href).resolve() == (grades / student / "index.html").resolve()


def test_bad_grades_directories_are_named(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    assert main(["report", "class", str(tmp_path / "empty"), "--out", str(tmp_path / "c")]) == 2
    assert "no results.json" in capsys.readouterr().err
    (tmp_path / "bad" / "zed").mkdir(parents=True)
    (tmp_path / "bad" / "zed" / "results.json").write_text("{not json")
    assert main(["report", "class", str(tmp_path / "bad"), "--out", str(tmp_path / "c")]) == 2
    assert "zed/results.json" in capsys.readouterr().err
    assert not (tmp_path / "c").exists()


def test_a_single_file_class_page_stands_alone(grades, browser, tmp_path):
    grades_dir, _ = grades
    out = tmp_path / "class"
    assert main(["report", "class", str(grades_dir), "--out", str(out), "--single-file"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["index.html"]  # no scores.png beside it
    assert_stands_alone(browser, out / "index.html", tmp_path)
