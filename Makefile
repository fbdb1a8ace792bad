# The README's two commands: `make run` and `make test`. Both build .venv from pinned requirements.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

export PYTHONPATH := $(CURDIR)

.PHONY: run test lint bench fuzz demo clean

# The venv gets the pinned requirements, then this package itself, editable: its console
# scripts .venv/bin/generator and .venv/bin/traj-gen run the working copy. PEP 660 (the
# wheel is built in a temporary directory) writes no build/ or *.egg-info into the tree,
# and pip installs the scripts in .venv/bin; setup.cfg's lib/traj_gen_ros script
# directory is for colcon and `ros2 run`. setup.py and setup.cfg declare the scripts.
$(STAMP): requirements.txt requirements-dev.txt setup.py setup.cfg
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check -r requirements-dev.txt
	$(PY) -m pip install --quiet --disable-pip-version-check --no-deps --no-build-isolation \
		--use-pep517 --editable .
	touch $(STAMP)

# control_msgs (the FollowJointTrajectory action, SpeedScalingFactor) has no PyPI wheel. Where
# it is not importable and its upstream source is beside the repository, it is built once
# into .venv/control_msgs (about 3 minutes on 2 cores); where neither, the node runs
# without the action and says so.
CONTROL_MSGS_SRC ?= ../shared/control_msgs
CONTROL_MSGS := $(VENV)/.control_msgs

$(CONTROL_MSGS): $(STAMP) requirements-control-msgs.txt scripts/build_control_msgs.sh
	@if $(PY) -c 'import control_msgs.action' 2>/dev/null; then \
		echo 'control_msgs: importable'; \
	elif [ -f $(CONTROL_MSGS_SRC)/package.xml ]; then \
		scripts/build_control_msgs.sh $(VENV) $(CONTROL_MSGS_SRC) requirements-control-msgs.txt; \
	else \
		echo 'control_msgs: not installed and no source in $(CONTROL_MSGS_SRC):' \
			'the node runs without ~/follow_joint_trajectory'; \
	fi
	touch $@

run: $(STAMP) $(CONTROL_MSGS)
	$(VENV)/bin/generator --ros-args --params-file config/generator.yaml

lint: $(STAMP)
	$(PY) -m ruff check traj_gen_ros test benchmarks launch

test: $(STAMP) $(CONTROL_MSGS) lint
	$(PY) -m pytest -q test

bench: $(STAMP) $(CONTROL_MSGS)
	$(PY) benchmarks/run.py

# The lecture's examples offline and through a running node; plots in out/.
# Reliability fuzz (issue 5): 20,000 generated requests through the planning layer and
# 3,000 against the live node over DDS, for seeds FUZZ_SEEDS; then the flood benchmark.
# Figures: out/reliability_fuzz.json (last seed), out/reliability_flood.json.
FUZZ_SEEDS ?= 5 6 7
fuzz: $(STAMP)
	for seed in $(FUZZ_SEEDS); do \
		FUZZ_SEED=$$seed FUZZ_CASES=20000 FUZZ_DDS_CASES=3000 \
			$(PY) -m pytest -q -s test/node/planning/test_pipeline_fuzz.py test/dds/test_reliability_fuzz.py || exit 1; \
	done
	$(PY) benchmarks/flood.py

demo: $(STAMP)
	PY=$(PY) scripts/demo.sh

clean:
	rm -rf $(VENV) build install log .pytest_cache .ruff_cache
