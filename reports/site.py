"""Writing the pages: Jinja2 templates (reports/templates/), the lessons' Markdown through
markdown-it-py, images as PNG files beside the page (or, ``single_file``, inlined as data:
URIs), and every site written atomically: built in a temporary directory beside the target and
renamed into place, so a failed run leaves the old site as it was.

The pages request nothing from any other host (no CDN, no web font, no script): formulas are
plain text and Unicode as the lessons write them, and the pages read the same without
JavaScript.
"""

from __future__ import annotations

import base64
import contextlib
import json
import math
import os
import re
import shutil
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from reports.lesson import NAMES, LessonPage

TEMPLATES = Path(__file__).resolve().parent / "templates"
# The scenes are small (81 x 61 pixels): shown three times larger, each pixel a square.
SCALE = 3


# An asterisk between two characters of a formula ("coef*ambient*material", quoted from the
# slides) is a product, not emphasis; emphasis opens after a space ("points *towards* it").
PRODUCT = re.compile(r"(?<=[\w)\]])\*(?=[\w(])")


def _products_escaped(text: str) -> str:
    """Escape the products' asterisks outside code (code spans, fenced and indented blocks)."""
    out, fenced = [], False
    for line in text.split("\n"):
        if line.lstrip().startswith("```"):
            fenced = not fenced
        if fenced or line.startswith("    ") or line.lstrip().startswith("```"):
            out.append(line)
            continue
        parts = line.split("`")
        parts[::2] = [PRODUCT.sub(r"\\*", part) for part in parts[::2]]
        out.append("`".join(parts))
    return "\n".join(out)


def markdown_html(text: str) -> str:
    """CommonMark with tables; raw HTML in the text is escaped, never passed through."""
    from markdown_it import MarkdownIt

    md = MarkdownIt("commonmark", {"html": False}).enable("table")
    return md.render(_products_escaped(text))


def markdown_inline(text: str) -> str:
    """One line of Markdown (a grader's verdict line) as inline HTML: no paragraph around it."""
    from markdown_it import MarkdownIt

    return MarkdownIt("commonmark", {"html": False}).renderInline(_products_escaped(text))


def _ssim(value: float) -> str:
    """SSIM near 1 as 1 - its distance from 1, which is what tells two such images apart."""
    if math.isfinite(value) and 0 < 1 - value < 1e-3:
        return f"1 \u2212 {_number(1 - value, 2)}"
    return _number(value, 5)


def _number(value: float, digits: int = 3) -> str:
    if isinstance(value, float) and math.isnan(value):
        return "NaN"
    if isinstance(value, float) and math.isinf(value):
        return "∞"
    if value == 0:
        return "0"
    if 1e-3 <= abs(value) < 1e4:
        return f"{value:.{digits + 1}g}"
    return f"{value:.{digits}e}".replace("e-0", "e-").replace("e+0", "e+")


def _seconds(value: float) -> str:
    return f"{value:.3f} s" if value < 10 else f"{value:.1f} s"


def environment() -> Any:
    import jinja2

    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(TEMPLATES),
        autoescape=jinja2.select_autoescape(["html"]),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
    )
    env.filters["num"] = _number
    env.filters["seconds"] = _seconds
    env.filters["ssim"] = _ssim
    env.filters["sentence"] = lambda v: v[:1].upper() + v[1:]
    env.filters["pct"] = lambda v: f"{100 * v:.3g}%"
    env.filters["md"] = markdown_html
    env.filters["md_inline"] = markdown_inline
    env.globals["NAMES"] = NAMES
    return env


