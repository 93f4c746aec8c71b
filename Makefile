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

# Headless CPU rendering and polite threading beside other processes (see README).
export MUJOCO_GL ?= egl
export PYOPENGL_PLATFORM ?= egl
export LP_NUM_THREADS ?= 1
export OMP_WAIT_POLICY ?= PASSIVE
export TOKENIZERS_PARALLELISM ?= false

.PHONY: setup demo test test-fast bench clean

setup: $(STAMP) $(V21_STAMP)

$(STAMP): pyproject.toml constraints.txt scripts/system_libs.sh
	bash scripts/system_libs.sh
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -c constraints.txt -e ".[lerobot,train,policies,dev]"
	$(BIN)/python -m pip install -q --no-deps lerobot==0.4.4
	touch $(STAMP)

$(V21_STAMP): $(STAMP)
	test -x $(V21)/bin/python || $(PYTHON) -m venv $(V21)
	$(BIN)/python -c "import site; print(site.getsitepackages()[0])" \
		> "$$($(V21)/bin/python -c 'import site; print(site.getsitepackages()[0])')/deconfound-main-venv.pth"
	$(V21)/bin/python -m pip install -q --no-deps lerobot==0.3.3 datasets==3.6.0
	touch $(V21_STAMP)

demo: $(STAMP)
	$(BIN)/python -m gen referent=object n=20 out=datasets/object overwrite=true

test: $(STAMP) $(V21_STAMP)
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
	rm -rf $(VENV) $(V21) .pytest_cache
