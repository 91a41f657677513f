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
	$(BIN)/rtgait simulate fig8 --robot talos --controller adaptive --html --out out/fig8-sim
	$(BIN)/rtgait simulate fig8 --robot talos --controller adaptive --velocity 0.2,0,0 --velocity 0,0,0.2@5 \
		--push 2.85,0.1,300,0 --html --out out/velocity-push-sim
	$(BIN)/python benchmarks/pushes.py --robot talos --controller adaptive --phase single --directions 4 \
		--tolerance 4 --out out/pushes
	@echo "Figures, trajectory.csv and summary.json for each scenario are in out/<scenario>/;"
	@echo "on Talos also joints.csv, multibody_zmp.png and replay.html (open it in a browser);"
	@echo "the walks in MuJoCo physics (adaptive controller) are in out/fig8-sim/ and out/velocity-push-sim/"
	@echo "(a velocity walk that turns, pushed 30 N s forward at 2.85 s); out/pushes/pushes.png is the largest"
	@echo "push Talos survives in 4 directions at mid single support (a short run of benchmarks/pushes.py)."

test: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/python -m pytest -q

lint: $(STAMP)
	$(BIN)/ruff check .

bench: $(STAMP)
	$(BIN)/python benchmarks/replan.py

clean:
	rm -rf $(VENV) out .pytest_cache .hypothesis
