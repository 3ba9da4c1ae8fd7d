"""The study's pages: a log-log plot per family (error against the knob, one line per method,
the knob values with undecidable rays shaded) and index.html through the reports' Jinja2
environment (reports/site.py, template reports/templates/study.html); and the error against
run time of every method as a Pareto plot (pareto.png, its numbers in pareto.json)."""

from __future__ import annotations

import json
import math
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


#: Where a t error of 0 ulps is drawn on the t panel's log axis.
T_FLOOR = 0.1
#: The t panel's metrics: (metric, line style).
T_METRICS = (("t_error_ulps_median", "-"), ("t_error_ulps_max", ":"))


def plot_family(family: Family, rows: list[dict[str, Any]], path: Path) -> str:
    """Write the family's plot: the headline share against the knob (left) and t's error in
    ulps, median and max over the rays both the method and the truth hit (right), "no data"
    marked where no ray is a hit for both (a method that misses everything has no t error,
    which a 0 would draw as perfect). Returns its alt text."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from tracer.image import atomic_path

    # A null value (an infinite error, study/run.py _json_value) is inf again: the line leaves
    # it out, the alt text says "at most inf".
    mine = [r | {"value": math.inf if r["value"] is None else r["value"]} for r in rows
            if r["family"] == family.name and r["metric"] == family.metric]  # fmt: skip
    fig, (ax, tax) = plt.subplots(1, 2, figsize=(11.0, 4.0), dpi=100)
    knobs = sorted({r["knob_value"] for r in mine})
    xs, label = _x(family, knobs)
    where = dict(zip(knobs, xs, strict=True))
    shaded = [r["knob_value"] for r in mine if r["undecidable"] > 0]
    for v in sorted(set(shaded)):
        x = where[v]
        lo, hi = (x / 1.5, x * 1.5) if family.log_knob else (x - 0.5, x + 0.5)
        for a in (ax, tax):
            a.axvspan(lo, hi, color="0.85", zorder=0)
    described = []
    t_said = []
    methods = list(dict.fromkeys(r["method"] for r in mine))
    t_rows = {(r["knob_value"], r["method"], r["metric"]): r["value"] for r in rows
              if r["family"] == family.name and r["metric"] in dict(T_METRICS)}  # fmt: skip
    no_data_drawn = False
    for i, method in enumerate(methods):
        color = f"C{i % 10}"
        pts = sorted((where[r["knob_value"]], max(r["value"], FLOOR)) for r in mine
                     if r["method"] == method)  # fmt: skip
        ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", label=method, color=color)
        worst = max(r["value"] for r in mine if r["method"] == method)
        described.append(f"{method} at most {worst:.3g}")
        if not t_rows:
            continue
        for metric, style in T_METRICS:
            tp = [(where[k], max(t_rows[(k, method, metric)], T_FLOOR)) for k in knobs
                  if t_rows.get((k, method, metric)) is not None]  # fmt: skip
            if tp:
                tax.plot([p[0] for p in tp], [p[1] for p in tp], style, marker=".", color=color)
        missing = [k for k in knobs if (k, method, "t_error_ulps_median") not in t_rows]
        if missing:
            # No ray is a hit for both: no data (drawn below the axis' floor, never as 0).
            tax.plot([where[k] for k in missing], [T_FLOOR / 3] * len(missing), "x",
                     color=color, markersize=8)  # fmt: skip
            no_data_drawn = True
        worst_t = max((t_rows[(k, method, "t_error_ulps_max")] or 0.0 for k in knobs
                       if (k, method, "t_error_ulps_max") in t_rows), default=None)  # fmt: skip
        t_said.append(f"{method} " + (f"at most {worst_t:.3g} ulps" if worst_t is not None
                                      else "no data") +
                      (f" (no data at {', '.join(f'{k:g}' for k in missing)})"
                       if missing and worst_t is not None else ""))  # fmt: skip
    for a in (ax, tax) if t_rows else (ax,):
        if family.log_knob:
            a.set_xscale("log")
        a.set_yscale("log")
        a.set_xlabel(label)
    ax.set_ylabel(family.metric.replace("_", " ") + f" (0 drawn at {FLOOR:g})")
    ax.set_title(family.name + (" (grey: knob values with undecidable rays)" if shaded else ""),
                 fontsize=10)  # fmt: skip
    ax.legend(fontsize=8)
    if t_rows:
        tax.set_ylabel(f"t error, ulps (0 drawn at {T_FLOOR:g})")
        tax.set_title("t error: median (solid), max (dotted); x: no data", fontsize=10)
        if no_data_drawn:
            tax.axhline(T_FLOOR / 2, color="0.5", linewidth=0.5)
            tax.text(0.01, 0.02, "x below the line: no ray a hit for both (no data)",
                     transform=tax.transAxes, fontsize=7)  # fmt: skip
    else:
        tax.set_xticks([])
        tax.set_yticks([])
        tax.set_title("t error", fontsize=10)
        tax.text(0.5, 0.5, "no data: this protocol judges no t", ha="center", va="center",
                 transform=tax.transAxes)  # fmt: skip
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)
    t_alt = ("; t error in ulps over the rays both hit: " + "; ".join(t_said) if t_rows
             else "; no t error: this protocol judges no t")  # fmt: skip
    return (f"{family.name}: {family.metric.replace('_', ' ')} against {family.knob}, one line "
            f"per method; " + "; ".join(described) + t_alt)  # fmt: skip


#: Method names that say how they are built, for the Pareto plot's labels (robust or naive,
#: double or float); a method not listed is labelled by its name alone.
KIND = {"rtlab": "robust, double", "textbook-double": "naive, double",
        "textbook-float": "naive, float", "rtlab-float": "robust, float",
        "mitsuba-scalar_rgb": "Mitsuba, float", "mitsuba-llvm_ad_rgb": "Mitsuba JIT, float",
        "embree": "Embree, float", "embree-robust": "Embree robust, float"}  # fmt: skip


def _mean(pairs: list[tuple[float, int]]) -> float:
    """The mean of values weighted by their rays."""
    rays = sum(n for _, n in pairs)
    return sum(v * n for v, n in pairs) / rays if rays else 0.0


#: The share metrics that say a method answered wrong, one per protocol (run.HEADLINE's).
WRONG = ("wrong_decisions", "self_hits", "false_occlusions", "scale_mismatches")
#: Methods measured on their own camera's rays only (study/methods_torus.py).
OWN_RAYS_ONLY = ("povray", "povray-sturm")


def pareto_points(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per method: its share of wrong answers (the headline share of each protocol: wrong
    decisions, self-hits, false occlusions, scale mismatches) over the rows (family and knob
    value) it has, and its time per ray on those same rows, both weighted by rays; the same
    over only the rows every method that takes any ray has ("common": the same rays for all,
    the fair comparison; POV-Ray takes only its camera's); and whether the method is on the
    Pareto front (no other method both faster and less often wrong)."""
    wrong: dict[tuple[str, float, str], list[tuple[float, int]]] = {}
    for r in rows:
        if r["metric"] in WRONG:
            wrong.setdefault((r["family"], r["knob_value"], r["method"]), []).append(
                (r["value"], r["rays"])
            )
    times = {(r["family"], r["knob_value"], r["method"]): r for r in rows
             if r["metric"] == "time_per_ray_s"}  # fmt: skip
    methods = list(dict.fromkeys(m for _, _, m in wrong))
    cells = {(f, k) for f, k, _ in wrong}
    # POV-Ray traces only its own camera's pixel rays (the torus-distance family): no cell of
    # the other families is its, so "every method" of the common panel is every other method.
    anyray = [m for m in methods if m not in OWN_RAYS_ONLY]
    common = {c for c in cells if all((*c, m) in wrong for m in anyray)}
    out = []
    for m in methods:
        mine = [c for c in sorted(cells) if (*c, m) in wrong]
        entry: dict[str, Any] = {"method": m, "kind": KIND.get(m, m)}
        for tag, where in (("", mine), ("common_", [c for c in mine if c in common])):
            entry[tag + "error"] = _mean([x for c in where for x in wrong[(*c, m)]])
            entry[tag + "time_per_ray_s"] = _mean([(times[(*c, m)]["value"], times[(*c, m)]["rays"])
                                                   for c in where if (*c, m) in times])  # fmt: skip
            entry[tag + "cells"] = len(where)
        out.append(entry)
    for tag in ("", "common_"):
        for e in out:
            e[tag + "front"] = e[tag + "cells"] > 0 and not any(
                o is not e
                and o[tag + "cells"] > 0
                and o[tag + "time_per_ray_s"] <= e[tag + "time_per_ray_s"]
                and o[tag + "error"] <= e[tag + "error"]
                and (o[tag + "time_per_ray_s"], o[tag + "error"])
                != (e[tag + "time_per_ray_s"], e[tag + "error"])
                for o in out
            )
    return out


