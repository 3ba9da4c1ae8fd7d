"""Untrusted student code, built and run only in child processes with limits.

A submission (a directory of C++ files named as in tracer/cpp/) is laid over the reference core
in a temporary directory; the compiler and whatever it built run as child processes with
resource.setrlimit limits on CPU time, address space and file size, a wall-clock timeout
(the whole process group is killed), and their output captured and cut at a limit. Each run
ends in one Outcome whose ``kind`` says what happened, in words a student can act on:

- ``ok``: exit status 0;
- ``failed``: another exit status (a compile error: the compiler's first errors);
- ``not_implemented``: a stub was called (lessons/cpp/not_implemented.h, exit status 86);
- ``crash``: killed by a signal (its name: SIGSEGV, SIGABRT, ...);
- ``memory``: it asked for more memory than the limit;
- ``hang``: it ran past the CPU-time or the wall-clock limit;
- ``flood``: it wrote more than the output limit (cut there, and the process killed).

The grader itself never imports student code; it only reads these outcomes.
"""

from __future__ import annotations

import contextlib
import fcntl
import functools
import hashlib
import json
import os
import resource
import shutil
import signal
import subprocess
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

from lessons.student import CORE, FLAGS, STUB_HEADER, SUPPORT

# The core's flags without -Werror: a student's warning is reported, not a failed build.
BUILD_FLAGS = [f for f in FLAGS.split() if f != "-Werror"]

NOT_IMPLEMENTED_STATUS = 86  # rt::not_implemented_status, lessons/cpp/not_implemented.h


@dataclass(frozen=True)
class Limits:
    """Limits of one child process. The defaults fit a check of one lesson: a probe runs in
    milliseconds, so 10 s of CPU is a hang; the core's scenes for a lesson are small, 512 MiB
    of address space holds them many times over; nothing a check prints needs more than
    64 KiB. The build gets its own (BUILD_LIMITS)."""

    cpu_s: int = 10
    wall_s: float = 20.0
    memory_bytes: int = 512 << 20
    file_bytes: int = 64 << 20
    output_bytes: int = 64 << 10


# The compiler: cc1plus needs about 340 MiB for the whole core (bindings.cpp, at -O1 or -O3,
# measured with /usr/bin/time -f %M), so 2 GiB leaves room for a student's larger code; two
# minutes of CPU are many times what that build takes (3 to 4.5 s of user time).
BUILD_LIMITS = Limits(cpu_s=120, wall_s=240, memory_bytes=2 << 30, output_bytes=256 << 10)


@dataclass
class Outcome:
    kind: str  # ok, failed, not_implemented, crash, memory, hang, flood
    returncode: int | None
    output: str  # stdout and stderr together, cut at the limit
    seconds: float
    message: str  # one line for the student

    @property
    def ok(self) -> bool:
        return self.kind == "ok"


