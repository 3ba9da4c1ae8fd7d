"""The C++ core built outside `make`: by CMake and ninja from the .venv into a folder of build/
(ninja rebuilds only what changed since the last run there), with a chosen compiler, CMake
options and source tree. One builder for every such build: tests/core_builds.py's second
compiler and instruction sets, reference/packet_model.py's core with symbols, and
reference/build_ab.py's variants timed against each other.

A CMake cache made for one compiler cannot be reused for another, so each compiler needs its
own folder; the callers name them so."""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[1]
VENV_BIN = Path(sys.executable).parent


class BuildError(RuntimeError):
    """The core did not configure or build; the message carries the tools' own output."""


def make_cxx() -> str:
    """The compiler `make` builds the core with: the Makefile's CORE_CXX (clang++-19), read
    from it so that the builds here follow it if it changes."""
    for line in (ROOT / "Makefile").read_text().splitlines():
        name, _, value = line.partition(":=")
        if name.strip() == "CORE_CXX" and value.strip():
            return value.strip()
    raise BuildError(f"{ROOT / 'Makefile'} names no CORE_CXX")


@dataclass(frozen=True)
class CoreBuild:
    so: Path  # the extension module, _core.<tag>.so
    warnings: tuple[str, ...]  # the compiler's warnings about rtlab's own sources


def build_core(
    build: Path, *options: str, source: Path = ROOT, build_type: str = "Release"
) -> CoreBuild:
    """Configure `source` (a tree with rtlab's CMakeLists.txt) into `build` with extra CMake
    `options` (-D...) and build the core. Release is what `make` builds (scikit-build-core's
    default); the CMakeLists' own -O3 comes after any build type's flags, so RelWithDebInfo
    gives the same code with symbols and line tables. Raises BuildError with the output of the
    step that failed. The warnings returned are those of the core's sources: nanobind's own
    are not ours, and ninja names each file it compiles."""
    nanobind = subprocess.run(
        [sys.executable, "-m", "nanobind", "--cmake_dir"], capture_output=True, text=True
    )
    if nanobind.returncode != 0:
        raise BuildError(f"nanobind is not installed in {sys.prefix}:\n{nanobind.stderr[-2000:]}")
    configure = [
        str(VENV_BIN / "cmake"), "-S", str(source), "-B", str(build), "-G", "Ninja",
        f"-DCMAKE_MAKE_PROGRAM={VENV_BIN / 'ninja'}", f"-DCMAKE_BUILD_TYPE={build_type}",
        f"-DPython_EXECUTABLE={sys.executable}", f"-Dnanobind_DIR={nanobind.stdout.strip()}",
        *options,
    ]  # fmt: skip
    compile_ = [str(VENV_BIN / "cmake"), "--build", str(build)]
    output = ""
    for step, command in (("configure", configure), ("build", compile_)):
        done = subprocess.run(command, capture_output=True, text=True)
        if done.returncode != 0:
            raise BuildError(
                f"cmake could not {step} the core in {build}:\n"
                f"{done.stdout[-4000:]}{done.stderr[-4000:]}"
            )
        output = done.stdout
    built = sorted(build.glob("_core.*.so"))
    if len(built) != 1:
        raise BuildError(f"the build in {build} made {len(built)} _core.*.so files, not one")
    return CoreBuild(built[0], source_warnings(output))


# Not a warning about rtlab: Clang 19's -march=native on the Xeon of this machine class, whose
# hypervisor shows AVX10.1-256 beside AVX-512, says once a compiled file that it takes
# AVX10.1-512 instead (the same instructions the build uses anyway).
MACHINE_WARNINGS = ("[-Winvalid-feature-combination]",)


def source_warnings(output: str) -> tuple[str, ...]:
    """The compiler's warnings in a build's output that concern rtlab's own sources and options:
    not nanobind's (its sources are not ours), nor MACHINE_WARNINGS (about the machine's CPU)."""
    return tuple(
        line
        for line in output.splitlines()
        if "warning:" in line
        and "nanobind" not in line
        and not any(tag in line for tag in MACHINE_WARNINGS)
    )


def load_core(so: str | os.PathLike[str]) -> ModuleType:
    """Load the extension at `so` as tracer._core, before anything imports tracer (which then
    renders with it): how another build of the core is run (tests/with_core.py, build_ab's
    workers, packet_model's traced process). Raises ImportError where `so` is no extension."""
    spec = importlib.util.spec_from_file_location("tracer._core", so)
    if spec is None or spec.loader is None:
        raise ImportError(f"{so}: not a Python extension")
    core = importlib.util.module_from_spec(spec)
    sys.modules["tracer._core"] = core
    spec.loader.exec_module(core)
    return core
