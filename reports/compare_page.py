"""``rtlab compare scene.toml --out-dir DIR --html``: the comparison as a page, DIR/<stem>.html,
beside the images and heat maps compare_scene wrote there, the lesson pages' scene block
(reports/templates/scene_block.html) over reference.compare's rows. Written atomically."""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Any

NAMES_BY_PREFIX = {"povray": "POV-Ray", "mitsuba": "Mitsuba 3"}


def _plain(value: Any) -> Any:
    """numpy scalars as Python's (the templates' number filters take float), inf kept."""
    import numpy as np

    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value.item() if isinstance(value, np.generic) else value


def _name(renderer: str) -> str:
    for prefix, name in NAMES_BY_PREFIX.items():
        if renderer.startswith(prefix):
            variant = renderer[len(prefix) :].lstrip("-")
            return f"{name} ({variant})" if variant else name
    return renderer


def _row(row: dict[str, Any], share: float | None) -> dict[str, Any]:
    """A reference's row in the fields of reports.lesson.ComparisonRow."""
    tolerance = row.get("tolerance", "")
    return {
        **row,
        "pixels": int(row["width"]) * int(row["height"]),
        "tolerance": f"{tolerance:g}" if isinstance(tolerance, float) else str(tolerance),
        "max_share": share if share is not None else float("nan"),
    }


def compare_blocks(scene: Any, rows: list[dict[str, Any]], out: Path) -> list[dict[str, Any]]:
    """One block per camera (two for a stereo pair, by the rows' ``eye``)."""
    from reference.compare import share_bound

    blocks: dict[str, dict[str, Any]] = {}
    stem = Path(scene.source).stem or "scene"
    for row in rows:
        eye = row.get("eye")
        key = f"{stem}-{eye}" if eye and len({r.get("eye") for r in rows}) > 1 else stem
        b = blocks.setdefault(key, {
            "name": key, "title": f"{stem}, {eye} eye" if key != stem else stem,
            "width": int(row["width"]), "height": int(row["height"]),
            "images": {}, "heat": {}, "rows": [], "runs": {},
        })  # fmt: skip
        renderer = row["renderer"]
        if "image" in row:
            png = Path(row["image"]).with_suffix(".png")
            b["images"][renderer] = Path(os.path.relpath(png, out)).as_posix()
        if "heat_map" in row:
            b["heat"][renderer] = Path(os.path.relpath(row["heat_map"], out)).as_posix()
        rays = row.get("rays") if isinstance(row.get("rays"), dict) else {}
        b["runs"][renderer] = {
            "trace_seconds": row["trace_seconds"],
            "whole_seconds": row["whole_seconds"],
            "rays": {k: int(v) for k, v in rays.items()},
            "note": row.get("variant", ""),
        }
        if renderer != "rtlab":
            b["rows"].append(_row(row, share_bound(scene, renderer)))
    return list(blocks.values())


def write_compare_page(scene: Any, rows: list[dict[str, Any]], out_dir: str | Path, *,
                       command: str = "", json_path: str | Path | None = None,
                       inline: bool = False) -> Path:  # fmt: skip
    """``out_dir/<scene>.html`` over the images compare wrote there; ``inline``
    (``--single-file``): the images inlined as data: URIs (the files stay: they are compare's
    outputs)."""
    from reports.site import SCALE, environment
    from tracer.image import atomic_path

    out = Path(out_dir)
    stem = Path(scene.source).stem or "scene"
    blocks = compare_blocks(scene, rows, out)
    refs = [r for r in rows if r["renderer"] != "rtlab"]
    agreeing = sum(r.get("agrees") is True for r in refs)
    no_verdict = sum(r.get("agrees") is None for r in refs)
    summary = (
        f"{agreeing} of {len(refs)} comparisons agree"
        + (f" ({no_verdict} without a verdict: sampling noise)" if no_verdict else "")
        + "."
    )
    env = environment()
    env.globals["NAMES"] = {r["renderer"]: _name(r["renderer"]) for r in rows}
    json_name = ""
    if json_path is not None and Path(json_path).resolve().parent == out.resolve():
        json_name = Path(json_path).name
    html = env.get_template("compare.html").render(
        stem=stem,
        source=scene.source,
        against=", ".join(dict.fromkeys(_name(r["renderer"]) for r in refs)),
        summary=summary,
        blocks=_plain(blocks),
        scale=SCALE,
        command=command,
        json_name=json_name,
        threads=next((r.get("threads") for r in rows if r["renderer"] == "rtlab"), "all"),
        made=time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
    )
    if inline:
        from reports.site import inline_images

        html, _ = inline_images(html, out)
    path = out / f"{stem}.html"
    with atomic_path(path) as tmp:
        tmp.write_text(html)
    return path
