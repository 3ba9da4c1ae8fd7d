"""rtlab report's pages: L04's page and a course index opened in a real browser (Debian's
Chromium driven by Playwright, from file://), their numbers against the metrics recomputed
here, and the site's atomic writing."""

import dataclasses
import html.parser
import itertools
import json
from pathlib import Path

import numpy as np
import pytest

from lessons.scene_checks import lesson_scenes, references
from reference.metrics import FLOAT32_SLACK, MITSUBA_TOLERANCE, compare
from reports.lesson import build_lesson_page
from reports.site import markdown_html, write_course_site, write_lesson_site

ROOT = Path(__file__).resolve().parents[2]
CHROMIUM = Path("/usr/bin/chromium")  # Debian's package, which the Makefile installs


@pytest.fixture(scope="module")
def pages():
    """L04 (three scenes; two known-wrong versions, their builds cached in build/) and L01
    (no scenes yet): built once for every test here."""
    return {
        "L04": build_lesson_page("L04", mistake_cap=2, command="tests/reports"),
        "L01": build_lesson_page("L01", mistake_cap=2, command="tests/reports"),
    }


@pytest.fixture(scope="module")
def site(pages, tmp_path_factory):
    out = tmp_path_factory.mktemp("site") / "site"
    write_course_site(out, pages.__getitem__, ["L01", "L04"], command="tests/reports")
    return out


@pytest.fixture(scope="module")
def browser():
    assert CHROMIUM.exists(), (
        f"{CHROMIUM} is missing: the page tests need Debian's chromium (`make setup` "
        "installs it with apt-get; `playwright install` cannot work offline)"
    )
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=str(CHROMIUM), args=["--no-sandbox", "--disable-gpu"])
        yield b
        b.close()


def open_page(browser, path: Path, javascript: bool = True):
    """Load ``path`` from file://; every request the page makes is recorded, and any that would
    leave the machine (not file://) is aborted. Returns (page, requests, errors)."""
    context = browser.new_context(java_script_enabled=javascript)
    page = context.new_page()
    requests, errors = [], []

    def route(r):
        requests.append(r.request.url)
        if r.request.url.startswith("file://"):
            r.continue_()
        else:
            r.abort()

    page.route("**/*", route)
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("requestfailed", lambda r: errors.append(f"failed: {r.url}"))
    page.goto(path.resolve().as_uri(), wait_until="load")
    return page, requests, errors


def images_of(page):
    return page.eval_on_selector_all(
        "img", "els => els.map(e => [e.getAttribute('src'), e.naturalWidth, e.alt])"
    )


def assert_offline_and_whole(page, requests, errors, root: Path):
    assert errors == []
    outside = [u for u in requests if not u.startswith(root.resolve().as_uri())]
    assert outside == [], f"requests that leave the site: {outside}"
    for src, width, alt in images_of(page):
        assert width > 0, f"broken image {src[:80]}"
        assert alt.strip(), f"an image without alt text: {src[:80]}"
    levels = page.eval_on_selector_all("h1, h2, h3, h4", "els => els.map(e => +e.tagName[1])")
    assert levels[0] == 1 and levels.count(1) == 1
    assert all(b - a <= 1 for a, b in itertools.pairwise(levels)), levels


# A phone's viewport (CSS pixels of a small phone held upright) and a projector's (1080p).
PHONE = {"width": 360, "height": 740}
PROJECTOR = {"width": 1920, "height": 1080}


def assert_reads_on_a_phone_and_a_projector(page) -> None:
    """On a phone the page is one column: nothing wider than the screen but what scrolls in
    its own box (a wide table, a code block), so the text never runs off the side; on a
    projector the body text is at least 16 CSS pixels (readable from the back of a room only
    if the browser's default is kept, not shrunk)."""
    page.set_viewport_size(PHONE)
    width = page.evaluate("document.documentElement.scrollWidth")
    assert width <= PHONE["width"], f"the page is {width} px wide on a {PHONE['width']} px phone"
    page.set_viewport_size(PROJECTOR)
    size = page.evaluate("parseFloat(getComputedStyle(document.body).fontSize)")
    assert size >= 16, size


def assert_stands_alone(browser, path: Path, tmp: Path) -> None:
    """A --single-file page copied alone into an empty directory (as mailed) still shows every
    image, each inlined as a data: URI, and makes no request but its own."""
    alone = tmp / "alone"
    alone.mkdir()
    copy = alone / path.name
    copy.write_bytes(path.read_bytes())
    page, requests, errors = open_page(browser, copy)
    assert_offline_and_whole(page, requests, errors, alone)
    srcs = [src for src, _, _ in images_of(page)]
    assert srcs and all(src.startswith("data:image/png;base64,") for src in srcs)
    assert requests == [copy.resolve().as_uri()]


