"""Builds of the core timed against each other, A against B (issue 12).

``python -m reference.build_ab --variant SPEC --variant SPEC [...] [--cases ex25,...]
[--threads 1 2] [--rounds 7] [--repeats 5] [--allow-different] [--json FILE]``

How every speed change of reference/speed-log.md was kept or dropped, as one command: a
compiler, a flag or a commit against another, on the bench's own cases, on one machine in one
run. Each variant is built into build/ab/NAME (reference/core_build.py; ninja rebuilds only
what changed), then each runs in a worker process of its own that loads its build as
tracer._core. The workers take turns, one timing each per case, thread count and round (the
best of ``--repeats`` runs), the order reversed every other round, so that a drift of the
machine (20% from hour to hour here) falls on all of them alike. A round's figure for a variant
is its speed against the first variant's in that round; the table gives each one's median time
and the median [range] of that ratio over the rounds.

Before any timing counts, each case's output (the image, or the hits) must be the same bit for
bit in every variant as in the first, thread count by thread count: a change of speed is
measured on the same work, and a build that changed the image is not a faster one.
``--allow-different`` times them anyway (a change meant to alter the output) and says which
differ.

A SPEC is a name, then ``key=value`` words (shell quoting, so flags may hold spaces):

    installed                      the core `make` built (.venv), built by nobody here
    NAME                           this checkout's files, as `make` builds them (its
                                   CORE_CXX, Clang 19)
    NAME cxx=clang++-22            another compiler
    NAME flags="-mtune=znver4"     CMAKE_CXX_FLAGS (before the CMakeLists' own options,
                                   so an -O level there is overridden by its -O3)
    NAME rev=HEAD~1                a commit's files (git archive) instead of the checkout's
    NAME cmake="-DRTLAB_MARCH=rocketlake"
                                   more CMake options (the core's instruction set:
                                   CMakeLists.txt's RTLAB_MARCH)

The cases are `rtlab bench`'s rtlab sides (reference/bench.py), at its sizes: ex25 (1920x1024, 1
spp), bunny-primary (the aov integrator's camera rays), bunny-diffuse (2M incoherent rays, the
batch call), cornell-64 and cornell-128 (64 spp, Sobol points). ``--size W H`` renders ex25 and
bunny-primary smaller (a quick look, not the bench's figures).

Examples: ``python -m reference.build_ab --variant installed --variant "c22 cxx=clang++-22"``
(a compiler); ``--variant "old rev=HEAD~1" --variant new`` (the last commit)."""

from __future__ import annotations

import argparse
import difflib
import hashlib
import io
import json
import os
import shlex
import shutil
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

from reference.core_build import ROOT, BuildError, build_core, load_core, make_cxx

CASES = ("ex25", "bunny-primary", "bunny-diffuse", "cornell-64", "cornell-128")
_KEYS = ("cxx", "flags", "rev", "cmake")
#: The installed core, `make`'s build: a variant of this name is not built here.
INSTALLED = "installed"


class ABError(RuntimeError):
    """A usage error, a variant that did not build, a worker that failed, or outputs that
    differ: the message says which and why."""


@dataclass(frozen=True)
class Variant:
    name: str
    cxx: str = field(default_factory=make_cxx)  # the Makefile's CORE_CXX
    flags: str = ""
    rev: str | None = None  # a git revision; None: this checkout's files
    cmake: str = ""  # more CMake options, shell-quoted

    @property
    def installed(self) -> bool:
        return self.name == INSTALLED

    def describe(self) -> str:
        if self.installed:
            return "the core make built (.venv)"
        words = [self.cxx] + [w for w in (self.flags, self.cmake) if w]
        return " ".join(words) + (f", commit {self.rev}" if self.rev else ", this checkout")


def parse_variant(text: str) -> Variant:
    """A --variant SPEC: a name, then key=value words (shlex)."""
    try:
        words = shlex.split(text)
    except ValueError as error:
        raise ABError(f"--variant {text!r}: {error}") from error
    if not words or "=" in words[0]:
        raise ABError(f"--variant {text!r}: expected a name first, then key=value words")
    name, fields = words[0], {}
    if not all(c.isalnum() or c in "-_." for c in name):
        raise ABError(f"--variant {text!r}: a name of letters, digits, '-', '_' and '.' only")
    for word in words[1:]:
        key, eq, value = word.partition("=")
        if not eq:
            raise ABError(f"--variant {text!r}: {word!r} is not key=value")
        if key not in _KEYS:
            near = difflib.get_close_matches(key, _KEYS, n=1)
            hint = f" (did you mean {near[0]!r}?)" if near else ""
            raise ABError(
                f"--variant {text!r}: unknown key {key!r}{hint}; expected {', '.join(_KEYS)}"
            )
        if key in fields:
            raise ABError(f"--variant {text!r}: {key} given twice")
        fields[key] = value
    if name == INSTALLED and fields:
        raise ABError(f"--variant {text!r}: {INSTALLED} is make's build; it takes no keys")
    return Variant(name, **fields)


