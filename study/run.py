"""The study's run: every family's knob values, every method that applies, the metrics
aggregated per knob value into rows, and the outputs (rows.json, breakdown.json,
failures.json, a plot per family, index.html), each written atomically."""

from __future__ import annotations

import difflib
import functools
import json
import multiprocessing
import os
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from study import chains, metrics, truth
from study.families import FAMILIES, Case, Family
from study.methods import Method, methods

#: --quick: rays per knob value (the full run: FULL_RAYS), and the seed of every generator.
QUICK_RAYS = 1000
FULL_RAYS = 4000
SEED = 20251

#: The share of wrong answers past which a method is said to break (issue 11: 0.1%).
BREAKDOWN = 1e-3
#: The share metrics a breakdown is judged by, per protocol.
HEADLINE = {"decision": "wrong_decisions", "spawn": "self_hits", "shadow": "false_occlusions",
            "scale": "scale_mismatches"}  # fmt: skip
HEADLINE.update(chains.HEADLINE)  # mirror chains: study/chains.py
#: Failing rays kept per family, knob value, method and metric (as hex floats).
KEEP = 10


class StudyError(ValueError):
    """Bad input to the study (an unknown family, an --out that is a file)."""


def family_named(name: str) -> Family:
    if name in FAMILIES:
        return FAMILIES[name]
    near = difflib.get_close_matches(name, FAMILIES, n=1)
    hint = f"; did you mean {near[0]!r}?" if near else ""
    raise StudyError(f"--family: unknown family {name!r}{hint} (one of {', '.join(FAMILIES)})")


@dataclass
class _Acc:
    rays: int = 0
    undecidable: int = 0
    sums: dict[str, float] | None = None
    weights: dict[str, int] | None = None  # the rays of the cases that report each metric
    maxima: dict[str, float] | None = None

    def add(self, m: dict[str, float], rays: int, undecidable: int) -> None:
        self.sums = self.sums or {}
        self.weights = self.weights or {}
        self.maxima = self.maxima or {}
        for k, v in m.items():
            if k.endswith("_max") or k.endswith("_max_separated"):
                self.maxima[k] = max(self.maxima.get(k, 0.0), v)
            else:
                self.sums[k] = self.sums.get(k, 0.0) + v * rays
                self.weights[k] = self.weights.get(k, 0) + rays
        self.rays += rays
        self.undecidable += undecidable

    def values(self) -> dict[str, float]:
        """Each metric over the cases that report it (a case with no ray that both the method
        and the truth hit reports no t error: it is left out, not counted as 0)."""
        weights = self.weights or {}
        out = {k: v / weights[k] for k, v in (self.sums or {}).items()}
        return out | dict(self.maxima or {})


def _json_value(v: float) -> float | None:
    """A row's value as JSON has it: NaN and infinities (an overflowed t error) are null."""
    return v if np.isfinite(v) else None


def _hex(v: np.ndarray) -> list[str]:
    return [float(x).hex() for x in v]


def _protocol_fields(case: Case, i: int) -> dict[str, Any]:
    """What replaying ray i of the case needs beyond its origin and direction (study/freeze.py):
    the protocol, and its spawned direction and side, its light, or its scale."""
    out: dict[str, Any] = {"protocol": case.protocol}
    if case.leave is not None:
        out["leave"] = _hex(case.leave[i])
    if case.outward is not None:
        out["outward"] = bool(case.outward[i])
    if case.light is not None:
        out["light"] = [float(x).hex() for x in case.light]
    if case.protocol == "scale":
        out["scale_k"] = case.scale_k
    return out


def _evaluate(case: Case, method: Method, tru: truth.Truth | None) -> metrics.Result:
    if case.protocol in chains.PROTOCOLS:  # nearly touching surfaces: study/chains.py
        return chains.evaluate(case, method)
    if case.protocol == "decision":
        assert tru is not None
        return metrics.decision(case, method, tru)
    if case.protocol == "spawn":
        return metrics.spawn(case, method)
    if case.protocol == "shadow":
        return metrics.shadow(case, method)
    return metrics.scale(case, method)


def _applies(method: Method, case: Case) -> bool:
    if case.protocol in chains.PROTOCOLS:
        return chains.applies(method, case)
    if case.shape.kind not in method.kinds:
        return False
    # Every method has spawn and occluded now; a method may still name fewer protocols.
    return case.protocol in method.protocols


