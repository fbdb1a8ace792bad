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
# Reliability fuzz (issue 5): 20,000 generated requests through the planning layer and
# 3,000 against the live node over DDS, for seeds FUZZ_SEEDS; then the flood benchmark.
# Figures: out/reliability_fuzz.json (last seed), out/reliability_flood.json.
FUZZ_SEEDS ?= 5 6 7
fuzz: $(STAMP)
	for seed in $(FUZZ_SEEDS); do \
		FUZZ_SEED=$$seed FUZZ_CASES=20000 FUZZ_DDS_CASES=3000 \
			$(PY) -m pytest -q -s test/test_reliability_fuzz.py || exit 1; \
	done
	$(PY) benchmarks/flood.py

demo: $(STAMP)
	PY=$(PY) scripts/demo.sh

clean:
	rm -rf $(VENV) build install log .pytest_cache .ruff_cache