def _commit(variant: Variant) -> str | None:
    """The commit a variant builds from (None: this checkout's files)."""
    if variant.rev is None:
        return None
    commit = subprocess.run(
        ["git", "-C", str(ROOT), "rev-parse", "--verify", "--quiet", f"{variant.rev}^{{commit}}"],
        capture_output=True, text=True,
    )  # fmt: skip
    if commit.returncode != 0:
        raise ABError(f"variant {variant.name}: rev={variant.rev}: not a commit of {ROOT}")
    return commit.stdout.strip()


def _compiler(variant: Variant) -> str:
    found = shutil.which(variant.cxx)
    if found is None:
        raise ABError(
            f"variant {variant.name}: compiler {variant.cxx} is not on PATH "
            f"(Debian: apt-get install {variant.cxx.replace('++', '')})"
        )
    return found


def check_variants(variants: list[Variant]) -> None:
    """Everything that can be wrong with the variants before any is built: two or more, each
    its own name, each compiler on PATH, each commit known."""
    names = [v.name for v in variants]
    if len(variants) < 2 or len(set(names)) != len(names):
        raise ABError(f"--variant: expected two or more, each its own name; got {names}")
    for variant in variants:
        if not variant.installed:
            _compiler(variant)
            _commit(variant)


def _source(variant: Variant, folder: Path) -> Path:
    """The tree a variant builds from: this checkout, or its commit's files, exported again
    whenever the commit the revision names is not the one exported last. The variant's build
    goes with the old files: git archive gives each file its commit's time, older than the
    objects built from the last export, so ninja would see nothing changed and keep them."""
    commit = _commit(variant)
    if commit is None:
        return ROOT
    source, stamp = folder / "src", folder / "src.commit"
    if stamp.exists() and stamp.read_text() == commit:
        return source
    shutil.rmtree(source, ignore_errors=True)
    shutil.rmtree(folder / "build", ignore_errors=True)
    source.mkdir(parents=True)
    archive = subprocess.run(
        ["git", "-C", str(ROOT), "archive", "--format=tar", commit], capture_output=True, check=True
    )
    with tarfile.open(fileobj=io.BytesIO(archive.stdout)) as files:
        files.extractall(source, filter="data")
    stamp.write_text(commit)
    return source


def installed_core() -> Path:
    """The path of the core `make` built, found without loading it."""
    import importlib.util

    spec = importlib.util.find_spec("tracer._core")
    if spec is None or spec.origin is None:
        raise ABError("no installed core (tracer._core): run `make setup` first")
    return Path(spec.origin)


def build_variant(variant: Variant, log: Callable[[str], None] = print) -> Path:
    """The variant's core, built into build/ab/NAME (the installed one as it is). A folder
    last configured otherwise (another compiler, flags or options under the same name) is
    emptied first: CMake's cache would keep an option the new spec no longer gives."""
    if variant.installed:
        return installed_core()
    compiler = _compiler(variant)
    folder = ROOT / "build" / "ab" / variant.name
    options = [f"-DCMAKE_CXX_COMPILER={compiler}", f"-DCMAKE_CXX_FLAGS={variant.flags}"]
    options += shlex.split(variant.cmake)
    source = _source(variant, folder)
    # The source folder is part of the configuration: CMake refuses a build folder configured
    # from another one (a name used first with rev=, then for this checkout).
    configuration = [*options, f"source={source}"]
    configured = folder / "build" / "rtlab-options.json"
    if configured.exists() and json.loads(configured.read_text()) != configuration:
        shutil.rmtree(folder / "build")
    log(f"building {variant.name} ({variant.describe()}) in {folder / 'build'}")
    start = time.perf_counter()
    try:
        made = build_core(folder / "build", *options, source=source)
    except BuildError as error:
        raise ABError(f"variant {variant.name} ({variant.describe()}): {error}") from error
    configured.write_text(json.dumps(configuration))
    for line in made.warnings:
        log(f"  {variant.name}: {line}")
    log(f"built {variant.name} in {time.perf_counter() - start:.0f} s")
    return made.so


