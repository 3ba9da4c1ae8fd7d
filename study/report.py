"""The study's pages: a log-log plot per family (error against the knob, one line per method,
the knob values with undecidable rays shaded) and index.html through the reports' Jinja2
environment (reports/site.py, template reports/templates/study.html)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from study.families import Family

#: Where a share of zero is drawn on a log axis (below any share of QUICK_RAYS rays).
FLOOR = 1e-5


def _x(family: Family, values: list[float]) -> tuple[list[float], str]:
    """Knob values as drawn: 0 on a log axis at a tenth of the smallest positive one."""
    if not family.log_knob:
        return values, family.knob
    positive = [v for v in values if v > 0]
    zero = min(positive) / 10 if positive else 1.0
    note = f" (0 drawn at {zero:g})" if 0 in values else ""
    return [v if v > 0 else zero for v in values], family.knob + note


def plot_family(family: Family, rows: list[dict[str, Any]], path: Path) -> str:
    """Write the family's plot; returns its alt text."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from tracer.image import atomic_path

    mine = [r for r in rows if r["family"] == family.name and r["metric"] == family.metric]
    fig, ax = plt.subplots(figsize=(6.4, 4.0), dpi=100)
    knobs = sorted({r["knob_value"] for r in mine})
    xs, label = _x(family, knobs)
    where = dict(zip(knobs, xs, strict=True))
    shaded = [r["knob_value"] for r in mine if r["undecidable"] > 0]
    for v in sorted(set(shaded)):
        x = where[v]
        lo, hi = (x / 1.5, x * 1.5) if family.log_knob else (x - 0.5, x + 0.5)
        ax.axvspan(lo, hi, color="0.85", zorder=0)
    described = []
    for method in dict.fromkeys(r["method"] for r in mine):
        pts = sorted((where[r["knob_value"]], max(r["value"], FLOOR)) for r in mine
                     if r["method"] == method)  # fmt: skip
        ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", label=method)
        worst = max(r["value"] for r in mine if r["method"] == method)
        described.append(f"{method} at most {worst:.3g}")
    if family.log_knob:
        ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(label)
    ax.set_ylabel(family.metric.replace("_", " ") + f" (0 drawn at {FLOOR:g})")
    ax.set_title(family.name + (" (grey: knob values with undecidable rays)" if shaded else ""))
    ax.legend(fontsize=8)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)
    return (f"{family.name}: {family.metric.replace('_', ' ')} against {family.knob}, one line "
            f"per method; " + "; ".join(described))  # fmt: skip


def write_report(
    out: Path,
    families: list[Family],
    rows: list[dict[str, Any]],
    breakdown: list[dict[str, Any]],
    failures: list[dict[str, Any]],
    *,
    quick: bool,
    seconds: dict[str, float],
) -> Path:
    from reports.site import environment
    from tracer.image import atomic_path

    sections = []
    for f in families:
        image = f"{f.name}.png"
        alt = plot_family(f, rows, out / image)
        mine = [r for r in rows if r["family"] == f.name]
        table = [r for r in mine if r["metric"] == f.metric]
        sections.append({
            "family": f, "image": image, "alt": alt, "rows": table,
            "breakdown": [b for b in breakdown if b["family"] == f.name],
            "failures": sum(1 for x in failures if x["family"] == f.name
                            and x["method"] == "rtlab"),
            "seconds": seconds.get(f.name, 0.0),
        })  # fmt: skip
    html = environment().get_template("study.html").render(sections=sections, quick=quick)
    path = out / "index.html"
    with atomic_path(path) as tmp:
        tmp.write_text(html)
    return path
