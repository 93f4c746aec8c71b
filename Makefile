# Two commands: `make demo` and `make test`. Both set everything up from nothing.
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

# Headless CPU rendering and polite threading beside other processes (see README).
export MUJOCO_GL ?= egl
export PYOPENGL_PLATFORM ?= egl
export LP_NUM_THREADS ?= 1
export OMP_WAIT_POLICY ?= PASSIVE
export TOKENIZERS_PARALLELISM ?= false

.PHONY: setup demo test test-fast bench clean

setup: $(STAMP)

$(STAMP): pyproject.toml constraints.txt scripts/system_libs.sh
	bash scripts/system_libs.sh
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -c constraints.txt -e ".[lerobot,train,policies,dev]"
	$(BIN)/python -m pip install -q --no-deps lerobot==0.4.4
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/python -m gen referent=object n=20 out=datasets/object overwrite=true

test: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/python -m pytest -q

# The pure core, planning, the audit and the command lines: nothing simulated (< 3 min on 2 cores).
test-fast: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/python -m pytest -q -m fast

bench: $(STAMP)
	$(BIN)/python bench/generate.py

clean:
	rm -rf $(VENV) .pytest_cache
