# grainscale entry points. Every target installs what it needs on a fresh Debian machine.
#   make demo    run the demo: a silo that jams coarse graining, pure CG and multi-level against
#                the resolved reference (prints the rates; writes plots, VTK files, a summary)
#   make test    build, install and run the test suite
#   make test-sanitize  the C++ tests and a reduced Python suite under AddressSanitizer and
#                UndefinedBehaviorSanitizer (a separate build in build/sanitize)
#   make bench   side-by-side benchmark against LIGGGHTS (installs it if missing)
#   make bench-dense  dense-bed benchmark against LIGGGHTS (a settled bed, 2000 timed steps)
#   make docs    build the documentation site into build/docs (open build/docs/index.html)
#   make wheel   the portable wheel (x86-64-v2, serial) into build/wheel-dist, installed into a
#                fresh virtual environment (build/wheel-venv) and smoke-tested there

SHELL := /bin/bash
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
SOURCES := $(shell find cpp python -type f \( -name '*.cpp' -o -name '*.hpp' -o -name '*.py' -o -name '*.pyi' \) 2>/dev/null) CMakeLists.txt pyproject.toml

.PHONY: all system-deps venv install demo test test-mpi test-cpp test-sanitize docs wheel bench bench-dense bench-cpp \
  lint format clean

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

# AddressSanitizer and UndefinedBehaviorSanitizer (serial, -O1 -g): the core, the C++ tests and
# the extension module in build/sanitize; the module goes into a copy of the package there, so
# the installed build is untouched. Python is not instrumented: the sanitizer runtimes are
# preloaded, and Python's own leaks are not reported. A finding fails the target.
SAN_DIR := build/sanitize
SAN_OPTIONS := ASAN_OPTIONS=abort_on_error=1:detect_leaks=1 \
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
SAN_PYTHON := env LD_PRELOAD="$$(gcc -print-file-name=libasan.so) $$(gcc -print-file-name=libubsan.so)" \
  ASAN_OPTIONS=abort_on_error=1:detect_leaks=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  PYTHONPATH=$(abspath $(SAN_DIR))/python $(PY)
# The reduced suite: tests/unit and tests/physics (every contact law, walls, insertion,
# checkpoints, hierarchies), without the hopper demo (a minute of subprocess; its mesh walls
# and outlet run in tests/physics/test_mesh_walls.py and tests/unit/test_insert.py).
SAN_TESTS := tests/unit tests/physics --ignore=tests/unit/test_hopper_demo.py

test-sanitize: install
	$(VENV)/bin/cmake -S . -B $(SAN_DIR) -G Ninja -DCMAKE_MAKE_PROGRAM=$(abspath $(VENV)/bin/ninja) \
	  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g -DNDEBUG" \
	  -DCMAKE_INTERPROCEDURAL_OPTIMIZATION=OFF -DGRAINSCALE_SANITIZE=ON -DGRAINSCALE_BUILD_TESTS=ON \
	  -DGRAINSCALE_BUILD_PYTHON=ON -DGRAINSCALE_WITH_MPI=OFF -DPython_EXECUTABLE=$(abspath $(PY)) \
	  -Dpybind11_DIR="$$($(PY) -m pybind11 --cmakedir)" >/dev/null
	$(VENV)/bin/cmake --build $(SAN_DIR) -j2
	$(SAN_OPTIONS) $(VENV)/bin/ctest --test-dir $(SAN_DIR) --output-on-failure
	rm -rf $(SAN_DIR)/python && mkdir -p $(SAN_DIR)/python
	cp -r python/grainscale $(SAN_DIR)/python/
	rm -f $(SAN_DIR)/python/grainscale/_core*.so && cp $(SAN_DIR)/_core*.so $(SAN_DIR)/python/grainscale/
	$(SAN_PYTHON) -c 'import grainscale._core as c; print(c.__file__); assert "/$(SAN_DIR)/" in c.__file__'
	$(SAN_PYTHON) -m pytest -q -p no:cacheprovider $(SAN_TESTS)

# The portable wheel: `python -m build --wheel` with GRAINSCALE_NATIVE=OFF (-march=x86-64-v2, so
# it runs on any x86-64-v2 CPU) and without MPI (WHEEL_MPI=AUTO links the MPI found here), in
# its own build directory (build/wheel/<tag>; from-source installs use build/<tag>). The check
# refuses a compile command without -march=x86-64-v2 or with -march=native, AVX or FMA
# instructions in the module and absolute paths of this machine in the wheel. The wheel is then installed with
# its run-time dependencies from PyPI into a fresh virtual environment and smoke-tested from a
# directory outside the source tree, so that the source package cannot be imported.
WHEEL_DIST := build/wheel-dist
WHEEL_BUILD := build/wheel
WHEEL_VENV := build/wheel-venv
WHEEL_MPI ?= OFF

wheel: system-deps venv
	$(PY) -m pip install --quiet build
	rm -rf $(WHEEL_DIST)
	GRAINSCALE_WITH_MPI=$(WHEEL_MPI) $(PY) -m build --wheel --outdir $(WHEEL_DIST) \
	  -C cmake.define.GRAINSCALE_NATIVE=OFF -C cmake.define.CMAKE_EXPORT_COMPILE_COMMANDS=ON \
	  -C build-dir=$(WHEEL_BUILD)/{wheel_tag}
	$(PY) tests/smoke/wheel_check.py $(WHEEL_DIST)/grainscale-*.whl \
	  --compile-commands $(WHEEL_BUILD)/*/compile_commands.json
	rm -rf $(WHEEL_VENV)
	$(PYTHON) -m venv $(WHEEL_VENV)
	$(WHEEL_VENV)/bin/python -m pip install --quiet --upgrade pip
	$(WHEEL_VENV)/bin/python -m pip install --quiet $(WHEEL_DIST)/grainscale-*.whl
	smoke=$$(mktemp -d) && cd $$smoke && \
	  $(abspath $(WHEEL_VENV))/bin/python $(abspath tests/smoke/wheel_smoke.py) --expect portable && \
	  $(abspath $(WHEEL_VENV))/bin/grainscale info && cd / && rm -rf $$smoke

bench: install
	$(PY) bench/python/settle.py

bench-dense: install
	$(PY) bench/python/dense_bed.py

bench-cpp: install
	$(VENV)/bin/cmake -S . -B build/bench -DGRAINSCALE_BUILD_BENCH=ON -DCMAKE_BUILD_TYPE=Release >/dev/null
	$(VENV)/bin/cmake --build build/bench -j2
	./build/bench/bench_pair_loop
	./build/bench/bench_neighbor_build
	./build/bench/bench_roofline

# mypy --strict over the package and tests/typing/user_script.py (settings in pyproject.toml);
# stubtest compares the stub of the C++ core with the installed extension.
lint: install
	$(VENV)/bin/ruff check python tests bench studies docs
	$(VENV)/bin/ruff format --check python tests bench studies docs
	$(VENV)/bin/mypy
	$(PY) -m mypy.stubtest --mypy-config-file pyproject.toml \
	  --allowlist tests/typing/core_stub_allowlist.txt grainscale._core
	$(VENV)/bin/clang-format --dry-run --Werror $$(find cpp bench/cpp tests/cpp -name '*.cpp' -o -name '*.hpp')

format: install
	$(VENV)/bin/ruff format python tests bench studies docs
	$(VENV)/bin/ruff check --fix python tests bench studies docs
	$(VENV)/bin/clang-format -i $$(find cpp bench/cpp tests/cpp -name '*.cpp' -o -name '*.hpp')

clean:
	rm -rf build out $(VENV) *.egg-info
