# grainscale entry points. Every target installs what it needs on a fresh Debian machine.
#   make demo    run the demo: a silo that jams coarse graining, pure CG and multi-level against
#                the resolved reference (prints the rates; writes plots, VTK files, a summary)
#   make test    build, install and run the test suite
#   make bench   side-by-side benchmark against LIGGGHTS (installs it if missing)
#   make docs    build the documentation site into build/docs (open build/docs/index.html)

SHELL := /bin/bash
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
SOURCES := $(shell find cpp python -type f \( -name '*.cpp' -o -name '*.hpp' -o -name '*.py' \) 2>/dev/null) CMakeLists.txt pyproject.toml

.PHONY: all system-deps venv install demo test test-mpi test-cpp docs bench bench-cpp lint format clean

# mpirun for the MPI tests and benchmarks: allowed as root (CI runs as root).
MPIRUN := env OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 mpirun

all: install

# Debian packages: Eigen 3 and Open MPI (headers, runtime, mpirun).
system-deps:
	@if [ ! -f /usr/include/eigen3/Eigen/Core ] || ! command -v mpirun >/dev/null; then \
	  echo "Installing Debian packages (libeigen3-dev libopenmpi-dev openmpi-bin)"; \
	  $(SUDO) apt-get update && \
	  $(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get install -y libeigen3-dev libopenmpi-dev openmpi-bin; \
	fi

$(VENV)/bin/python:
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip

venv: $(VENV)/bin/python

$(VENV)/.installed: $(SOURCES) | system-deps $(VENV)/bin/python
	$(PY) -m pip install --quiet scikit-build-core pybind11 cmake ninja
	$(PY) -m pip install --quiet --no-build-isolation ".[test,dev,docs]"
	@touch $@

install: system-deps $(VENV)/.installed

demo: install
	$(VENV)/bin/grainscale demo --output out/demo

# Lint, the C++ unit tests (serial build), the documentation site (warnings are errors), the
# Python suite (unit, physics validation, demo, the docs' code blocks and docstring examples),
# then the MPI tests on 2 ranks and on 3 (more ranks than cores).
test: install lint test-cpp docs
	$(PY) -m pytest -q tests
	$(MAKE) --no-print-directory test-mpi

# The documentation site: Sphinx (MyST Markdown pages, API reference from the docstrings) into
# build/docs; warnings are errors and every internal reference and link is checked (-n).
docs: install
	rm -rf build/docs
	$(PY) -m sphinx -W --keep-going -n -q -b html docs build/docs
	@echo "documentation: build/docs/index.html"

# Every rank runs the same tests (tests/mpi); a hang would be killed by the timeout.
test-mpi: install
	timeout 900 $(MPIRUN) -np 2 $(PY) -m pytest -q -p no:cacheprovider --color=no tests/mpi
	timeout 900 $(MPIRUN) -np 3 --oversubscribe $(PY) -m pytest -q -p no:cacheprovider --color=no tests/mpi

test-cpp: install
	$(VENV)/bin/cmake -S . -B build/cpp-tests -DGRAINSCALE_BUILD_TESTS=ON -DGRAINSCALE_WITH_MPI=OFF -DCMAKE_BUILD_TYPE=Release >/dev/null
	$(VENV)/bin/cmake --build build/cpp-tests -j2
	$(VENV)/bin/ctest --test-dir build/cpp-tests --output-on-failure

bench: install
	$(PY) bench/python/settle.py

bench-cpp: install
	$(VENV)/bin/cmake -S . -B build/bench -DGRAINSCALE_BUILD_BENCH=ON -DCMAKE_BUILD_TYPE=Release >/dev/null
	$(VENV)/bin/cmake --build build/bench -j2
	./build/bench/bench_pair_loop
	./build/bench/bench_neighbor_build

lint: install
	$(VENV)/bin/ruff check python tests bench studies docs
	$(VENV)/bin/ruff format --check python tests bench studies docs
	$(VENV)/bin/clang-format --dry-run --Werror $$(find cpp bench/cpp tests/cpp -name '*.cpp' -o -name '*.hpp')

format: install
	$(VENV)/bin/ruff format python tests bench studies docs
	$(VENV)/bin/ruff check --fix python tests bench studies docs
	$(VENV)/bin/clang-format -i $$(find cpp bench/cpp tests/cpp -name '*.cpp' -o -name '*.hpp')

clean:
	rm -rf build out $(VENV) *.egg-info
