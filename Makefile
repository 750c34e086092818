# `make demo` and `make test` set up everything they need on a fresh machine.
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
DEMO_OUT ?= out/demo
# pytest workers (pytest-xdist): one per core; TEST_WORKERS=0 runs the suite in one process.
TEST_WORKERS ?= auto

.PHONY: demo test docs lint benchmark clean

# One stamp per install: the demo needs the package and pandas (the README's Python
# example makes DataFrames); the tests add pinocchio,
# pytest-xdist, hypothesis, playwright (report.html in Debian's Chromium, which .ci/run
# installs), pandas, pyarrow and dask; lint and the benchmarks add ruff.
$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(VENV)/.demo: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[pandas]'
	touch $@

$(VENV)/.test: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $@

$(VENV)/.docs: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[docs]'
	touch $@

$(VENV)/.dev: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $@

# The demo's outputs are its own: a second run overwrites them (--force).
demo: $(VENV)/.demo
	$(BIN)/casadi-posture validate problems/*.toml
	$(BIN)/casadi-posture simulate problems/holding_m45.toml --strategy active \
		--out $(DEMO_OUT)/holding_m45-active --force
	$(BIN)/casadi-posture simulate problems/holding_m45.toml --strategy passive \
		--out $(DEMO_OUT)/holding_m45-passive --force
	$(BIN)/casadi-posture simulate problems/line_plane_hysteresis.toml \
		--out $(DEMO_OUT)/line_plane_hysteresis --force
	$(BIN)/casadi-posture simulate problems/standing_wall_horizontal.toml --animate=gif \
		--out $(DEMO_OUT)/standing_wall_horizontal --force
	$(BIN)/casadi-posture compare problems/*.toml --out $(DEMO_OUT)/compare --force
	$(BIN)/casadi-posture curve problems/frontal_elbow.toml --dof elbow_flexion \
		--out $(DEMO_OUT)/frontal_elbow_fig3.png --force
	@echo "demo outputs in $(DEMO_OUT)/"

test: $(VENV)/.test
	$(BIN)/python -m pytest -n $(TEST_WORKERS)

# The documentation site (mkdocs.yml) into site/; --strict fails on a broken link, a missing
# page or a docstring the API reference cannot render.
docs: $(VENV)/.docs
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict

benchmark: $(VENV)/.dev
	$(BIN)/python benchmarks/scaling.py
	$(BIN)/python benchmarks/solvers.py
	$(BIN)/python benchmarks/simulation.py
	$(BIN)/python benchmarks/whatif.py
	$(BIN)/python benchmarks/fuzz.py --examples 600

lint: $(VENV)/.dev
	$(BIN)/ruff check .

clean:
	rm -rf $(VENV) out site .pytest_cache
