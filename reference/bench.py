"""Speed, side by side: ``rtlab bench SUITE --json FILE`` (a benchmark, not a test).

Every row has ``case``, ``renderer``, ``threads``, ``metric``, ``value`` and ``unit``, plus
``repeats`` and ``machine``. Times are the best of several runs in one process, interleaved by
renderer, so that ratios taken within one run hold even when the shared machine's absolute
speed drifts. Renderers: ``rtlab``, ``povray`` (its own Trace Time of one pass, start-up
excluded), ``mitsuba-llvm`` (a warm render, JIT compile excluded), ``mitsuba-scalar``.
"""

from __future__ import annotations

import json
import os
import platform
from collections.abc import Callable
from pathlib import Path
from typing import Any

from tracer.cli import demo_scene_path
from tracer.image import atomic_path
from tracer.render import render_with_stats
from tracer.scene import load_scene


def machine() -> str:
    model = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{model}, {os.cpu_count()} cores, {platform.system()} {platform.release()}"


def _best(fn: Callable[[], float], repeats: int) -> float:
    return min(fn() for _ in range(repeats))


def suite_classic(
    repeats: int = 3, threads: tuple[int, ...] = (1, 2), width: int = 1920, height: int = 1024
) -> list[dict[str, Any]]:
    """The demo scene (Ex 25) at 1920x1024, 1 spp: seconds per frame."""
    from reference.mitsuba import run_mitsuba
    from reference.povray import run_povray

    scene = load_scene(demo_scene_path()).with_overrides(width=width, height=height, spp=1)
    case = f"ex25-{width}x{height}"
    rows = []
    for n in threads:
        times = {
            # rtlab's frame is short, so the shared machine's hiccups weigh more: more repeats.
            "rtlab": _best(
                lambda n=n: render_with_stats(scene, threads=n, progress=False).seconds,
                2 * repeats + 1,
            ),
            "povray": _best(
                lambda n=n: run_povray(scene, threads=n, exr_pass=False).trace_seconds,
                max(1, repeats - 1),
            ),
            "mitsuba-llvm": _best(
                lambda n=n: run_mitsuba(scene, variant="llvm_ad_rgb", threads=n).render_seconds,
                max(1, repeats - 1),
            ),
        }
        for renderer, value in times.items():
            rows.append({"case": case, "renderer": renderer, "threads": n, "metric": "seconds",
                         "value": value, "unit": "s", "repeats": repeats})  # fmt: skip
    return rows


SUITES: dict[str, Callable[..., list[dict[str, Any]]]] = {"classic": suite_classic}


def run_suites(names: list[str], json_path: str | os.PathLike[str] | None) -> list[dict]:
    rows: list[dict[str, Any]] = []
    where = machine()
    for name in names:
        for row in SUITES[name]():
            row["suite"] = name
            row["machine"] = where
            rows.append(row)
    if json_path is not None:
        with atomic_path(json_path) as tmp:
            tmp.write_text(json.dumps(rows, indent=2) + "\n")
    return rows


def format_ratios(rows: list[dict[str, Any]]) -> str:
    """Each case and thread count: every renderer's value and its ratio to rtlab's."""
    lines = []
    keys = sorted({(r["case"], r["threads"], r["metric"]) for r in rows})
    for case, threads, metric in keys:
        group = {r["renderer"]: r for r in rows if (r["case"], r["threads"], r["metric"]) ==
                 (case, threads, metric)}  # fmt: skip
        ours = group.get("rtlab")
        lines.append(f"{case}, {threads} thread{'s' if threads > 1 else ''} ({metric}):")
        for name, r in group.items():
            ratio = ""
            if ours is not None and name != "rtlab":
                # seconds: how many times slower the other is; throughput: how many times faster
                x = r["value"] / ours["value"] if r["unit"] == "s" else ours["value"] / r["value"]
                ratio = (
                    f"   rtlab is {x:.2f}x faster" if x >= 1 else f"   rtlab is {1 / x:.2f}x slower"
                )
            lines.append(f"  {name:<16}{r['value']:>10.4f} {r['unit']}{ratio}")
    if rows:
        lines.append(f"machine: {rows[0]['machine']}")
    return "\n".join(lines)