def run_family(
    family: Family, quick: bool, all_methods: list[Method]
) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    rows: list[dict[str, Any]] = []
    failures: list[dict[str, Any]] = []
    values = family.quick_values if quick else family.values
    n = QUICK_RAYS if quick else FULL_RAYS
    for value in values:
        index = list(FAMILIES).index(family.name)
        # Seeded by the knob value's place in the full sweep: --quick traces a subset of it.
        # And by the family's place in FAMILIES: a new family goes at the end, never between,
        # or every family after it gets other rays (and the tests' measured facts move).
        rng = np.random.default_rng([SEED, index, family.values.index(value)])
        cases = family.generate(value, n, rng)
        acc: dict[str, _Acc] = {}
        for case in cases:
            tru = None
            if case.protocol == "decision":
                # Route 2 on every 4th ray of the quick run, every ray of the full one.
                tru = truth.truth(case.shape, case.origins, case.directions,
                                  check_every=4 if quick else 1)  # fmt: skip
            for method in all_methods:
                if not _applies(method, case):
                    continue
                m, undecidable, fails = _evaluate(case, method, tru)
                acc.setdefault(method.name, _Acc()).add(m, len(case.origins), undecidable)
                for metric, idx in fails.items():
                    for i in idx[:KEEP]:
                        failures.append({
                            "family": family.name, "knob_value": value, "method": method.name,
                            "version": method.version, "metric": metric,
                            "shape": {"kind": case.shape.kind} | case.shape.scene_object(),
                            "origin": _hex(case.origins[i]), "direction": _hex(case.directions[i]),
                        } | _protocol_fields(case, int(i)))  # fmt: skip
        for method in all_methods:
            if method.name not in acc:
                continue
            a = acc[method.name]
            for metric, v in sorted(a.values().items()):
                rows.append({
                    "family": family.name, "knob": family.knob, "knob_value": value,
                    "method": method.name, "version": method.version, "metric": metric,
                    "value": _json_value(v), "rays": a.rays, "undecidable": a.undecidable,
                })  # fmt: skip
    return rows, failures


