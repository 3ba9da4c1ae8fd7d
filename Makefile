# The verbs a person types. `make demo` and `make test` each do the whole set-up on a fresh
# Debian machine (as root): system packages, a virtual environment in .venv, the build.

SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
# System packages: POV-Ray is a reference renderer; libLLVM 19 runs Mitsuba's llvm_ad_rgb
# variant (Debian 12's default libLLVM 15 aborts in it); OSMesa lets pyrender rasterise offscreen.
APT_PACKAGES := povray libllvm19 libosmesa6
CPP_SOURCES := CMakeLists.txt pyproject.toml $(wildcard tracer/cpp/*.h tracer/cpp/*.cpp)
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: setup system demo test lint format bench clean

setup: $(VENV)/.built

# apt-get only when something is missing, so a set-up machine starts at once.
system:
	@missing=""; \
	for p in $(APT_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	command -v c++ >/dev/null 2>&1 || missing="$$missing g++"; \
	command -v $(PYTHON) >/dev/null 2>&1 || missing="$$missing python3 python3-dev"; \
	$(PYTHON) -c 'import venv, ensurepip' >/dev/null 2>&1 || missing="$$missing python3-venv"; \
	if [ -n "$$missing" ]; then \
	  echo "make: installing system packages:$$missing"; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq $$missing >/dev/null || \
	  { echo "make: apt-get could not install:$$missing" >&2; exit 1; }; \
	fi; \
	$(PYTHON) -c 'import sys; sys.exit(sys.version_info < (3, 11))' || \
	  { echo "make: rtlab needs Python 3.11 or newer; $(PYTHON) is $$($(PYTHON) --version)" >&2; exit 1; }

$(VENV)/.installed: requirements-dev.txt | system
	@[ -x $(PY) ] || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -r requirements-dev.txt
	@# pyrender pins PyOpenGL 3.1.0, whose OSMesa binding fails; 3.1.10 works (pip warns).
	$(PY) -m pip install -q --no-deps pyopengl==3.1.10
	@touch $@

# The C++ core, built by scikit-build-core into an editable install; rebuilt when a source changes.
$(VENV)/.built: $(VENV)/.installed $(CPP_SOURCES)
	$(PY) -m pip install -q --no-build-isolation --no-deps -e .
	@touch $@

# The demo scene with rtlab, POV-Ray and Mitsuba; images, heat maps and a table in out/.
demo: setup
	$(VENV)/bin/rtlab demo --out-dir out

# Speed side by side (a benchmark, not a test): every suite, JSON rows in out/bench.json.
bench: setup
	$(VENV)/bin/rtlab bench all --json out/bench.json

lint: setup
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .

format: setup
	$(VENV)/bin/ruff format .
	$(VENV)/bin/ruff check --fix .

test: setup lint
	$(PY) -m pytest

clean:
	rm -rf build out $(VENV) .pytest_cache .ruff_cache