def test_l04_page_in_a_browser(site, pages, browser):
    page, requests, errors = open_page(browser, site / "L04" / "index.html")
    assert_offline_and_whole(page, requests, errors, site)
    assert "L04" in page.inner_text("h1")
    h2 = page.eval_on_selector_all("h2", "els => els.map(e => e.textContent)")
    for title in (
        "The idea",
        "The scenes, by rtlab, POV-Ray and Mitsuba",
        "What the mistake looks like",
        "What the checks probe",
    ):
        assert title in h2
    scenes = pages["L04"].scenes
    assert len(scenes) == 3
    for s in scenes:
        rows = page.eval_on_selector_all(
            f"#metrics-{s.check.name} tbody tr", "els => els.map(e => e.dataset.renderer)"
        )
        assert rows == ["povray", "mitsuba"]
    # Three renders and two heat maps per scene, three images per known-wrong version shown.
    shown = [m for m in pages["L04"].mistakes_shown if m.image is not None]
    assert len(shown) == 2
    assert len(images_of(page)) == 5 * len(scenes) + 3 * len(shown)
    # The mistakes' images are the grader's kind of render and changed the picture.
    assert all(m.changes_picture for m in shown)
    # A screenshot of the page kind, kept as the test's artefact.
    (ROOT / "out").mkdir(exist_ok=True)
    page.screenshot(path=str(ROOT / "out" / "report-lesson-L04.png"), full_page=True)
    assert_reads_on_a_phone_and_a_projector(page)


def test_l04_page_reads_without_javascript(site, browser):
    page, requests, errors = open_page(browser, site / "L04" / "index.html", javascript=False)
    assert_offline_and_whole(page, requests, errors, site)
    assert page.locator("table.metrics").count() == 3


def test_course_index_in_a_browser(site, browser):
    page, requests, errors = open_page(browser, site / "index.html")
    assert_offline_and_whole(page, requests, errors, site)
    links = page.eval_on_selector_all("main a", "els => els.map(e => e.getAttribute('href'))")
    assert links == ["L01/index.html", "L04/index.html"]
    for link in links:
        assert (site / link).is_file()
    page.screenshot(path=str(ROOT / "out" / "report-course-index.png"), full_page=True)
    assert_reads_on_a_phone_and_a_projector(page)
    # L01's page: its text, a metric table per scene, the probes' concepts and the mistakes.
    page, requests, errors = open_page(browser, site / "L01" / "index.html")
    assert_offline_and_whole(page, requests, errors, site)
    text = page.inner_text("main")
    assert page.locator("table.metrics").count() == len(lesson_scenes("L01")) > 0
    assert "primary rays through pixel centres" in text
    assert page.locator("table.listed tbody tr").count() >= 4


def test_single_file_page_inlines_every_image(pages, browser, tmp_path):
    path = write_lesson_site(tmp_path, pages["L04"], inline=True)
    assert sorted(p.name for p in path.parent.iterdir()) == ["index.html", "metrics.json"]
    assert_stands_alone(browser, path, tmp_path)


class Cells(html.parser.HTMLParser):
    """The metric tables' cells: (table id, renderer, field) -> (data-value, text)."""

    def __init__(self):
        super().__init__()
        self.cells, self.table, self.renderer, self.cell, self.text = {}, None, None, None, ""

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "table":
            self.table = a.get("id")
        elif tag == "tr":
            self.renderer = a.get("data-renderer")
        elif tag == "td" and "data-field" in a:
            self.cell, self.text = (
                (self.table, self.renderer, a["data-field"], a.get("data-value")),
                "",
            )

    def handle_data(self, data):
        if self.cell is not None:
            self.text += data

    def handle_endtag(self, tag):
        if tag == "td" and self.cell is not None:
            table, renderer, name, value = self.cell
            self.cells[(table, renderer, name)] = (value, self.text.strip())
            self.cell = None


def test_the_numbers_on_the_page_are_the_metrics_of_its_images(site, pages):
    import tracer

    cells = Cells()
    cells.feed((site / "L04" / "index.html").read_text())
    rows = json.loads((site / "L04" / "metrics.json").read_text())
    checked = 0
    for s in pages["L04"].scenes:
        ours = s.images["rtlab"]
        # The page's rtlab image is the solution's render (packets give the same bits).
        assert np.array_equal(ours, tracer.render(s.check.load(), threads=2, progress=False))
        refs = references(s.check)
        for name in s.check.references:
            # The images compared are the grader's references, under the grader's tolerances.
            assert np.array_equal(s.images[name], refs[name])
            bound = refs["povray_bound"] + FLOAT32_SLACK if name == "povray" else MITSUBA_TOLERANCE
            again = compare(refs[name], ours, bound).as_dict()
            row = next(r for r in rows if r["scene"] == s.check.name and r["renderer"] == name)
            for field in ("rmse", "max_abs", "psnr", "ssim", "flip", "over_tolerance"):
                value, text = cells.cells[(f"metrics-{s.check.name}", name, field)]
                assert float(value) == pytest.approx(again[field], rel=1e-12, abs=0), field
                assert float(row[field]) == float(value)
                assert text  # a formatted number
                checked += 1
            assert row["pixels_over"] == again["pixels_over"]
            _, over = cells.cells[(f"metrics-{s.check.name}", name, "over_tolerance")]
            assert f"({again['pixels_over']} of {ours.shape[0] * ours.shape[1]})" in over
            # The solution agrees with both references on every scene of the lesson.
            assert cells.cells[(f"metrics-{s.check.name}", name, "agrees")][1] == "yes"
    assert checked == 3 * 2 * 6