# -- The worker: one variant's core, timing one case at a time --------------------------------


def _digest(*arrays: Any) -> str:
    import numpy as np

    h = hashlib.sha256()
    for a in arrays:
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()[:16]


def _case_runner(case: str, size: tuple[int, int] | None) -> Callable[[int], tuple[float, str]]:
    """A function of a thread count that runs `case` once: (seconds, digest of its output)."""
    from reference.bench import (
        DIFFUSE_RAYS,
        DIFFUSE_SEED,
        bunny_alone,
        cornell_scene,
        diffuse_rays,
        ex25_scene,
    )
    from tracer.render import render_with_stats, to_core

    width, height = size or (1920, 1024)
    if case in ("ex25", "bunny-primary", "cornell-64", "cornell-128"):
        if case == "ex25":
            scene = ex25_scene(width, height)
        elif case == "bunny-primary":
            scene = bunny_alone(width, height)
        else:
            scene = cornell_scene(int(case.split("-")[1]))

        def render(threads: int) -> tuple[float, str]:
            done = render_with_stats(scene, threads=threads, progress=False)
            return done.seconds, _digest(done.image)

        return render
    if case == "bunny-diffuse":
        from tracer import _core

        bunny = bunny_alone()
        mesh = bunny.objects[0]
        origins, directions = diffuse_rays(mesh.vertices, mesh.faces, DIFFUSE_RAYS, DIFFUSE_SEED)
        core = to_core(bunny)

        def trace(threads: int) -> tuple[float, str]:
            start = time.perf_counter()
            hits = _core.closest_mesh_hits(core, origins, directions, threads)
            return time.perf_counter() - start, _digest(*hits)

        return trace
    raise ABError(f"unknown case {case!r}")


def worker(so: str, stdin: IO[str], stdout: IO[str]) -> None:
    """Serve timings with the core at `so` loaded as tracer._core: one JSON request a line
    ({"case", "threads", "repeats", "size"}), one JSON answer a line ({"seconds": the best of
    the repeats, "digest"}, or {"error"}); the first answer names the core's compiler."""
    core = load_core(so)
    print(json.dumps({"compiler": str(core.compiler)}), file=stdout, flush=True)
    runners: dict[tuple[str, Any], Callable[[int], tuple[float, str]]] = {}
    for line in stdin:
        request = json.loads(line)
        try:
            size = tuple(request["size"]) if request.get("size") else None
            key = (request["case"], size)
            if key not in runners:
                runners[key] = _case_runner(request["case"], size)  # type: ignore[arg-type]
            runs = [runners[key](request["threads"]) for _ in range(request["repeats"])]
            answer: dict[str, Any] = {
                "seconds": min(s for s, _ in runs),
                "digest": runs[0][1] if len({d for _, d in runs}) == 1 else "unsteady",
            }
        except Exception as error:  # the parent reports it with the variant's name
            answer = {"error": f"{type(error).__name__}: {error}"}
        print(json.dumps(answer), file=stdout, flush=True)


@dataclass
class Worker:
    variant: Variant
    process: subprocess.Popen[str]
    errors: IO[str]  # the process's stderr
    compiler: str = ""

    def ask(self, request: dict[str, Any]) -> dict[str, Any]:
        assert self.process.stdin is not None and self.process.stdout is not None
        self.process.stdin.write(json.dumps(request) + "\n")
        self.process.stdin.flush()
        return self.answer()

    def answer(self) -> dict[str, Any]:
        assert self.process.stdout is not None
        line = self.process.stdout.readline()
        if not line:
            self.process.wait()
            self.errors.seek(0)
            err = self.errors.read()[-3000:]
            raise ABError(
                f"the worker of variant {self.variant.name} stopped "
                f"(exit {self.process.returncode}):\n{err}"
            )
        answer: dict[str, Any] = json.loads(line)
        if "error" in answer:
            raise ABError(f"variant {self.variant.name}: {answer['error']}")
        return answer


