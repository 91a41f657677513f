"""Shared, expensive objects of the physics tests: the Talos model in Pinocchio and in MuJoCo, and short walks.

Imports of MuJoCo- and Pinocchio-based modules happen inside the fixtures, so this file loads without them and the
test modules (which call ``pytest.importorskip``) are skipped cleanly.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import pytest


@pytest.fixture(scope="session")
def talos() -> Any:
    from rtgait.robot.model import RobotModel

    return RobotModel.load("talos")


@pytest.fixture(scope="session")
def talos_sim(talos: Any) -> Any:
    """Talos in MuJoCo without the visual meshes (builds in a few hundredths of a second; same physics)."""
    from rtgait.sim.model import SimConfig, build_sim_model

    return build_sim_model(talos, SimConfig(meshes=False))


def short_scenario(name: str, steps: int, changes: tuple = ()) -> Any:
    """A built-in scenario cut to ``steps`` steps (with ``changes`` instead of its own) and a 1 s settle."""
    from rtgait.scenario.loading import load_scenario

    scenario = load_scenario(name)
    timing = dataclasses.replace(scenario.timing, settle=1.0)
    return dataclasses.replace(scenario, steps=steps, changes=changes, timing=timing)


@pytest.fixture(scope="session")
def shorten() -> Any:
    """:func:`short_scenario`, for tests that need a walk of their own."""
    return short_scenario


@pytest.fixture(scope="session")
def short_walk(talos: Any, talos_sim: Any) -> Any:
    """fig8's timing (quasi-real-time, T_s 0.7 s, T_dbl 0.1 s) for 3 steps of 0.05 m, then a 0.15 m one, the
    controller on the simulator's truth: its users check the simulation's mechanics and measures against MuJoCo's
    state, not the estimator (the CI walks and ``test_sim_estimation`` walk on the estimate). Sole levelling is off:
    its users pin this walk's landings (two late, three re-anchored swings), which the levelling moves."""
    from rtgait.control.settings import ControllerOptions
    from rtgait.core.analysis.rollout import ScheduledChange
    from rtgait.io.sim_run import simulate
    from rtgait.sim.loop_options import LoopOptions

    scenario = short_scenario("fig8", 4, (ScheduledChange(4, length=0.15),))
    options = ControllerOptions(sole_level=0.0)
    return scenario, simulate(
        scenario, talos, sim=talos_sim, options=LoopOptions(state="truth"), controller_options=options
    )
