"""Shared, expensive objects of the robot tests: loaded robots and one planned-and-solved walk per robot.

Imports of Pinocchio-based modules happen inside the fixtures, so this file loads without Pinocchio and the test
modules (which call ``pytest.importorskip("pinocchio")``) are skipped cleanly.
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
def g1() -> Any:
    from rtgait.robot.model import RobotModel

    return RobotModel.load("g1")


def planned_walk(robot: Any, scenario_name: str = "fig8", **changes: Any) -> Any:
    """Roll out a built-in scenario with the robot's COG height, step width and sole (and any other changes)."""
    from rtgait.core.analysis.rollout import rollout
    from rtgait.core.planner.online import OnlinePlanner
    from rtgait.robot.motion import robot_scenario
    from rtgait.scenario.loading import load_scenario

    scenario = dataclasses.replace(robot_scenario(load_scenario(scenario_name), robot), **changes)
    planner = OnlinePlanner(scenario.planner_config(), scenario.strides())
    return rollout(planner, scenario.dt, scenario.sole, scenario.changes)


@pytest.fixture(scope="session")
def talos_fig8(talos: Any) -> Any:
    """The fig8 walk planned for Talos at the scenario's own period (5 ms)."""
    return planned_walk(talos)


@pytest.fixture(scope="session")
def talos_fig8_motion(talos: Any, talos_fig8: Any) -> Any:
    from rtgait.robot.motion import whole_body_motion

    return whole_body_motion(talos, talos_fig8)


@pytest.fixture(scope="session")
def plan_walk() -> Any:
    """:func:`planned_walk`, for tests that need a walk of their own."""
    return planned_walk
