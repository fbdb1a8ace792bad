# The README's two commands: `make run` and `make test`. Both build .venv from pinned requirements.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

export PYTHONPATH := $(CURDIR)

.PHONY: run test lint bench fuzz demo clean

$(STAMP): requirements.txt requirements-dev.txt
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check -r requirements-dev.txt
	touch $(STAMP)

run: $(STAMP)
	$(PY) -m traj_gen_ros.generator_node --ros-args --params-file config/generator.yaml

lint: $(STAMP)
	$(PY) -m ruff check traj_gen_ros test benchmarks

test: $(STAMP) lint
	$(PY) -m pytest -q test

bench: $(STAMP)
	$(PY) benchmarks/run.py

# The lecture's examples offline and through a running node; plots in out/ (traj-gen is
# `$(PY) -m traj_gen_ros.cli` here, `traj-gen` once the package is installed).
demo: $(STAMP)
	PY=$(PY) scripts/demo.sh

clean:
	rm -rf $(VENV) build install log .pytest_cache .ruff_cache
