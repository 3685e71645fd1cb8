# ligwf set-up and entry points. `make demo` and `make test` install whatever is missing
# (Debian packages, a .venv with ligwf, mpi4py built against the system OpenMPI), then run.
# Re-running is quick: each step checks before it installs.

SHELL := /bin/bash
VENV ?= .venv
PY := $(VENV)/bin/python
LIGWF := $(VENV)/bin/ligwf
APT_PACKAGES := liggghts openmpi-bin libopenmpi-dev python3-venv python3-dev libgl1 libegl1 libxrender1
# what only the tests need: headless Chromium opens the report page (tests/report/test_page_browser.py);
# a real Slurm (tests/slurm/local_cluster.py) and its two-node twin made of network namespaces
# (tests/slurm/two_node_cluster.py: ip from iproute2, libpmix for srun --mpi=pmix)
TEST_APT_PACKAGES := chromium slurmctld slurmd munge iproute2 libpmix-dev
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
STAMP := $(VENV)/.ligwf-installed
DEMO_OUT ?= runs/demo
PYTEST_ARGS ?=
# the fast lane: every test that needs no engine, MPI or Slurm and is not marked slow (by
# mark; tests/conftest.py marks every test using the engine or Slurm fixtures)
FAST_MARKS := not engine and not mpi and not slurm and not slow

.PHONY: demo test test-fast install system-packages test-packages clean

# The demo study: run (ranks and packing from the rank plan) + analyse + report -> $(DEMO_OUT)/report/
demo: install
	$(LIGWF) study workflows/demo.yaml --out $(DEMO_OUT)

test: install test-packages
	$(PY) -m pytest $(PYTEST_ARGS)

# a developer's loop after every edit: under 90 s on 2 cores, no engine, mpirun or Slurm
test-fast: install
	$(PY) -m pytest -m "$(FAST_MARKS)" $(PYTEST_ARGS)

install: system-packages $(STAMP)

# liggghts RECOMMENDS paraview (~280 packages): installed without recommends on purpose.
# libgl1/libegl1/libxrender1: off-screen pyvista snapshots in the report.
system-packages:
	@if ! dpkg -s $(APT_PACKAGES) >/dev/null 2>&1; then \
	  echo "installing Debian packages: $(APT_PACKAGES)"; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $(APT_PACKAGES); \
	fi

test-packages:
	@if ! dpkg -s $(TEST_APT_PACKAGES) >/dev/null 2>&1; then \
	  echo "installing Debian packages for the tests: $(TEST_APT_PACKAGES)"; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $(TEST_APT_PACKAGES); \
	fi

# mpi4py must be compiled against the system OpenMPI (the PyPI wheel brings its own MPI,
# which cannot talk to the system mpirun or to libliggghts).
$(STAMP): pyproject.toml
	@[ -x $(PY) ] || python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q --no-binary mpi4py "mpi4py>=3.1"
	$(PY) -m pip install -q -e '.[test]'
	@touch $(STAMP)

clean:
	rm -rf $(VENV) runs .pytest_cache