@contextmanager
def workers(built: list[tuple[Variant, Path]]) -> Iterator[list[Worker]]:
    """A worker process per variant, stopped however the block ends."""
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "PYTHONPATH": str(ROOT)}
    started: list[Worker] = []
    with ExitStack() as files:
        try:
            for variant, so in built:
                # Its errors go to a file, read when it fails: a pipe nobody reads while it
                # runs would stop it once full.
                errors = files.enter_context(tempfile.TemporaryFile("w+"))
                process = subprocess.Popen(
                    [sys.executable, "-m", "reference.build_ab", "--worker", str(so)],
                    stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=errors,
                    text=True, cwd=ROOT, env=env,
                )  # fmt: skip
                started.append(Worker(variant, process, errors))
            for w in started:
                w.compiler = w.answer()["compiler"]
            yield started
        finally:
            for w in started:
                if w.process.poll() is None:
                    w.process.kill()
                w.process.wait()
                for pipe in (w.process.stdin, w.process.stdout):
                    if pipe is not None:
                        pipe.close()


# -- The rounds and their summary ------------------------------------------------------------


@dataclass
class Cell:
    """One case at one thread count: each variant's time in each round, and its digests."""

    case: str
    threads: int
    seconds: dict[str, list[float]]
    digests: dict[str, set[str]]


def order_of(round_: int, names: list[str]) -> list[str]:
    """The variants' turn order in a round: as given in even rounds, reversed in odd ones."""
    return names if round_ % 2 == 0 else names[::-1]


def different_outputs(cells: list[Cell], first: str) -> list[str]:
    """Where a variant's output differs from the first variant's (or from itself between
    runs), one line each; empty when every case gave the same bits everywhere."""
    lines = []
    for cell in cells:
        want = cell.digests[first]
        for name, got in cell.digests.items():
            if len(got) != 1 or "unsteady" in got:
                lines.append(f"{cell.case}, {cell.threads} thread(s): {name}'s output varies")
            elif name != first and got != want:
                lines.append(f"{cell.case}, {cell.threads} thread(s): {name} differs from {first}")
    return lines


def summarize(cells: list[Cell], names: list[str]) -> list[dict[str, Any]]:
    """A row per case, thread count and variant: the median of its round times, and the
    median, lowest and highest of its speed against the first variant, round by round."""
    rows = []
    for cell in cells:
        base = cell.seconds[names[0]]
        for name in names:
            times = cell.seconds[name]
            speed = [b / t for b, t in zip(base, times, strict=True)]
            rows.append({"case": cell.case, "threads": cell.threads, "variant": name,
                         "seconds": statistics.median(times), "rounds": times,
                         "speed_vs_first": statistics.median(speed),
                         "speed_min": min(speed), "speed_max": max(speed)})  # fmt: skip
    return rows


def format_table(rows: list[dict[str, Any]], names: list[str]) -> str:
    """The summary as text: a line per case and thread count, a column per variant."""
    head = f"{'case':<16} {'threads':>7}" + "".join(f" {n:>30}" for n in names)
    lines = [head]
    cells: dict[tuple[str, int], dict[str, dict[str, Any]]] = {}
    for row in rows:
        cells.setdefault((row["case"], row["threads"]), {})[row["variant"]] = row
    for (case, threads), by_name in cells.items():
        parts = []
        for i, name in enumerate(names):
            r = by_name[name]
            vs = "" if i == 0 else (
                f" {r['speed_vs_first']:.3f}x [{r['speed_min']:.3f}-{r['speed_max']:.3f}]"
            )  # fmt: skip
            parts.append(f" {r['seconds'] * 1e3:>10.2f} ms{vs:>17}")
        lines.append(f"{case:<16} {threads:>7}" + "".join(parts))
    return "\n".join(lines)


