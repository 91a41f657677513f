"""The built-in robots' ``[velocity]`` limits: a walk by command at each limit is one the robot can step.

The truth is the robot's own model: the whole-body IK (every joint within its URDF range; it raises
:class:`~rtgait.robot.motion.UnreachableError` when it cannot follow the plan) and the distance between the left and
right legs' collision meshes of the URDF (feet included), computed by Pinocchio's collision library along the
planned walk. Every command the planner accepts at the paper's three timings, once clamped, is within that reach;
and the limits are within the envelope the robots walked in MuJoCo, on the simulator's truth and on the estimate
(``docs/velocity_envelope.json``, ``docs/velocity_envelope_estimated.json``, recorded by ``benchmarks/sim.py
--envelope``). Then: the robot's walks carry the limits into the planner, and a bad
``[velocity]`` table is refused in one line naming the key.
"""

from __future__ import annotations

import itertools
import json
import math
import warnings
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

from rtgait.core.analysis.rollout import rollout  # noqa: E402
from rtgait.core.geometry.footsteps import stride_between  # noqa: E402
from rtgait.core.planner.config import VelocityLimits  # noqa: E402
from rtgait.core.planner.online import CommandClampedWarning, OnlinePlanner  # noqa: E402
from rtgait.robot.description import RobotError, load_robot  # noqa: E402
from rtgait.robot.model import RobotModel  # noqa: E402
from rtgait.robot.motion import robot_scenario, whole_body_motion  # noqa: E402
from rtgait.scenario.loading import load_scenario  # noqa: E402

LEG_CLEARANCE = 0.005  # m: the legs' meshes at least this far apart along the walk
STEPS = 6
TALOS_LEGS = VelocityLimits(max_step_length=0.29, max_step_lateral=0.25, max_step_turn=0.6, min_step_width=0.15)
"""What Talos's legs allow: its description's ``[velocity]`` table."""


_GEOMETRY: dict[str, tuple] = {}


def leg_geometry(robot: RobotModel):
    """The URDF's collision meshes of ``robot`` with every left-leg/right-leg pair, and their data (built once)."""
    if robot.name in _GEOMETRY:
        return _GEOMETRY[robot.name]
    description = robot.description
    geometry = pin.buildGeomFromUrdf(
        robot.full_model, str(description.urdf), pin.GeometryType.COLLISION,
        package_dirs=[str(p) for p in description.package_dirs],
    )  # fmt: skip
    full = robot.full_model
    # A leg's bodies are those on the chain from the root to its sole frame.
    chains = {side: set(full.supports[full.frames[frame].parentJoint]) - {0, 1}
              for side, frame in (("left", robot.full_left_sole_id), ("right", robot.full_right_sole_id))}  # fmt: skip
    side_of = {}
    for index, obj in enumerate(geometry.geometryObjects):
        for side, joints in chains.items():
            if obj.parentJoint in joints:
                side_of[index] = side
    for a in (i for i, s in side_of.items() if s == "left"):
        for b in (i for i, s in side_of.items() if s == "right"):
            geometry.addCollisionPair(pin.CollisionPair(a, b))
    assert len(geometry.collisionPairs) >= 9, "both legs have collision meshes"
    _GEOMETRY[robot.name] = geometry, geometry.createData()
    return _GEOMETRY[robot.name]


def leg_gap(robot: RobotModel, q: np.ndarray) -> float:
    """Least distance between a left-leg and a right-leg collision mesh of the URDF over configurations ``q`` of the
    reduced model (m)."""
    geometry, geometry_data = leg_geometry(robot)
    full = robot.full_model
    data = full.createData()
    gap = np.inf
    for row in q:
        pin.computeDistances(full, data, geometry, geometry_data, robot.full_configuration(row))
        gap = min(gap, min(result.min_distance for result in geometry_data.distanceResults))
    return gap


def walk_at(robot: RobotModel, vx: float, vy: float, wz: float, timing: str = "fig8", clamp: bool = False):
    """The walk of ``robot`` by this command at the timing of scenario ``timing`` (its step period and the robot's
    limits there), no clamping allowed unless ``clamp``."""
    walk = robot_scenario(load_scenario(timing), robot)
    planner = OnlinePlanner(walk.planner_config(), None)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore" if clamp else "error", CommandClampedWarning)
        planner.set_velocity(vx, vy, wz)
    plan = rollout(planner, walk.dt, walk.sole, duration=walk.timing.start + STEPS * walk.timing.step_period)
    return planner, plan


@pytest.mark.parametrize("name", ["talos", "g1"])
@pytest.mark.parametrize("motion", ["sideways", "turning"])
def test_a_walk_at_the_limit_is_reachable_without_the_legs_meeting(name, motion, request):
    robot = request.getfixturevalue(name)  # the session's loaded robot
    if name == "talos":
        assert robot.description.velocity == TALOS_LEGS
    limits = robot.description.velocity
    period = load_scenario("fig8").timing.step_period
    if motion == "sideways":
        command = (0.0, limits.max_step_lateral / (2.0 * period), 0.0)
    else:
        command = (0.0, 0.0, limits.max_step_turn / (2.0 * period))
    planner, plan = walk_at(robot, *command)
    # The walk really is at the limit: the widest stance against the narrowest, or the largest turn between the feet.
    strides = [stride_between(a, b) for a, b in itertools.pairwise(planner.footprints(STEPS)[1:])]
    if motion == "sideways":
        widths = [s.width for s in strides]
        assert max(widths) - min(widths) == pytest.approx(limits.max_step_lateral, abs=1e-9)
        assert min(widths) == pytest.approx(limits.min_step_width, abs=1e-9)
    else:
        assert max(abs(s.turn) for s in strides) == pytest.approx(0.5 * limits.max_step_turn, abs=1e-9)
    motion_q = whole_body_motion(robot, plan).q  # raises UnreachableError if the IK cannot follow it
    assert leg_gap(robot, motion_q[::25]) >= LEG_CLEARANCE  # every 0.125 s


