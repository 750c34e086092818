# `make demo` and `make test` set up everything they need on a fresh machine.
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
DEMO_OUT ?= out/demo

.PHONY: demo test lint benchmark clean

$(BIN)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $@

demo: $(BIN)/.installed
	mkdir -p $(DEMO_OUT)
	$(BIN)/casadi-posture validate problems/*.toml
	$(BIN)/casadi-posture torques problems/holding_m45.toml | tee $(DEMO_OUT)/torques_holding_m45.txt
	$(BIN)/casadi-posture torques problems/holding_m45.toml --json > $(DEMO_OUT)/torques_holding_m45.json
	$(BIN)/casadi-posture describe problems/holding_m45.toml --json > $(DEMO_OUT)/model_holding_m45.json
	$(BIN)/casadi-posture curve problems/frontal_elbow.toml --dof elbow_flexion \
		--out $(DEMO_OUT)/frontal_elbow_fig3.png
	$(BIN)/casadi-posture curve problems/holding_m45.toml --dof shoulder_flexion \
		--out $(DEMO_OUT)/holding_m45_shoulder.png
	@echo "demo outputs in $(DEMO_OUT)/"

test: $(BIN)/.installed
	$(BIN)/python -m pytest

lint: $(BIN)/.installed
	$(BIN)/ruff check .

clean:
	rm -rf $(VENV) out .pytest_cache
