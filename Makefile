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
	$(BIN)/casadi-posture simulate problems/holding_m45.toml --strategy active \
		--out $(DEMO_OUT)/holding_m45-active
	$(BIN)/casadi-posture simulate problems/holding_m45.toml --strategy passive \
		--out $(DEMO_OUT)/holding_m45-passive
	$(BIN)/casadi-posture simulate problems/line_plane_hysteresis.toml \
		--out $(DEMO_OUT)/line_plane_hysteresis
	$(BIN)/casadi-posture compare problems/*.toml --out $(DEMO_OUT)
	$(BIN)/casadi-posture curve problems/frontal_elbow.toml --dof elbow_flexion \
		--out $(DEMO_OUT)/frontal_elbow_fig3.png
	@echo "demo outputs in $(DEMO_OUT)/"

test: $(BIN)/.installed
	$(BIN)/python -m pytest

benchmark: $(BIN)/.installed
	$(BIN)/python benchmarks/solvers.py
	$(BIN)/python benchmarks/simulation.py
	$(BIN)/python benchmarks/whatif.py
	$(BIN)/python benchmarks/fuzz.py --examples 600

lint: $(BIN)/.installed
	$(BIN)/ruff check .

clean:
	rm -rf $(VENV) out .pytest_cache
