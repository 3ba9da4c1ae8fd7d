"""`rtlab compare scene.toml --against povray,mitsuba --out-dir DIR --html`: the comparison as a
page beside its images (the lesson pages' scene block), opened in Chromium, its numbers those
of the --json rows."""

import json
from pathlib import Path

import pytest

from reports.compare_page import write_compare_page
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
from tracer.scene import load_scene

__all__ = ["browser"]  # the fixture, shared with test_pages.py

SCENE = ROOT / "lessons" / "L04_lambert" / "scenes" / "coloured_light.toml"  # 81 x 61


def test_compare_html_in_a_browser(tmp_path: Path, browser) -> None:
    out = tmp_path / "cmp"
    status = main(["compare", str(SCENE), "--against", "povray,mitsuba", "--out-dir", str(out),
                   "--json", str(out / "rows.json"), "--html"])  # fmt: skip
    assert status == 0  # the solution's scene: both references agree
    rows = json.loads((out / "rows.json").read_text())
    page, requests, errors = open_page(browser, out / "coloured_light.html")
    assert_offline_and_whole(page, requests, errors, out)
    # rtlab's, POV-Ray's and Mitsuba's renders, and a heat map per reference: files beside it.
    srcs = [src for src, _, _ in images_of(page)]
    assert len(srcs) == 5 and all((out / s).is_file() for s in srcs)
    refs = [r for r in rows if r["renderer"] != "rtlab"]
    shown = page.eval_on_selector_all(
        "#metrics-coloured_light tbody tr", "els => els.map(e => e.dataset.renderer)"
    )
    assert shown == [r["renderer"] for r in refs]
    for r in refs:
        tr = page.locator(f"#metrics-coloured_light tr[data-renderer='{r['renderer']}']")
        for field in ("rmse", "max_abs", "psnr", "ssim", "flip", "over_tolerance"):
            value = tr.locator(f"[data-field={field}]").get_attribute("data-value")
            assert float(value) == pytest.approx(float(r[field]), rel=1e-12, abs=0), field
        assert tr.locator("[data-field=agrees]").inner_text() == ("yes" if r["agrees"] else "NO")
    times = page.eval_on_selector_all(
        "#times-coloured_light tbody tr", "els => els.map(e => e.dataset.renderer)"
    )
    assert times == [r["renderer"] for r in rows]
    (ROOT / "out").mkdir(exist_ok=True)
    page.screenshot(path=str(ROOT / "out" / "report-compare.png"), full_page=True)
    assert_reads_on_a_phone_and_a_projector(page)
    # --single-file's page (the same rows, written again inlined) mailed alone.
    path = write_compare_page(load_scene(SCENE), rows, out, inline=True)
    assert all((out / s).is_file() for s in srcs)  # compare's own outputs stay
    assert_stands_alone(browser, path, tmp_path)


def test_compare_html_needs_an_out_dir(capsys, tmp_path) -> None:
    assert main(["compare", str(SCENE), "--html"]) == 2
    assert "--out-dir" in capsys.readouterr().err
    assert main(["compare", str(SCENE), "--out-dir", str(tmp_path), "--single-file"]) == 2
    assert "--html" in capsys.readouterr().err