def run_rounds(pool: list[Worker], cases: list[str], threads: list[int], rounds: int,
               repeats: int, size: tuple[int, int] | None, allow_different: bool,
               log: Callable[[str], None] = print) -> list[Cell]:  # fmt: skip
    """The alternating rounds. After the first, the outputs are compared, and unless
    `allow_different` a difference stops the run before more time is spent."""
    from tracer import interrupt  # not at the top: a worker loads its core before tracer

    names = [w.variant.name for w in pool]
    by_name = {w.variant.name: w for w in pool}
    cells = [
        Cell(case, n, {name: [] for name in names}, {name: set() for name in names})
        for case in cases
        for n in threads
    ]
    for round_ in range(rounds):
        for cell in cells:
            for name in order_of(round_, names):
                # A Ctrl-C that a finaliser swallowed (tracer/interrupt.py) stops the rounds
                # here: the suite once saw this tool run on for a minute after its SIGINT.
                interrupt.raise_if_interrupted()
                answer = by_name[name].ask({"case": cell.case, "threads": cell.threads,
                                            "repeats": repeats, "size": size})  # fmt: skip
                cell.seconds[name].append(answer["seconds"])
                cell.digests[name].add(answer["digest"])
        log(f"round {round_ + 1} of {rounds}: " + ", ".join(
            f"{c.case}/{c.threads} " + " ".join(f"{c.seconds[n][-1] * 1e3:.1f}" for n in names)
            for c in cells))  # fmt: skip
        if round_ == 0:
            differ = different_outputs(cells, names[0])
            if differ and not allow_different:
                raise ABError(
                    "not the same work, so not timed further (--allow-different times it "
                    "anyway):\n  " + "\n  ".join(differ)
                )
    return cells


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if args[:1] == ["--worker"] and len(args) == 2:
        worker(args[1], sys.stdin, sys.stdout)
        return 0
    parser = argparse.ArgumentParser(
        prog="python -m reference.build_ab",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--variant",
        action="append",
        required=True,
        metavar="SPEC",
        help="a build to time (at least two; the first is the baseline)",
    )
    parser.add_argument(
        "--cases",
        default="ex25,bunny-diffuse",
        help=f"comma-separated, of {', '.join(CASES)} (default: %(default)s)",
    )
    parser.add_argument("--threads", type=int, nargs="+", default=[1])
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument(
        "--repeats",
        type=int,
        default=5,
        help="runs a turn, of which the best counts (default 5: a 2-thread Ex 25 of 25 ms is "
        "slowed by whatever else wakes on either core, so the best of 3 still spread 0.79x "
        "to 1.17x over 7 rounds of two builds on the Zen 4)",
    )
    parser.add_argument(
        "--size",
        type=int,
        nargs=2,
        metavar=("W", "H"),
        help="ex25 and bunny-primary at W x H instead of 1920 x 1024",
    )
    parser.add_argument(
        "--allow-different",
        action="store_true",
        help="time variants whose output differs from the first's",
    )
    parser.add_argument("--json", type=Path, help="write the rows here")  # fmt: skip
    opts = parser.parse_args(args)
    from tracer import interrupt  # the parent's; a worker loads its core before tracer

    handlers = interrupt.install()
    try:
        variants = [parse_variant(v) for v in opts.variant]
        check_variants(variants)
        names = [v.name for v in variants]
        cases = [c.strip() for c in opts.cases.split(",") if c.strip()]
        for case in cases:
            if case not in CASES:
                near = difflib.get_close_matches(case, CASES, n=1)
                hint = f" (did you mean {near[0]!r}?)" if near else ""
                raise ABError(f"--cases: unknown case {case!r}{hint}; expected {', '.join(CASES)}")
        for label, value in (("--rounds", opts.rounds), ("--repeats", opts.repeats)):
            if value < 1:
                raise ABError(f"{label}: expected a number >= 1, got {value}")
        if any(n < 1 for n in opts.threads):
            raise ABError(f"--threads: expected numbers >= 1, got {opts.threads}")
        if opts.size and min(opts.size) < 1:
            raise ABError(f"--size: expected a width and a height >= 1, got {opts.size}")
        built = [(v, build_variant(v)) for v in variants]
        from reference.bench import cpu

        with workers(built) as pool:
            for w in pool:
                print(f"{w.variant.name}: {w.compiler}; {w.variant.describe()}")
            size = tuple(opts.size) if opts.size else None
            cells = run_rounds(pool, cases, opts.threads, opts.rounds, opts.repeats, size,
                               opts.allow_different)  # fmt: skip
            compilers = {w.variant.name: w.compiler for w in pool}
    except ABError as error:
        print(f"build_ab: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # the workers are stopped by workers()' exit; nothing written
        print("build_ab: interrupted; no rows written", file=sys.stderr)
        return 130
    finally:
        interrupt.restore(handlers)
    for line in different_outputs(cells, names[0]):
        print(f"output differs: {line}")
    rows = summarize(cells, names)
    machine = cpu()
    print(
        f"{machine['cpu_model']}, {machine['cpu_count']} cores; {opts.rounds} rounds, each "
        f"the best of {opts.repeats}; speed against {names[0]}, median [range]:"
    )
    print(format_table(rows, names))
    if opts.json:
        from tracer.image import atomic_path

        for row in rows:
            variant = variants[names.index(row["variant"])]
            row.update(machine, compiler=compilers[row["variant"]], cxx=variant.cxx,
                       flags=variant.flags, cmake=variant.cmake, rev=variant.rev,
                       repeats=opts.repeats)  # fmt: skip
        with atomic_path(opts.json) as tmp:
            tmp.write_text(json.dumps(rows, indent=1) + "\n")
        print(f"rows: {opts.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
