# The two commands of the README. Each creates .venv and installs what it needs from PyPI.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test lint bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[viz,robot,sim,sweep,dev]'
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/rtgait scenarios
	$(BIN)/rtgait plan fig4 --out out/fig4
	$(BIN)/rtgait plan fig6 --out out/fig6
	$(BIN)/rtgait plan fig7 --out out/fig7
	$(BIN)/rtgait plan fig8 --out out/fig8
	$(BIN)/rtgait plan fig11 --robot talos --compensate-angular-momentum --html --out out/fig11-talos
	$(BIN)/rtgait plan fig8 --robot talos --compensate-angular-momentum --html --out out/fig8-talos
	$(BIN)/rtgait simulate fig8 --robot talos --html --out out/fig8-sim
	@echo "Figures, trajectory.csv and summary.json for each scenario are in out/<scenario>/;"
	@echo "on Talos also joints.csv, multibody_zmp.png and replay.html (open it in a browser);"
	@echo "the walk in MuJoCo physics is in out/fig8-sim/ (sim.csv, summary.json, zmp_sim.png, replay.html)."

test: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/python -m pytest -q

lint: $(STAMP)
	$(BIN)/ruff check .

bench: $(STAMP)
	$(BIN)/python benchmarks/replan.py

clean:
	rm -rf $(VENV) out .pytest_cache .hypothesis
