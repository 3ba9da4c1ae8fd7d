# The verbs a person types. `make demo` and `make test` each do the whole set-up on a fresh
# Debian machine (as root): system packages, a virtual environment in .venv, the build.

SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
# System packages: POV-Ray is a reference renderer; libLLVM 19 runs Mitsuba's llvm_ad_rgb
# variant (Debian 12's default libLLVM 15 aborts in it); OSMesa lets pyrender rasterise offscreen;
# Chromium (/usr/bin/chromium) is the browser the tests of `rtlab report`'s pages drive with
# Playwright (whose own `playwright install` downloads a browser, which cannot work offline);
# Clang 19 (Debian 12's clang-19) builds the C++ core: on the AMD Zen 4 of this machine class its
# build ran Ex 25 1.07x, the bunny's incoherent rays 1.05x and the Cornell box 1.03x faster than
# GCC 12's build of the same source, the bunny's primary packets 0.92x
# (reference/speed-log.md), and it compiles in two thirds of the time. GCC (g++) builds the
# core a second time for tests/test_second_compiler.py (undefined behaviour that one compiler
# lets pass, the other may not), for tests/test_instruction_sets.py and for `make sanitize`;
# the students' builds (lessons/) use c++ too.
APT_PACKAGES := povray libllvm19 libosmesa6 chromium clang-19
CORE_CXX := clang++-19
CPP_SOURCES := CMakeLists.txt pyproject.toml $(wildcard tracer/cpp/*.h tracer/cpp/*.cpp)
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: setup system demo test lint format bench clean sanitize

setup: $(VENV)/.built

# apt-get only when something is missing, so a set-up machine starts at once.
system:
	@missing=""; \
	for p in $(APT_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	command -v g++ >/dev/null 2>&1 || missing="$$missing g++"; \
	command -v $(PYTHON) >/dev/null 2>&1 || missing="$$missing python3 python3-dev"; \
	$(PYTHON) -c 'import venv, ensurepip' >/dev/null 2>&1 || missing="$$missing python3-venv"; \
	if [ -n "$$missing" ]; then \
	  echo "make: installing system packages:$$missing"; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq $$missing >/dev/null || \
	  { echo "make: apt-get could not install:$$missing" >&2; exit 1; }; \
	fi; \
	for tool in povray chromium $(CORE_CXX) g++; do command -v $$tool >/dev/null 2>&1 || \
	  { echo "make: $$tool is not on PATH after installing its package; the tests need it" >&2; exit 1; }; \
	done; \
	$(PYTHON) -c 'import sys; sys.exit(sys.version_info < (3, 11))' || \
	  { echo "make: rtlab needs Python 3.11 or newer; $(PYTHON) is $$($(PYTHON) --version)" >&2; exit 1; }

$(VENV)/.installed: requirements-dev.txt | system
	@[ -x $(PY) ] || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -r requirements-dev.txt
	@# pyrender pins PyOpenGL 3.1.0, whose OSMesa binding fails; 3.1.10 works (pip warns).
	$(PY) -m pip install -q --no-deps pyopengl==3.1.10
	@touch $@

# The C++ core, built by scikit-build-core into an editable install with CORE_CXX; rebuilt when a
# source or this file (which names the compiler) changes. Its build folder is the compiler's own:
# CMake drops a cache configured for another compiler and then fails to find nanobind (whose path
# scikit-build-core gave in the dropped cache).
$(VENV)/.built: $(VENV)/.installed $(CPP_SOURCES) Makefile
	$(PY) -m pip install -q --no-build-isolation --no-deps -e . \
	  -Cbuild-dir="build/{wheel_tag}-$(CORE_CXX)" \
	  -Ccmake.define.CMAKE_CXX_COMPILER="$$(command -v $(CORE_CXX))"
	@touch $@

# The demo scene with rtlab, POV-Ray and Mitsuba; images, heat maps and a table in out/.
demo: setup
	$(VENV)/bin/rtlab demo --out-dir out

# Speed side by side (a benchmark, not a test): every suite, JSON rows in out/bench.json.
# `make bench BENCH_RUNS=5`: five runs, summarised as medians with the range of each ratio
# (these machines drift by 20% from hour to hour; the README's tables are five runs).
BENCH_RUNS ?= 1
bench: setup
	$(VENV)/bin/rtlab bench all --runs $(BENCH_RUNS) --json out/bench.json --markdown out/bench.md

lint: setup
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .

format: setup
	$(VENV)/bin/ruff format .
	$(VENV)/bin/ruff check --fix .

# Two workers or more (pytest-xdist, one per core): the grader's builds and renders leave a core
# idle between them that the other worker's tests fill; loadgroup keeps each module of
# tests/conftest.py's GROUPED on one worker (their fixtures set up once) and hands out the rest
# one test at a time.
test: setup lint
	$(PY) -m pytest -n auto --dist loadgroup

# The core built by GCC with AddressSanitizer and UndefinedBehaviorSanitizer (CMake's
# RTLAB_SANITIZE, in build/sanitize-gcc, a folder named for its compiler: a CMake cache made for
# another one is dropped, and nanobind's path with it; .venv's own build is left alone), then the
# tests that exercise the core (tests/tracer) run against it, in one process that loads it as
# tracer._core (tests/with_core.py, which tests/test_second_compiler.py uses too). The
# sanitizer's runtime must be the process's first library, hence LD_PRELOAD (dropped again for
# the processes the tests start, which run the ordinary build). libstdc++ is preloaded with it:
# the runtime wraps __cxa_throw when it starts, and a C++ exception thrown later (nanobind
# re-raising a Python error from the progress callback) would find no real function to call.
# CPython keeps memory until exit by design, so leak reports are off; any other report ends the
# run with an error, and --capture=sys lets it reach the terminal. Deselected: the demo verb,
# which runs POV-Ray and Mitsuba (their JIT and runtimes are not ours to check).
SANITIZE_DIR := build/sanitize-gcc
SANITIZE_PYTEST := -q --capture=sys -p no:cacheprovider -p no:xdist \
  --deselect tests/tracer/test_cli_and_io.py::test_check_and_demo_verbs tests/tracer

sanitize: setup
	$(VENV)/bin/cmake -S . -B $(SANITIZE_DIR) -G Ninja -DCMAKE_MAKE_PROGRAM=$(abspath $(VENV)/bin/ninja) \
	  -DCMAKE_CXX_COMPILER="$$(command -v g++)" \
	  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DRTLAB_SANITIZE=ON -DPython_EXECUTABLE=$(abspath $(PY)) \
	  -Dnanobind_DIR="$$($(PY) -m nanobind --cmake_dir)" >/dev/null
	$(VENV)/bin/cmake --build $(SANITIZE_DIR)
	LD_PRELOAD="$$(g++ -print-file-name=libasan.so) $$(g++ -print-file-name=libstdc++.so)" \
	  ASAN_OPTIONS=detect_leaks=0 \
	  UBSAN_OPTIONS=print_stacktrace=1 $(PY) -m tests.with_core $(SANITIZE_DIR)/_core.*.so sanitized \
	  $(SANITIZE_PYTEST)

clean:
	rm -rf build out $(VENV) .pytest_cache .ruff_cache
