# The two commands of the README. Each creates .venv and installs what it needs from PyPI.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test lint bench docs clean images

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
	@echo "the walks in MuJoCo physics (adaptive controller, on the state estimated from the simulated sensors)"
	@echo "are in out/fig8-sim/ and out/velocity-push-sim/ (a velocity walk: 0.2 m/s forward, turning on the spot"
	@echo "from 5 s, pushed 30 N s forward at 2.85 s); their ZMP errors are printed as median, 95th percentile and"
	@echo "RMS over the single supports, and the estimate's errors against the simulator's truth."
	@echo "out/pushes/pushes.png is the largest push Talos survives in 4 directions at mid single support"
	@echo "(a short run of benchmarks/pushes.py, bisected to 4 N s)."

# The tests run in one process per core (pytest-xdist), at most four: each holds its own robot models (some 0.5 GB).
test: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/python -m pytest -q -n auto --maxprocesses 4

lint: $(STAMP)
	$(BIN)/ruff check .

bench: $(STAMP)
	$(BIN)/python benchmarks/replan.py

# The API reference from the docstrings (pdoc, in the dev extra): out/api/index.html. rtgait.core's __all__ lists
# its public names, which hides its subpackages from pdoc's walk through the package, so they are named here.
# MUJOCO_GL=disable: importing mujoco would otherwise load an OpenGL backend, which needs no display but starts a
# subprocess that pdoc refuses while it imports modules; the reference draws nothing. The annotations that name
# types imported only for type checking cannot be resolved at run time: pdoc shows them as written, and its
# warning about each is silenced.
API := out/api
CORE_SUBPACKAGES := $(subst /,.,$(patsubst %/__init__.py,%,$(wildcard rtgait/core/*/__init__.py)))
CORE_TOP_MODULES := $(subst /,.,$(patsubst %.py,%,$(filter-out %/__init__.py,$(wildcard rtgait/core/*.py))))
docs: $(STAMP)
	rm -rf $(API)
	MUJOCO_GL=disable PYTHONWARNINGS="ignore:Error parsing type annotation" $(BIN)/python -m pdoc --docformat restructuredtext --output-directory $(API) \
		rtgait $(CORE_SUBPACKAGES) $(CORE_TOP_MODULES)
	@echo "API reference: $(API)/index.html"

clean:
	rm -rf $(VENV) out .pytest_cache .hypothesis

# docs/images/ from the current code: the README's and docs' figures, remade in a scratch folder and copied. The
# physics ones on the simulator's truth, as results.md's tables beside them (the estimate's are in estimation.md).
IMAGES := out/images
images: $(STAMP)
	$(BIN)/rtgait plan fig4 --out $(IMAGES)/fig4
	$(BIN)/rtgait plan fig8 --out $(IMAGES)/fig8
	$(BIN)/rtgait plan fig11 --robot talos --compensate-angular-momentum --out $(IMAGES)/fig11-talos
	$(BIN)/rtgait simulate fig8 --robot talos --controller adaptive --state truth --out $(IMAGES)/fig8-sim
	$(BIN)/rtgait sweep sweeps/map.toml --quiet --out $(IMAGES)/map
	$(BIN)/python benchmarks/pushes.py --robot talos --controller open-loop --controller stabilized \
		--controller adaptive --directions 8 --state truth --out $(IMAGES)/pushes
	cp $(IMAGES)/fig4/zmp_cog.png docs/images/fig4_zmp_cog.png
	cp $(IMAGES)/fig8/top_view.png docs/images/fig8_top_view.png
	cp $(IMAGES)/fig11-talos/multibody_zmp.png docs/images/fig11_multibody_zmp.png
	cp $(IMAGES)/fig8-sim/zmp_sim.png docs/images/fig8_zmp_sim.png
	cp $(IMAGES)/map/map.png docs/images/sweep_map.png
	cp $(IMAGES)/pushes/pushes.png docs/images/pushes_talos.png