def breakdown(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per family and method, the knob value where the headline share first exceeds 0.1%,
    coming from the easy end (None: never): for families stiff at both ends, one per end."""
    out = []
    for family in FAMILIES.values():
        mine = [r for r in rows if r["family"] == family.name]
        for method in dict.fromkeys(r["method"] for r in mine):
            shares = {r["metric"] for r in mine if r["method"] == method}
            metric = next((m for m in HEADLINE.values() if m in shares), None)
            if metric is None:
                continue
            over = sorted(r["knob_value"] for r in mine if r["method"] == method
                          and r["metric"] == metric
                          and (r["value"] is None or r["value"] > BREAKDOWN))  # fmt: skip
            entry: dict[str, Any] = {
                "family": family.name,
                "knob": family.knob,
                "method": method,
                "metric": metric,
                "exceeding": over,
            }
            middle = 0.0 if not family.log_knob else 1.0
            if family.stiffer == "up":
                entry["breaks_at"] = over[0] if over else None
            elif family.stiffer == "down":
                entry["breaks_at"] = over[-1] if over else None
            else:
                low = [v for v in over if v < middle]
                high = [v for v in over if v > middle]
                entry["breaks_at"] = {"low": low[-1] if low else None,
                                      "high": high[0] if high else None}  # fmt: skip
            out.append(entry)
    return out


@functools.lru_cache(maxsize=2)
def _methods(include_mitsuba: bool) -> list[Method]:
    return methods(include_mitsuba)


def _family_job(name: str, quick: bool, include_mitsuba: bool) -> tuple[list, list, float]:
    """One family in a worker process: its rows, its failures, its seconds."""
    t0 = time.perf_counter()
    rows, fails = run_family(FAMILIES[name], quick, _methods(include_mitsuba))
    return rows, fails, time.perf_counter() - t0


#: What a family's shard depends on besides its name and options: the study's code, the core
#: it traces (the methods call tracer._core) and the bindings.
STUDY_SOURCES = ("study/*.py", "tracer/cpp/*", "tracer/*.py", "converters/*.py")


def family_shard(name: str, quick: bool, include_mitsuba: bool, path: str) -> dict[str, Any]:
    """One batch task (tracer/batch.py): a family's rows and failures into the shard file
    `path` (atomically); what it returns is the seconds, kept apart from the shard (which
    must not depend on the machine)."""
    from tracer.batch import write_atomic

    rows, fails, secs = _family_job(name, quick, include_mitsuba)
    write_atomic(Path(path), json.dumps({"rows": rows, "failures": fails}, indent=1,
                                        allow_nan=False) + "\n")  # fmt: skip
    return {"seconds": round(secs, 3)}


def _batched(families: list[Family], out: Path, quick: bool, include_mitsuba: bool,
             engine: Any) -> list[tuple[list, list, float]]:  # fmt: skip
    """Each family a task of the batch layer, its shard in out/shards/ keyed by what went
    in; a shard of an earlier run with the same key is read, not traced again."""
    from study import __file__ as study_init
    from tracer.batch import Task, digest, run_batch, sources_digest, summary

    root = Path(study_init).resolve().parent.parent
    code = sources_digest(root, STUDY_SOURCES)
    shards = (out / "shards").resolve()
    tasks = []
    # The costliest first, so that the last to finish is a short one.
    for f in sorted(families, key=lambda f: -len(f.quick_values if quick else f.values)):
        key = digest(f.name, quick, include_mitsuba, code)
        path = shards / f"{f.name}-{'quick' if quick else 'full'}.json"
        tasks.append(Task(f.name, family_shard, (f.name, quick, include_mitsuba, str(path)),
                          path.with_suffix(".done.json"), key))  # fmt: skip
    outcomes = {o.name: o for o in run_batch(tasks, engine, desc="study")}
    bad = [o for o in outcomes.values() if o.status != "ok" and o.status != "skipped"]
    if bad:
        raise StudyError(summary(list(outcomes.values()), "families"))
    made = []
    for f in families:  # FAMILIES' order, whatever order they finished in
        path = shards / f"{f.name}-{'quick' if quick else 'full'}.json"
        shard = json.loads(path.read_text())
        made.append((shard["rows"], shard["failures"], outcomes[f.name].data.get("seconds", 0.0)))
    return made


def run(out: Path, quick: bool = False, family: str | None = None,
        include_mitsuba: bool = True, jobs: int | None = None,
        engine: Any = None) -> dict[str, Any]:  # fmt: skip
    """Run the study into ``out``; returns a summary (rows, breakdown, seconds). ``jobs``:
    families traced at once, each in its own process (default: one per core); the rows come
    out in FAMILIES' order whatever the order they finish in, and each family's rays are its
    own seed's (study/run.py run_family()), so the outputs do not depend on ``jobs``.
    ``engine`` (tracer.batch.Engine: --workers, --scheduler): each family a task of the batch
    layer instead, its shard kept in out/shards/ (an interrupted run, run again, traces only
    the families that did not finish); the outputs are the same bytes."""
    from tracer.image import atomic_path

    families = [family_named(family)] if family else list(FAMILIES.values())
    if out.exists() and not out.is_dir():
        raise StudyError(f"--out: {out} is a file; expected a directory (it is created)")
    if jobs is not None and jobs < 1:
        raise StudyError(f"--jobs: {jobs}; expected a number of processes, 1 or more")
    start = time.perf_counter()
    jobs = min(jobs or os.cpu_count() or 1, len(families))
    rows: list[dict[str, Any]] = []
    failures: list[dict[str, Any]] = []
    seconds: dict[str, float] = {}
    if engine is not None:
        done = iter(_batched(families, out, quick, include_mitsuba, engine))
        jobs = 1
    elif jobs == 1:
        done = (_family_job(f.name, quick, include_mitsuba) for f in families)
    else:
        # "spawn": a fresh interpreter per worker (Dr.Jit's and Embree's threads do not survive
        # a fork). Each worker sets its methods up once (Mitsuba's import, its variants).
        pool = ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context("spawn"))
        # The costliest first, so that the last to finish is a short one.
        order = sorted(families, key=lambda f: -len(f.quick_values if quick else f.values))
        futures = {f.name: pool.submit(_family_job, f.name, quick, include_mitsuba)
                   for f in order}  # fmt: skip
        done = (futures[f.name].result() for f in families)
    try:
        for f, (r, fails, secs) in zip(families, done, strict=True):
            rows += r
            failures += fails
            seconds[f.name] = secs
    finally:
        if jobs > 1:
            pool.shutdown(cancel_futures=True)
    brk = breakdown(rows)
    out.mkdir(parents=True, exist_ok=True)
    for name, data in (("rows.json", rows), ("breakdown.json", brk),
                       ("failures.json", failures)):  # fmt: skip
        with atomic_path(out / name) as tmp:
            tmp.write_text(json.dumps(data, indent=1, allow_nan=False) + "\n")
    from study.report import write_report

    write_report(out, families, rows, brk, failures, quick=quick, seconds=seconds)
    return {"rows": rows, "breakdown": brk, "failures": failures, "seconds": seconds,
            "total_seconds": time.perf_counter() - start}  # fmt: skip