class Assets:
    """The page's images: written as PNG files into the page's directory and named by a
    relative path; with ``inline``, read back as data: URIs and not kept."""

    def __init__(self, directory: Path, inline: bool) -> None:
        self.directory = directory
        self.inline = inline

    def _src(self, path: Path) -> str:
        if not self.inline:
            return path.relative_to(self.directory).as_posix()
        uri = data_uri(path)
        path.unlink()
        return uri

    def image(self, name: str, image: np.ndarray) -> str:
        from tracer.image import save_image

        path = self.directory / name
        path.parent.mkdir(parents=True, exist_ok=True)
        save_image(path, np.asarray(image)[..., :3])
        return self._src(path)

    def png(self, name: str, data: bytes) -> str:
        """A PNG already drawn (a plot's, reports/plots.py)."""
        path = self.directory / name
        path.write_bytes(data)
        return self._src(path)

    def heat_map(self, name: str, reference: np.ndarray, test: np.ndarray) -> str:
        from reference.metrics import heat_map

        path = self.directory / name
        path.parent.mkdir(parents=True, exist_ok=True)
        heat_map(reference, test, path)
        return self._src(path)


# An image's source in our templates: <img ... src="NAME" ...>, NAME a file beside the page.
IMG_SRC = re.compile(r'(<img\b[^>]*?\bsrc=")([^"]+)(")')
MIME = {".png": "image/png", ".jpg": "image/jpeg", ".jpeg": "image/jpeg", ".svg": "image/svg+xml"}


def data_uri(path: Path) -> str:
    """A file as a data: URI, its type from its suffix (a page's image inlined)."""
    mime = MIME.get(path.suffix.lower(), "application/octet-stream")
    return f"data:{mime};base64,{base64.b64encode(path.read_bytes()).decode('ascii')}"


def inline_images(html: str, directory: Path) -> tuple[str, set[Path]]:
    """``--single-file``: every <img> whose source is a file under ``directory`` becomes a
    data: URI, so the page stands alone (to mail, to attach); returns the page and the files
    read (the caller removes those that exist only for the page). A source that is already a
    data: URI, or names no file there, is left as it is (the browser tests find the latter)."""
    import html as htmllib

    directory = Path(directory).resolve()
    used: set[Path] = set()

    def replace(match: re.Match[str]) -> str:
        src = htmllib.unescape(match.group(2))
        path = (directory / src).resolve()
        if src.startswith("data:") or "://" in src or not path.is_file():
            return match.group(0)
        if not path.is_relative_to(directory):
            return match.group(0)
        used.add(path)
        return f"{match.group(1)}{data_uri(path)}{match.group(3)}"

    return IMG_SRC.sub(replace, html), used


def _jsonable(value: Any) -> Any:
    from reference.compare import _jsonable as plain

    return plain(value)


# The lesson whose page links to the stiff study (study/, `rtlab study stiff`): the study is
# the precision lesson's report (issue 11).
STUDY_LESSON = "L13"


def render_lesson(page: LessonPage, directory: Path, *, inline: bool, index: bool,
                  study: str = "") -> Path:  # fmt: skip
    """Write ``directory/index.html`` (and its images, and metrics.json: the comparison rows
    the page shows) for one lesson; ``index``: the page links to the course's index;
    ``study``: the stiff study's page, relative to this one, where the site has it."""
    directory.mkdir(parents=True, exist_ok=True)
    assets = Assets(directory, inline)
    scenes = []
    for s in page.scenes:
        ours = s.images["rtlab"]
        images = {name: assets.image(f"{s.check.name}-{name}.png", image)
                  for name, image in s.images.items()}  # fmt: skip
        heat = {name: assets.heat_map(f"{s.check.name}-diff-{name}.png", s.images[name], ours)
                for name in s.check.references}  # fmt: skip
        scenes.append({"page": s, "images": images, "heat": heat})
    mistakes = []
    for m in page.mistakes_shown:
        entry: dict[str, Any] = {"shown": m}
        if m.image is not None and m.correct is not None:
            stem = f"mistakes/{m.mistake.name}-{m.scene}"
            entry["image"] = assets.image(f"{stem}.png", m.image)
            entry["correct"] = assets.image(f"{stem}-correct.png", m.correct)
            entry["heat"] = assets.heat_map(f"{stem}-diff.png", m.correct, m.image)
        mistakes.append(entry)
    plots = [{"plot": p, "src": assets.png(f"plot-{p.name}.png", p.png)} for p in page.plots]
    html = (
        environment()
        .get_template("lesson.html")
        .render(
            page=page,
            text_html=markdown_html(page.text_markdown) if page.text_markdown else "",
            scenes=scenes,
            mistakes=mistakes,
            plots=plots,
            scale=SCALE,
            index=index,
            study=study,
            study_lesson=STUDY_LESSON,
        )
    )
    (directory / "index.html").write_text(html)
    rows = [r.as_dict() for r in page.rows]
    (directory / "metrics.json").write_text(json.dumps(_jsonable(rows), indent=2) + "\n")
    with contextlib.suppress(OSError):
        (directory / "mistakes").rmdir()  # empty when inlined
    return directory / "index.html"


