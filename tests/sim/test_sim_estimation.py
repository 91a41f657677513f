"""The kinematic-inertial estimator on the simulated robot's sensors against the simulator's truth, on a short walk
the ground-truth estimator drives (the estimate in the shadow, so both see the same walk), and the closed loop
walking on the estimate.

Bounds: the goals for an estimator (COM relative to the stance sole 5 mm RMS, COM velocity 0.02 m/s RMS,
DCM 10 mm RMS, the feet's contact states right in 99 % of ticks, landings seen within 10 ms), with the feet's
force sensors (Talos). A robot without them (G1) estimates its feet's wrenches from the joint torques and the legs'
dynamics, low-passed against the torques' noise, with a landing threshold above the estimate's error on a swinging
leg (``docs/estimation.md``): it meets the goals but for the contact states, which disagree for a few ticks at each
landing where the foot touches, bounces and comes down again within tens of milliseconds.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")

from rtgait.estimation.ground_truth import GroundTruthEstimator
from rtgait.estimation.kinematic_inertial import KinematicInertialEstimator
from rtgait.io.sim_run import _controller, robot_and_scenario_options
from rtgait.robot.motion import robot_scenario
from rtgait.sim.config import SensorSettings, SimConfig
from rtgait.sim.loop import ClosedLoop, LoopOptions
from rtgait.sim.model import build_sim_model
from rtgait.sim.robot import SimRobot
from rtgait.stack.estimators import kinematic_inertial_estimator
from rtgait.stack.setup import start_pose, walking_stack
from rtgait.stack.walking_stack import WalkingStack


@pytest.fixture(scope="module")
def g1():
    from rtgait.robot.model import RobotModel

    return RobotModel.load("g1")


@pytest.fixture(scope="module")
def scenario(shorten):
    """fig8's timing for 3 steps of 5 cm, then a 15 cm one."""
    from rtgait.core.analysis.rollout import ScheduledChange

    return shorten("fig8", 4, (ScheduledChange(4, length=0.15),))


def _loop(robot, scenario, noise: float, state: str = "truth"):
    """The walk ``scenario`` of ``robot`` with sensors at ``noise`` times their description's, its controller the
    adaptive level."""
    sim = build_sim_model(robot, SimConfig(meshes=False, sensors=SensorSettings(noise=noise)))
    walk = robot_scenario(scenario, robot)
    options = robot_and_scenario_options(robot, scenario)
    level, changes, stop_after = _controller(walk, None, "adaptive", sim, options)
    return ClosedLoop(sim, level, LoopOptions(changes=changes, stop_after_steps=stop_after, state=state))


def _shadow(robot, scenario, noise: float):
    """Each tick of the walk: the estimate from the sensors and the ground-truth estimator's state of that instant."""
    loop = _loop(robot, scenario, noise)
    _, left, right = start_pose(loop.planner)
    estimator = kinematic_inertial_estimator(robot, loop.planner.w, start_feet=(tuple(left), tuple(right)))
    truth = GroundTruthEstimator(loop.planner.w, robot.mass * 9.81)
    pairs = []
    while loop.step() and not loop.done:
        if loop.k < loop.k0:
            continue
        t = loop.time_of(loop.k)
        readings = loop.robot.read()
        readings = readings._replace(t=readings.t - (loop.data.time - t))
        pairs.append((estimator.update(readings), truth.update(None, loop.robot.ground_truth(t))))
    assert not loop.fell
    return pairs


def _rms(errors) -> float:
    return float(np.sqrt(np.mean(np.sum(np.square(errors), axis=1))))


WITHIN = 0.010 + 1e-9  # s: landings seen within 10 ms (the tick times' round-off aside)
RELANDING_AIR_TIME = 0.2  # s in the air below which a true landing is a re-landing after a bounce, not a step's


def _errors(pairs):
    """RMS errors of the COM relative to the more loaded sole (m), COM velocity (m/s), DCM (m); the share of ticks
    whose contact states agree; each true step landing's delay until the estimate's of the same foot (s), a foot in
    the air for at least ``RELANDING_AIR_TIME`` before it (a re-landing after a bounce may be seen as part of the
    step's landing)."""
    relative, velocity, dcm = [], [], []
    for m, g in pairs:
        i = 0 if g.left.normal_force >= g.right.normal_force else 1
        estimated, true = (m.left, m.right)[i], (g.left, g.right)[i]
        relative.append(np.subtract(m.com, estimated.pose[:3]) - np.subtract(g.com, true.pose[:3]))
        velocity.append(np.subtract(m.com_vel, g.com_vel))
        dcm.append(np.subtract(m.dcm, g.dcm))
    agree = np.mean([m.left.loaded == g.left.loaded and m.right.loaded == g.right.loaded for m, g in pairs])
    seen = [(landing.t, landing.side) for m, _ in pairs for landing in m.landings]
    delays, last_loaded = [], {"left": -math.inf, "right": -math.inf}
    for _, g in pairs:
        for g_landing in g.landings:
            if g_landing.t - last_loaded[g_landing.side] >= RELANDING_AIR_TIME:
                after = [t - g_landing.t for t, side in seen if side == g_landing.side]
                near = [d for d in after if -0.05 < d < 0.2]
                delays.append(min(near, key=abs) if near else math.inf)
        for side, foot in (("left", g.left), ("right", g.right)):
            if foot.loaded and not any(landing.side == side for landing in g.landings):
                last_loaded[side] = g.t
    return _rms(relative), _rms(velocity), _rms(dcm), float(agree), delays


