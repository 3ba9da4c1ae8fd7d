"""Run pytest against another build of the core, loaded as tracer._core before anything imports
tracer: `make sanitize`'s AddressSanitizer build, tests/test_second_compiler.py's build by the
compiler the .venv build was not made with (GCC or Clang), tests/test_instruction_sets.py's builds
for AVX2 and for SSE2.

    python -m tests.with_core CORE.so {sanitized,clang,gcc,avx2,sse2} [pytest arguments]

The second argument names the build expected, and a core that is not it stops the run: a test of
the wrong build would pass for the wrong reason. LD_PRELOAD (the sanitizer's runtime, which must
be this process's first library) is dropped for the processes the tests start: they run the
ordinary .venv build."""

import os
import sys

from reference.core_build import load_core

EXPECTED = {
    "sanitized": lambda core: core.sanitized,
    "clang": lambda core: core.compiler_family == "clang",
    "gcc": lambda core: core.compiler_family == "gcc",
    # tests/test_instruction_sets.py's builds: packets of 4 lanes (AVX2), of 2 (SSE2 alone).
    "avx2": lambda core: core.rays_per_packet == 4,
    "sse2": lambda core: core.rays_per_packet == 2,
}


def main(argv: list[str]) -> int:
    if len(argv) < 2 or argv[1] not in EXPECTED:
        raise SystemExit(f"usage: python -m tests.with_core CORE.so {{{','.join(EXPECTED)}}} ...")
    path, expected, *pytest_args = argv
    os.environ.pop("LD_PRELOAD", None)
    core = load_core(path)
    if not EXPECTED[expected](core):
        raise SystemExit(
            f"{path}: not the {expected} build (compiler {core.compiler}, "
            f"{core.rays_per_packet} rays a packet)"
        )
    import pytest

    return int(pytest.main(pytest_args))


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
