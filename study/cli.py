"""``rtlab study stiff --out DIR [--quick] [--family NAME]`` and ``rtlab study freeze --from
DIR/failures.json --out tests/study/frozen``: the verb's work (its entry in the parser lives in
tracer/cli.py beside the other verbs)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def add_arguments(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="study_command", required=True)
    p = sub.add_parser("stiff", help="stiff and extreme cases: where each method breaks")
    p.add_argument("--out", required=True, help="the study's directory, e.g. study/")
    p.add_argument("--quick", action="store_true",
                   help="a fixed-seed subset: a few knob values, 1000 rays each")  # fmt: skip
    p.add_argument("--family", help="one family only (default: all)")
    p.add_argument(
        "--jobs",
        type=int,
        default=None,
        help="families traced at once, a process each (default: one a core); or, with "
        "--workers or --scheduler, each family a task of a Dask batch (tracer/batch.py)",
    )
    from tracer.batch import add_engine_arguments

    add_engine_arguments(p, default_serial=True, zero="no Dask: --jobs")
    f = sub.add_parser("freeze", help="freeze failing rays of a run as regression tests")
    f.add_argument("--from", dest="source", required=True,
                   help="a run's failures.json (from rtlab study stiff)")  # fmt: skip
    f.add_argument("--out", required=True, help="where FAMILY.json go, e.g. tests/study/frozen")
    f.add_argument("--per", type=int, default=2,
                   help="rays kept per family, method and metric (default 2)")  # fmt: skip


def freeze(args: argparse.Namespace) -> int:
    from study.freeze import FreezeError, write_frozen

    try:
        counts = write_frozen(Path(args.source), Path(args.out), per=args.per)
    except FreezeError as error:
        print(f"rtlab: error: {error}", file=sys.stderr)
        return 2
    said = ", ".join(f"{family} {n}" for family, n in counts.items()) or "none"
    print(f"rtlab: froze {sum(counts.values())} rays into {args.out}: {said}")
    return 0


def run(args: argparse.Namespace) -> int:
    """Exit status: 0 done; 2 bad input (an unknown family, an --out that is a file, a
    failures.json that is missing or not one)."""
    if args.study_command == "freeze":
        return freeze(args)
    from study.run import StudyError
    from study.run import run as run_study
    from tracer.batch import Engine

    # --workers N (N > 0) or --scheduler: the batch layer; otherwise --jobs, as before.
    engine = None
    if args.scheduler is not None or args.workers:
        if args.jobs is not None:
            print("rtlab: error: --jobs is the study's own process pool; --workers and "
                  "--scheduler the batch layer's: give one of them", file=sys.stderr)  # fmt: skip
            return 2
        engine = Engine(args.workers, args.scheduler)
    try:
        summary = run_study(Path(args.out), quick=args.quick, family=args.family, jobs=args.jobs,
                            engine=engine)  # fmt: skip
    except StudyError as error:
        print(f"rtlab: error: {error}", file=sys.stderr)
        return 2
    fails = sum(1 for f in summary["failures"] if f["method"] == "rtlab")
    print(f"rtlab: wrote {Path(args.out) / 'index.html'}: {len(summary['rows'])} rows in "
          f"{summary['total_seconds']:.1f} s; rtlab failed on {fails} kept rays")  # fmt: skip
    return 0