def memory_available() -> int:
    """The memory this process may use: the machine's, or its container's (cgroup v2
    memory.max, v1 memory.limit_in_bytes) where that is less; $RTLAB_SANDBOX_MEMORY (bytes,
    or with a K, M or G suffix) says it instead (to try a smaller machine's limits)."""
    given = os.environ.get("RTLAB_SANDBOX_MEMORY", "").strip().upper()
    if given:
        scale = {"K": 1 << 10, "M": 1 << 20, "G": 1 << 30}.get(given[-1], 1)
        return int(float(given.rstrip("KMG")) * scale)
    sizes = [os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")]
    for path in ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"):
        with contextlib.suppress(OSError, ValueError):
            sizes.append(int(Path(path).read_text().split()[0]))  # "max" is no limit
    return min(sizes)


# The least address space a child gets whatever the machine: the compiler needs about 300 MiB
# for bindings.cpp (a build under 256 MiB runs out, under 320 MiB it passes; the render child
# passes under 256 MiB).
MEMORY_FLOOR = 384 << 20


def address_space(limits: Limits, available: int | None = None) -> int:
    """A child's address-space limit: its own, but at most half the memory available, so that
    two children at once (the probe build beside the extension build) leave the grader room. On
    Gradescope's default of 768 MB a student's runaway allocation then ends as this child's
    "memory" outcome, never as the container's OOM killer taking the grader and its results."""
    available = memory_available() if available is None else available
    return min(limits.memory_bytes, max(available // 2, MEMORY_FLOOR))


def _limit(limits: Limits, memory: int) -> None:  # runs in the child, before exec
    resource.setrlimit(resource.RLIMIT_CPU, (limits.cpu_s, limits.cpu_s + 1))
    resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    resource.setrlimit(resource.RLIMIT_FSIZE, (limits.file_bytes, limits.file_bytes))
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))


def _kill_group(process: subprocess.Popen) -> None:
    with contextlib.suppress(ProcessLookupError):
        os.killpg(process.pid, signal.SIGKILL)


MEMORY_WORDS = ("std::bad_alloc", "Cannot allocate memory", "out of memory", "virtual memory")


def run_limited(command: list[str], cwd: Path, limits: Limits, what: str) -> Outcome:
    """Run `command` in `cwd` under `limits`; `what` names it in the message ("the build")."""
    start = time.monotonic()
    memory = address_space(limits)
    # The C locale: the compiler's messages in plain ASCII quotes, the same on every machine.
    env = {**os.environ, "LC_ALL": "C", "LANG": "C"}
    process = subprocess.Popen(
        command,
        cwd=cwd,
        env=env,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        start_new_session=True,  # its own process group, killed whole on a timeout
        preexec_fn=lambda: _limit(limits, memory),
    )
    chunks: list[bytes] = []
    flooded = threading.Event()

    def read() -> None:
        total = 0
        assert process.stdout is not None
        while chunk := process.stdout.read1(65536):
            if total < limits.output_bytes:
                chunks.append(chunk[: limits.output_bytes - total])
            total += len(chunk)
            if total > limits.output_bytes and not flooded.is_set():
                flooded.set()
                _kill_group(process)

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    timed_out = False
    try:
        process.wait(timeout=limits.wall_s)
    except subprocess.TimeoutExpired:
        timed_out = True
    finally:
        # The group killed whatever ended the wait: a timeout; an interrupt (Ctrl-C, or SIGTERM
        # turned into an exception by the caller), which never reached the child, in a session
        # of its own, so that it ran on to its CPU limit after the grader had gone; or the
        # child's exit, after which what it left running in its group goes too.
        _kill_group(process)
        process.wait()
    reader.join(timeout=5)
    seconds = time.monotonic() - start
    output = b"".join(chunks).decode("utf-8", errors="replace")
    code = process.returncode
    if flooded.is_set():
        return Outcome(
            "flood",
            code,
            output,
            seconds,
            f"{what} wrote more than {limits.output_bytes // 1024} KiB of output: cut there "
            "and stopped",
        )
    if timed_out or code in (-signal.SIGXCPU, -signal.SIGKILL):
        limit = f"{limits.wall_s:g} s wall clock" if timed_out else f"{limits.cpu_s} s of CPU"
        return Outcome("hang", code, output, seconds, f"{what} did not finish within {limit}")
    if code == NOT_IMPLEMENTED_STATUS:
        first = next((ln for ln in output.splitlines() if "not implemented" in ln), "")
        return Outcome("not_implemented", code, output, seconds, f"{what}: {first.strip()}")
    if (code is not None and code < 0) or any(w in output for w in MEMORY_WORDS):
        if any(w in output for w in MEMORY_WORDS):
            return Outcome(
                "memory",
                code,
                output,
                seconds,
                f"{what} ran out of memory (the limit is {memory >> 20} MiB)",
            )
        name = signal.Signals(-code).name if code is not None else "?"
        return Outcome("crash", code, output, seconds, f"{what} crashed: {name}")
    if code != 0:
        return Outcome("failed", code, output, seconds, f"{what} failed with exit status {code}")
    return Outcome("ok", code, output, seconds, f"{what}: ok")


def first_errors(output: str, count: int = 3) -> str:
    """The compiler's first `count` errors, with the lines that follow each (the source line
    and the caret), as a student reads them."""
    lines = output.splitlines()
    picked: list[str] = []
    errors = 0
    for i, line in enumerate(lines):
        if ": error:" in line or ": fatal error:" in line:
            errors += 1
            if errors > count:
                break
            picked += lines[i : i + 3]
    return "\n".join(picked) if picked else "\n".join(lines[:10])


class SubmissionError(ValueError):
    """A submission that cannot be laid over the core (no C++ files of the core's names)."""


def _compiled(command: list[str], work: Path, limits: Limits) -> Outcome:
    """A compiler run under limits; a failure is a compile error, told by its first errors."""
    outcome = run_limited(command, work, limits, "the build")
    if outcome.kind == "failed":
        outcome.kind = "compile_error"
        outcome.message = "the build failed; the compiler's first errors:\n" + first_errors(
            outcome.output
        )
    return outcome


def overlay(submission: Path, work: Path, core: Path = CORE) -> list[str]:
    """Copy the reference core to `work` and the submission's files of the core's names over
    it; returns the names taken from the submission. Other files are ignored."""
    shutil.copytree(core, work, dirs_exist_ok=True)
    shutil.copyfile(SUPPORT, work / STUB_HEADER)
    names = {p.name for p in core.iterdir()}
    taken = []
    for base in (submission, submission / "cpp"):
        if not base.is_dir():
            continue
        for path in sorted(base.iterdir()):
            if path.is_file() and path.name in names:
                shutil.copyfile(path, work / path.name)
                taken.append(path.name)
    if not taken:
        raise SubmissionError(
            f"{submission}: no C++ file named as in tracer/cpp/ (e.g. 10_classic.h)"
        )
    return sorted(set(taken))


@dataclass
class Build:
    outcome: Outcome
    binary: Path | None
    files: list[str]


# --- a cache of builds, for the test suite ----------------------------------------------
# $RTLAB_BUILD_CACHE names a directory (tests/conftest.py gives one per test session; the
# grader's own runs set none, and build every submission): a build whose inputs are
# byte-identical to one already built there (every file the compiler is given, the command,
# the compiler, the limits) takes that binary instead of compiling again. The suite grades the
# same sources many times over (the solution's extension in every lesson's full-marks test and
# in each integration check; a known-wrong version's probe program in the grader's test, the
# lesson check and the autograder's), and each build is seconds of CPU. Only a build that
# succeeded is kept; its outcome (the compiler's warnings) is replayed with it.
BUILD_CACHE_ENV = "RTLAB_BUILD_CACHE"


def build_cache() -> Path | None:
    given = os.environ.get(BUILD_CACHE_ENV, "").strip()
    return Path(given) if given else None


@functools.cache
def _compiler_identity() -> str:
    compiler = shutil.which("c++") or "c++"
    done = subprocess.run([compiler, "--version"], capture_output=True, text=True, check=False)
    return f"{os.path.realpath(compiler)}\0{done.stdout}"


def build_key(command: list[str], inputs: list[Path], root: Path, limits: Limits) -> str:
    """The digest of what makes a build: the compiler, the command (its paths relative to the
    work directory `root`, or the same absolute ones: the venv's headers), each input file's
    name and bytes, and the limits it ran under (a build that fits 384 MiB is not one that
    fits 2 GiB)."""
    h = hashlib.sha256()
    h.update(_compiler_identity().encode() + b"\0")
    h.update(json.dumps([command, asdict(limits), address_space(limits)]).encode() + b"\0")
    for path in sorted(inputs):
        name = path.relative_to(root) if path.is_relative_to(root) else path.name
        h.update(str(name).encode() + b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()[:32]


def _inputs(work: Path, *extra: Path) -> list[Path]:
    return [p for p in (work / "cpp").rglob("*") if p.is_file()] + list(extra)


def cached_build(key: str, binary: Path, files: list[str], build: Callable[[], Build]) -> Build:
    """`build()`, or (with $RTLAB_BUILD_CACHE) the binary it made before from the same key,
    copied to `binary`, with `files` (this submission's, from its own overlay). A lock per
    key: a second process wanting the same build waits for the first one's, rather than
    compiling it beside it on the same cores."""
    cache = build_cache()
    if cache is None:
        return build()
    entry = cache / key
    entry.mkdir(parents=True, exist_ok=True)
    with open(entry / "lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        stored, meta = entry / binary.name, entry / "outcome.json"
        if meta.exists() and stored.exists():
            shutil.copy2(stored, binary)
            with open(entry / "hits", "a") as hits:  # how often it served: for the suite's log
                hits.write(f"{os.getpid()}\n")
            return Build(Outcome(**json.loads(meta.read_text())), binary, files)
        made = build()
        if made.outcome.ok and made.binary is not None:
            partial = entry / f".{binary.name}.{os.getpid()}"
            shutil.copy2(made.binary, partial)
            os.replace(partial, stored)
            (entry / "outcome.part").write_text(json.dumps(asdict(made.outcome)))
            os.replace(entry / "outcome.part", meta)  # after the binary: a hit finds both
        return made


def build_probe(
    submission: Path,
    main_source: str,
    work: Path,
    limits: Limits | None = None,
    optimisation: str = "-O1",
) -> Build:
    """Lay `submission` over the core in `work` and compile `main_source` (a C++ program that
    includes the core's headers) against it, with the core's flags, under limits. On a
    compile error the outcome's message holds the compiler's first errors."""
    limits = limits or BUILD_LIMITS
    cpp = work / "cpp"
    files = overlay(submission, cpp)
    (work / "main.cpp").write_text(main_source)
    binary = work / "probe"
    command = ["c++", *BUILD_FLAGS, optimisation, "-pthread", "-Icpp", "main.cpp", "-o", "probe"]

    def build() -> Build:
        outcome = _compiled(command, work, limits)
        return Build(outcome, binary if outcome.ok else None, files)

    if build_cache() is None:
        return build()
    key = build_key(command, _inputs(work, work / "main.cpp"), work, limits)
    return cached_build(key, binary, files, build)


def run_probe(build: Build, args: list[str], limits: Limits | None = None) -> Outcome:
    if build.binary is None:
        raise ValueError("the build failed: nothing to run")
    return run_limited(
        [str(build.binary), *args], build.binary.parent, limits or Limits(), "the check"
    )


def temporary_work() -> tempfile.TemporaryDirectory:
    return tempfile.TemporaryDirectory(prefix="rtlab-sandbox-")


# The extension, built without CMake: nanobind's library (the same for every submission,
# compiled once into NANOBIND_CACHE) and bindings.cpp with the submission laid over the core.
# Measured on this 2-core machine (/usr/bin/time, c++ 12): bindings.cpp 3.5 s at -O1 against
# 4.7 s at -O3; nanobind's library 4.3 s, paid once. -O1 is the default: a check runs small
# scenes, where the build, not the render, is the time a student waits.
NANOBIND_CACHE = CORE.parent.parent / "build" / "lessons-nanobind"


def _python_build_paths() -> tuple[Path, list[str], str]:
    import sysconfig

    import nanobind

    nb = Path(nanobind.include_dir()).parent
    includes = [
        f"-I{nb / 'include'}",
        f"-I{nb / 'ext' / 'robin_map' / 'include'}",
        f"-I{sysconfig.get_paths()['include']}",
    ]
    return nb, includes, str(sysconfig.get_config_var("EXT_SUFFIX"))


def nanobind_object(cache: Path | None = None) -> Path:
    """nanobind's library compiled once (it is the same for every submission): written to a
    temporary name and renamed, so a half-written object is never taken for a good one. Its
    place: `cache`, NANOBIND_CACHE, or with $RTLAB_BUILD_CACHE a folder there named by the
    digest of its command (an unpacked autograder's checkout then builds it no more)."""
    nb, includes, _ = _python_build_paths()
    command = [
        "c++", "-std=c++17", "-fPIC", "-O3", "-fvisibility=hidden", "-fno-strict-aliasing",
        *includes, "-c", str(nb / "src" / "nb_combined.cpp"),
    ]  # fmt: skip
    if cache is None:
        shared = build_cache()
        source = nb / "src" / "nb_combined.cpp"
        cache = (
            shared / f"nanobind-{build_key(command, [source], nb, BUILD_LIMITS)}"
            if shared is not None
            else NANOBIND_CACHE
        )
    target = cache / "nb_combined.o"
    if target.exists():
        return target
    cache.mkdir(parents=True, exist_ok=True)
    # One build at a time per cache, across processes and threads alike (an flock belongs to
    # its open file, and each caller opens its own): a grader's two build threads once both
    # compiled into the same pid-named partial file, and the second rename found it gone.
    with open(cache / "lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if target.exists():  # built by whoever held the lock before
            return target
        partial = cache / f"nb_combined.{os.getpid()}.{threading.get_ident()}.o"
        outcome = run_limited(
            [*command, "-o", str(partial)], cache, BUILD_LIMITS, "the build of nanobind"
        )
        if not outcome.ok:
            raise RuntimeError(outcome.message + "\n" + outcome.output[-2000:])
        os.replace(partial, target)
    return target


def build_extension(
    submission: Path, work: Path, limits: Limits | None = None, optimisation: str = "-O1"
) -> Build:
    """The extension tracer._core with `submission` laid over the core, built in `work` under
    limits; Build.binary is the shared library (load it only in a child process)."""
    limits = limits or BUILD_LIMITS
    files = overlay(submission, work / "cpp")
    _, includes, suffix = _python_build_paths()
    nb = nanobind_object()
    library = work / f"_core{suffix}"
    compile_ = [
        "c++", *BUILD_FLAGS, optimisation, "-fPIC", "-fvisibility=hidden", "-pthread",
        *includes, "-c", "cpp/bindings.cpp", "-o", "bindings.o",
    ]  # fmt: skip
    link = ["c++", "-shared", "-pthread", "bindings.o", str(nb), "-o", str(library)]

    def build() -> Build:
        outcome = _compiled(compile_, work, limits)
        if not outcome.ok:
            return Build(outcome, None, files)
        outcome = run_limited(link, work, limits, "the link")
        return Build(outcome, library if outcome.ok else None, files)

    if build_cache() is None:
        return build()
    # The link's output path is this work directory's: the key takes its file name, and
    # nanobind's object by its bytes.
    key = build_key([*compile_, *link[:4], nb.name, library.name], _inputs(work, nb), work, limits)
    return cached_build(key, library, files, build)


# A child process that loads a built extension as tracer._core and renders a scene file with
# the one-ray tracer (the student's code; the packet tracer restates it), printing the image's
# digest and sum, so the parent never imports student code.
RENDER_CHILD = """
import hashlib, importlib.util, sys
spec = importlib.util.spec_from_file_location("tracer._core", sys.argv[1])
core = importlib.util.module_from_spec(spec)
sys.modules["tracer._core"] = core
spec.loader.exec_module(core)
from tracer.render import render_with_stats
from tracer.scene import load_scene
result = render_with_stats(load_scene(sys.argv[2]), threads=2, progress=False, packets=False)
digest = hashlib.sha256(result.image.tobytes()).hexdigest()
print(f"image sha256 {digest} sum {float(result.image.sum(dtype='float64')):.17g}")
"""


def render_in_child(build: Build, scene: Path, limits: Limits | None = None) -> Outcome:
    import sys

    if build.binary is None:
        raise ValueError("the build failed: nothing to run")
    # A Python interpreter with numpy and Mitsuba's libraries maps far more address space
    # than it uses: 4 GiB of it, not 512 MiB, before the scene's own memory.
    limits = limits or Limits(memory_bytes=4 << 30)
    command = [sys.executable, "-c", RENDER_CHILD, str(build.binary), str(scene)]
    return run_limited(command, CORE.parent.parent, limits, "the render")