def plot_pareto(points: list[dict[str, Any]], path: Path) -> str:
    """Error against time per ray, log-log, one point per method, the front drawn: left all
    of each method's rows, right only the rows every method has. Returns alt text."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from tracer.image import atomic_path

    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.4), dpi=100, sharey=True)
    for ax, tag, title in ((axes[0], "", "each method's own rows"),
                           (axes[1], "common_", "rows every method has")):  # fmt: skip
        pts = [p for p in points if p[tag + "cells"] > 0]
        for i, p in enumerate(pts):
            x, y = p[tag + "time_per_ray_s"], max(p[tag + "error"], FLOOR)
            ax.scatter([x], [y], marker="o" if "float" in p["kind"] else "s", zorder=3,
                       color="C3" if p[tag + "front"] else "C0")  # fmt: skip
            # Staggered labels: methods of one kind of call lie close together.
            ax.annotate(p["method"], (x, y), textcoords="offset points",
                        xytext=(4, 4 - 9 * (i % 3)), fontsize=7)  # fmt: skip
        front = sorted((p[tag + "time_per_ray_s"], max(p[tag + "error"], FLOOR)) for p in pts
                       if p[tag + "front"])  # fmt: skip
        if front:
            ax.step([f[0] for f in front], [f[1] for f in front], where="post", color="C3",
                    label="Pareto front", zorder=2)  # fmt: skip
            ax.legend(fontsize=8)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("time per ray (s; the method's own batch call)")
        ax.set_title(title, fontsize=10)
    axes[0].set_ylabel(f"share of wrong answers (0 drawn at {FLOOR:g})")
    fig.suptitle("Error against run time (square: double, circle: float; red: on the front)",
                 fontsize=10)  # fmt: skip
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)
    on = [p["method"] for p in points if p["common_front"] and p["common_cells"]]
    best = min((p for p in points if p["common_cells"]), key=lambda p: p["common_error"],
               default=None)  # fmt: skip
    said = "; ".join(f"{p['method']} ({p['kind']}): {p['common_error']:.3g} wrong at "
                     f"{p['common_time_per_ray_s']:.3g} s a ray" for p in points
                     if p["common_cells"])  # fmt: skip
    by = {p["method"]: p for p in points if p["common_cells"]}
    pairs = [(a, b) for a, b in (("rtlab-float", "textbook-float"), ("rtlab", "textbook-double"))
             if a in by and b in by]  # fmt: skip
    robust = " ".join(
        f"Robust against naive in {by[a]['kind'].split(', ')[1]}: {a} {by[a]['common_error']:.3g} "
        f"wrong at {by[a]['common_time_per_ray_s'] / by[b]['common_time_per_ray_s']:.2g} times "
        f"the time of {b} ({by[b]['common_error']:.3g} wrong)."
        for a, b in pairs
    )
    return (f"Share of wrong answers against time per ray on the rays every method traced: on "
            f"the Pareto front {', '.join(on) or 'none'}; fewest wrong: "
            f"{best['method'] if best else 'none'}. {robust} {said}")  # fmt: skip


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
    points = pareto_points(rows)
    with atomic_path(out / "pareto.json") as tmp:
        tmp.write_text(json.dumps(points, indent=1) + "\n")
    pareto = {"image": "pareto.png", "alt": plot_pareto(points, out / "pareto.png"),
              "points": points}  # fmt: skip
    html = environment().get_template("study.html").render(sections=sections, quick=quick,
                                                           pareto=pareto)  # fmt: skip
    path = out / "index.html"
    with atomic_path(path) as tmp:
        tmp.write_text(html)
    return path