COMMANDS = {
    "forward": (1.0, 0.0, 0.0),
    "backward": (-1.0, 0.0, 0.0),
    "left": (0.0, 0.5, 0.0),
    "right": (0.0, -0.5, 0.0),
    "the issue's diagonal": (0.2, 0.08, 0.0),
    "backward-right": (-0.5, -0.5, 0.0),
    "left turning": (0.0, 0.3, 1.0),
}
"""Commands (m/s, m/s, rad/s) beyond or near the limits at every paper timing, one per direction of the sweep."""


@pytest.mark.parametrize("name", ["talos", "g1"])
@pytest.mark.parametrize("timing", ["fig6", "fig7", "fig8"])
def test_every_command_the_planner_accepts_is_within_the_robot_s_reach(name, timing, request):
    """Clamped onto the limits of the timing's sway, each command's walk is one the IK follows (at fig7's timing
    G1 used to be refused 0.2 m/s forward and 0.08 m/s sideways as out of reach: cut per axis, it asked both limits
    at once)."""
    robot = request.getfixturevalue(name)
    for command in COMMANDS.values():
        _, plan = walk_at(robot, *command, timing=timing, clamp=True)
        whole_body_motion(robot, plan)  # raises UnreachableError if the IK cannot follow it


DOCS = Path(__file__).resolve().parents[2] / "docs"
ENVELOPES = {"truth": DOCS / "velocity_envelope.json", "estimated": DOCS / "velocity_envelope_estimated.json"}
"""The recorded sweeps, on the simulator's truth and on the estimator's state (``benchmarks/sim.py --envelope
--state S --record FILE``)."""


@pytest.mark.parametrize("state", ["truth", "estimated"])
@pytest.mark.parametrize("name", ["talos", "g1"])
def test_the_limits_are_within_the_walked_envelope(name, state, request):
    """Along every direction of the recorded sweep, at each paper timing, the command on the robot's clamp (the
    limits of that timing's sway) asks no more than the largest one the robot walked in MuJoCo, on the truth and on
    the estimate: raise a limit, or let a case of a record fail, and this fails until the envelope is walked again."""
    robot = request.getfixturevalue(name)
    record = json.loads(ENVELOPES[state].read_text(encoding="utf-8"))
    assert record["state"] == state and not record["quick"]
    entries = [entry for entry in record["summary"] if entry["robot"] == name]
    assert {entry["timing"] for entry in entries} == {"fig6", "fig7", "fig8"}
    assert len(entries) == 3 * 11  # every direction of the full grid
    for entry in entries:
        config = robot_scenario(load_scenario(entry["timing"]), robot).planner_config()
        limits = (config.max_step_length, config.max_step_lateral, config.max_step_turn)
        assert math.isclose(math.hypot(*entry["unit"]), 1.0), entry
        for unit, limit, walked in zip(entry["unit"], limits, entry["stride"], strict=True):
            assert abs(unit) * limit <= abs(walked) + 1e-9, (entry["timing"], entry["direction"], entry["failed"])


def test_the_robot_s_walks_carry_its_limits(g1):
    config = robot_scenario(load_scenario("fig8"), g1).planner_config()
    velocity = g1.description.velocity
    assert (config.max_step_length, config.max_step_lateral, config.max_step_turn, config.min_step_width) == (
        velocity.max_step_length, velocity.max_step_lateral, velocity.max_step_turn, velocity.min_step_width
    )  # fmt: skip
    assert config.min_step_width <= config.step_width == g1.step_width


G1_TEXT = resources.files("rtgait").joinpath("robots", "g1.toml").read_text(encoding="utf-8")


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [("max_step_turn = 1.0", "max_step_turn = 2.0", r"^velocity\.max_step_turn must be within \(0, pi/2\) rad"),
     ("max_step_lateral = 0.18", "max_step_lateral = 0", r"^velocity\.max_step_lateral must be within"),
     ("min_step_width = 0.15", "min_step_width = 0.05", r"^velocity\.min_step_width \(0\.05 m\) must be at least 2"),
     ("min_step_width = 0.15", "min_width = 0.15", r"^unknown key velocity\.min_width"),
     ("max_step_length = 0.25", 'max_step_length = "long"', r"^velocity\.max_step_length must be a number")],
)  # fmt: skip
def test_a_bad_velocity_table_is_refused_naming_the_key(tmp_path, old, new, message):
    table = G1_TEXT[G1_TEXT.index("[velocity]") :]
    assert old in table
    path = tmp_path / "robot.toml"
    path.write_text(G1_TEXT.replace(table, table.replace(old, new, 1)), encoding="utf-8")
    with pytest.raises(RobotError, match=message):
        load_robot(path)


def test_a_min_step_width_wider_than_the_stance_is_refused_naming_the_key(tmp_path):
    path = tmp_path / "robot.toml"
    path.write_text(G1_TEXT.replace("min_step_width = 0.15", "min_step_width = 0.25"), encoding="utf-8")
    wide = RobotModel.load(path)  # G1 stands with its feet 0.237 m apart
    with pytest.raises(RobotError, match=r"^velocity\.min_step_width \(0\.25 m\) must be at most the stance"):
        robot_scenario(load_scenario("fig8"), wide)