@pytest.fixture(scope="module")
def talos_pairs(talos, scenario):
    return _shadow(talos, scenario, 0.0)


def test_talos_estimate_from_its_sensors_meets_the_goals(talos_pairs):
    relative, velocity, dcm, agree, delays = _errors(talos_pairs)
    assert relative < 0.005
    assert velocity < 0.02
    assert dcm < 0.010
    assert agree >= 0.99
    assert len(delays) >= 4 and max(abs(d) for d in delays) <= WITHIN


def test_talos_estimate_with_the_sensors_noise(talos, scenario):
    relative, velocity, dcm, agree, delays = _errors(_shadow(talos, scenario, 1.0))
    assert relative < 0.005 and velocity < 0.02 and dcm < 0.010
    assert len(delays) >= 4 and max(abs(d) for d in delays) <= WITHIN
    # The goal, at the sensors' noise too: the foot's inertia taken out of the ankle sensors' force and
    # their zeros learnt in the air (docs/estimation.md).
    assert agree >= 0.99


@pytest.mark.parametrize("noise", [0.0, 1.0])
def test_g1_estimate_from_joint_torques(g1, scenario, noise):
    relative, velocity, dcm, agree, delays = _errors(_shadow(g1, scenario, noise))
    assert relative < 0.005 and velocity < 0.02 and dcm < 0.010
    assert len(delays) >= 4 and all(abs(d) <= WITHIN for d in delays)
    # The contact states disagree for a few ticks at each landing, where the foot touches, bounces and comes down
    # again faster than the low-passed torque estimate follows (docs/estimation.md).
    assert agree >= 0.95


@pytest.mark.parametrize("name", ["talos", "g1"])
def test_the_closed_loop_walks_on_the_estimate_and_reports_its_errors(request, monkeypatch, scenario, name):
    robot = request.getfixturevalue(name)
    # Each tick, the estimate the controller acts on and the ground-truth estimator's state of the same instant,
    # tick by tick, to check the errors the run reports from its log at the end.
    pairs: list = []
    estimates: list = []
    shadow: list = []  # the ground-truth estimator, made with the planner's omega once the loop is
    stack_estimate, read_truth = WalkingStack.estimate, SimRobot.ground_truth

    def estimate(stack, readings, truth_=None):
        estimates.append(stack_estimate(stack, readings, truth_))
        return estimates[-1]

    def ground_truth(sim_robot, t=None, velocities=False):
        value = read_truth(sim_robot, t, velocities)
        pairs.append((estimates[-1], shadow[0].update(None, value)))
        return value

    monkeypatch.setattr(WalkingStack, "estimate", estimate)
    monkeypatch.setattr(SimRobot, "ground_truth", ground_truth)
    loop = _loop(robot, scenario, 1.0, state="estimated")
    shadow.append(GroundTruthEstimator(loop.planner.w, robot.mass * 9.81))
    assert isinstance(loop.stack.estimator, KinematicInertialEstimator)
    while loop.step() and not loop.done:
        pass
    result = loop.result()
    assert not result.fell
    assert loop.steps_completed >= 4
    relative, velocity, dcm, agree, delays = _errors(pairs)
    errors = result.estimation_errors
    assert errors is not None and errors.ticks == len(pairs) == len(estimates)
    assert errors.com_relative_rms == pytest.approx(relative, rel=1e-9)
    assert errors.com_velocity_rms == pytest.approx(velocity, rel=1e-9)
    assert errors.dcm_rms == pytest.approx(dcm, rel=1e-9)
    assert errors.contact_agreement == pytest.approx(agree, rel=1e-12)
    assert errors.landings == len(delays) and errors.landings >= 4  # the step landings
    zmp = [np.subtract(m.zmp, g.zmp) for m, g in pairs if np.isfinite(m.zmp).all() and np.isfinite(g.zmp).all()]
    assert errors.zmp_rms == pytest.approx(_rms(zmp), rel=1e-6)
    summary = result.summary()
    assert summary["state"] == "estimated" and summary["sensors"] == {"noise": 1.0, "latency": 0, "seed": 0}
    assert summary["estimation"]["dcm_rms"] == errors.dcm_rms


def test_the_stack_and_the_loop_take_the_state_by_name(talos, scenario):
    walk = robot_scenario(scenario, talos)
    stack = walking_stack(talos, walk, dt=0.001, state="estimated")
    assert isinstance(stack.estimator, KinematicInertialEstimator)
    assert isinstance(walking_stack(talos, walk, dt=0.001).estimator, KinematicInertialEstimator)  # the default
    assert isinstance(walking_stack(talos, walk, dt=0.001, state="truth").estimator, GroundTruthEstimator)
    assert LoopOptions().state == "estimated"
    with pytest.raises(ValueError, match="state must be one of truth, estimated"):
        walking_stack(talos, walk, dt=0.001, state="guessed")
    with pytest.raises(ValueError, match=r"LoopOptions\.state"):
        dataclasses.replace(LoopOptions(), state="guessed")