def test_a_failed_run_leaves_the_old_site(site, pages, tmp_path):
    import shutil

    out = tmp_path / "site"
    shutil.copytree(site, out)
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    broken = dataclasses.replace(pages["L04"].scenes[0])
    broken.images = dict(broken.images, rtlab=np.zeros((4, 4)))
    page = dataclasses.replace(pages["L04"], scenes=[broken])
    with pytest.raises(ValueError, match="shape"):  # the injected failure happened
        write_lesson_site(out, page)
    with pytest.raises(ValueError, match="shape"):
        write_course_site(out, {"L01": pages["L01"], "L04": page}.__getitem__, ["L01", "L04"])
    after = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    assert after == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["site"]  # no stage left beside it
    assert sorted(p.name for p in out.iterdir()) == ["L01", "L04", "index.html"]
    # And a good run replaces the lesson's directory whole.
    write_lesson_site(out, pages["L04"])
    assert (out / "L04" / "index.html").read_bytes() == before[out / "L04" / "index.html"]
    assert sorted(p.name for p in out.iterdir()) == ["L01", "L04", "index.html"]


def test_products_in_formulas_are_not_emphasis():
    text = markdown_html('"color += coef*ambient*material" points *towards* it, `a*b*c`')
    assert "coef*ambient*material" in text
    assert "<em>towards</em>" in text
    assert "<code>a*b*c</code>" in text


def test_unknown_lesson_is_bad_input(capsys):
    from tracer.cli import main

    assert main(["report", "lesson", "L99", "--out", "/nonexistent/site"]) == 2
    assert "L99" in capsys.readouterr().err


@pytest.fixture(scope="module")
def special(tmp_path_factory):
    """L11 (stereo pairs: the references render one eye at a time) and L12 (path-traced
    scenes, compared in the statistical sense), each scene as the grader judges it."""
    out = tmp_path_factory.mktemp("special") / "site"
    pages = {
        i: build_lesson_page(i, mistake_cap=1, command="tests/reports") for i in ("L11", "L12")
    }
    write_course_site(out, pages.__getitem__, list(pages), command="tests/reports")
    return out, pages


def test_stereo_and_path_scenes_are_judged_as_the_grader_judges_them(special, browser):
    from lessons.scene_checks import PathSceneCheck, path_seeds

    out, pages = special
    for lesson, page in pages.items():
        assert [s.check.name for s in page.scenes] == [c.name for c in lesson_scenes(lesson)]
        for s in page.scenes:
            # The course's solution passes the grader's check of every scene, and says so.
            assert s.agrees, (lesson, s.check.name, s.verdict)
            assert s.verdict and all("**differs**" not in line for line in s.verdict)
            assert all(row.agrees for row in s.rows)
            if isinstance(s.check, PathSceneCheck):  # the mean of the grader's replicates
                scene = s.check.load()
                import tracer

                again = [tracer.render(scene.with_overrides(seed=seed), threads=2,
                                       progress=False) for seed in path_seeds(s.check)]  # fmt: skip
                mean = np.mean(np.asarray(again, np.float64), axis=0)
                # The page's mean is of the same float32 renders, summed in double and rounded
                # to float32 once: within float32's half ulp (2^-24 relative) of this one.
                assert np.allclose(s.images["rtlab"], mean, rtol=2**-23, atol=0)
                assert np.array_equal(s.images["mitsuba"], references(s.check)["path_mean"]
                                      .astype(np.float32))  # fmt: skip
            elif s.check.load().camera.stereo is not None:  # both eyes, side by side or not
                assert s.images["povray"].shape == s.images["rtlab"].shape
    shown = pages["L12"].mistakes_shown
    assert len(shown) == 1 and shown[0].changes_picture and shown[0].caught.startswith("fails ")
    for lesson in pages:
        page, requests, errors = open_page(browser, out / lesson / "index.html")
        assert_offline_and_whole(page, requests, errors, out)
        said = page.eval_on_selector_all(".grader strong", "els => els.map(e => e.textContent)")
        assert said == ["it passes"] * len(pages[lesson].scenes)
        assert "<p>" not in page.inner_text("main")  # the verdict lines' Markdown rendered


def test_a_ctrl_c_lost_in_a_finaliser_stops_the_report_before_its_next_scene(lost_interrupt):
    """A Ctrl-C lost on the way (tests/conftest.py) stops `rtlab report` before the next scene
    renders, not at the end of the course."""
    from reports.lesson import scene_page
    from tracer import interrupt

    check = lesson_scenes("L04")[0]
    with pytest.raises(interrupt.Interrupted):
        scene_page(check)