def render_index(pages: list[LessonPage], directory: Path, *, command: str, seconds: float,
                 made: str) -> Path:  # fmt: skip
    html = (
        environment()
        .get_template("index.html")
        .render(pages=pages, command=command, seconds=seconds, made=made)
    )
    path = directory / "index.html"
    path.write_text(html)
    return path


@contextlib.contextmanager
def staged(target: Path) -> Iterator[Path]:
    """A temporary directory beside ``target``; on success it replaces ``target`` (the old one
    renamed aside first, then removed); on failure it is removed and ``target`` is untouched."""
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    stage = Path(tempfile.mkdtemp(prefix=f".{target.name}.tmp-", dir=target.parent))
    try:
        yield stage
    except BaseException:
        shutil.rmtree(stage, ignore_errors=True)
        raise
    os.chmod(stage, 0o755)  # mkdtemp's 0700 would hide the site from a web server
    old = None
    if target.exists():
        old = Path(tempfile.mkdtemp(prefix=f".{target.name}.old-", dir=target.parent))
        os.rename(target, old / target.name)
    os.rename(stage, target)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


def write_lesson_site(out: Path, page: LessonPage, *, inline: bool = False) -> Path:
    """``out/Lnn/index.html``, replacing that lesson's directory only."""
    with staged(Path(out) / page.lesson.id) as stage:
        render_lesson(page, stage, inline=inline, index=(Path(out) / "index.html").exists())
    return Path(out) / page.lesson.id / "index.html"


def write_course_site(
    out: Path,
    build: Callable[[str], LessonPage],
    lesson_ids: list[str],
    *,
    inline: bool = False,
    command: str = "",
    progress: Callable[[str], None] = lambda line: None,
    study: str = "none",
) -> Path:
    """Every lesson's page and the index, the whole of ``out`` replaced at the end;
    ``study`` ("quick" or "full"): the stiff study too (study/run.py), in ``out/study/``,
    linked from the precision lesson's page."""
    import time

    start = time.perf_counter()
    with staged(Path(out)) as stage:
        link = ""
        if study != "none":
            from study.run import run as run_study

            summary = run_study(stage / "study", quick=study == "quick")
            link = "../study/index.html"
            progress(f"study: {len(summary['rows'])} rows in {summary['total_seconds']:.1f} s")
        pages = []
        for lesson_id in lesson_ids:
            page = build(lesson_id)
            render_lesson(page, stage / lesson_id, inline=inline, index=True,
                          study=link if lesson_id == STUDY_LESSON else "")  # fmt: skip
            pages.append(page)
            progress(f"{lesson_id}: {len(page.scenes)} scenes, "
                     f"{len(page.mistakes_shown)} known-wrong versions rendered")  # fmt: skip
        made = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
        render_index(pages, stage, command=command, seconds=time.perf_counter() - start,
                     made=made)  # fmt: skip
    return Path(out) / "index.html"
