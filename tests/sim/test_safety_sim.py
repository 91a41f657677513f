"""The safety layer in physics: the simulated drives' damping law, readings that go stale mid-walk ending in damping
(the joints brake, no exception), a fault inside the closed loop logged to the run's outputs, and a normal walk that
never trips."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest

pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")

from rtgait.control.controller import make_controller
from rtgait.interface.command import JointCommand
from rtgait.io.sim_files import sim_report, write_sim_outputs
from rtgait.robot.controller_info import robot_info
from rtgait.robot.motion import robot_scenario
from rtgait.scenario import load_scenario
from rtgait.sim.log_file import sim_events
from rtgait.sim.loop import ClosedLoop, LoopOptions
from rtgait.sim.robot import SimRobot
from rtgait.stack.setup import walking_stack

STALE_AT = 2.35  # s: fig8's third step, its swing foot in the air


@pytest.fixture(autouse=True)
def servos_back(talos_sim):
    """The shared model's drives back to their servos after each test (damping is set in the model)."""
    yield
    data = talos_sim.new_data()
    SimRobot(talos_sim, data, data.qpos[talos_sim.qpos_index].copy())


def period(body: SimRobot) -> None:
    """One control period of physics."""
    body.first_substep()
    for i in range(1, body.substeps):
        body.substep(i)


def rms_joint_speed(body: SimRobot) -> float:
    dq = body.data.qvel[body.sim.dof_index]
    return float(np.sqrt(np.mean(dq * dq)))


@pytest.fixture(scope="module")
def stale_walk(talos, talos_sim):
    """fig8 on Talos in a loop of one's own, the readings frozen from :data:`STALE_AT` on, about 0.25 s past the trip;
    the state at the trip and the joint speeds from it on kept."""
    stack = walking_stack(talos, robot_scenario(load_scenario("fig8"), talos), dt=talos_sim.control_dt)
    body = SimRobot(talos_sim, talos_sim.new_data(q=stack.q), stack.q[7:])
    dt = talos_sim.control_dt
    stack.start(0.0, stack.estimate(body.read(), body.ground_truth(t=0.0)))
    frozen, at_trip, speeds = None, None, []
    for k in range(round((STALE_AT + 0.25) / dt)):
        t = k * dt
        readings = body.read()
        if t >= STALE_AT:
            frozen = frozen or readings
            readings = frozen
        out = stack.tick(t, readings, body.ground_truth(t=t))
        if out.command.kp is not None and at_trip is None:
            at_trip = (t, copy.copy(body.data), rms_joint_speed(body))
        body.write(out.command)
        period(body)
        if at_trip is not None:
            speeds.append(rms_joint_speed(body))
    return stack, body, frozen, at_trip, speeds


def test_readings_stale_mid_walk_end_in_damping_without_an_exception(stale_walk, talos_sim):
    stack, body, frozen, (t_trip, _, _), _ = stale_walk
    stale_periods = stack.safety.settings.stale_periods
    # The frozen readings' first tick is fresh; N more are tolerated; the (N+1)th trips.
    assert t_trip == pytest.approx(frozen.t + (stale_periods + 1) * talos_sim.control_dt, abs=1e-9)
    [event] = stack.safety.events
    assert event.kind == "stale-readings" and event.t == pytest.approx(t_trip)
    assert stack.safety.damping and body.damping
    np.testing.assert_array_equal(talos_sim.model.actuator_gainprm[:, 0], stack.safety.damping_kd)


def test_the_joints_brake_in_damping_and_move_slower_than_limp_drives(stale_walk, talos_sim):
    stack, _, _, (_, state, speed), speeds = stale_walk
    dt = talos_sim.control_dt
    # The walk's joint motion is braked at once: 10 ms after the trip the joints turn at well under the walk's speed.
    assert speeds[round(0.01 / dt)] < 0.75 * speed
    # Damping does not hold the robot up (kp = 0): it sinks, but its joints move at a fraction of the speed of drives
    # that let go (kd = 0), from the same state.
    n = len(stack.safety.damping_kd)
    limp = SimRobot(talos_sim, copy.copy(state), stack.q[7:])
    command = JointCommand(np.zeros(n), np.zeros(n), None, np.zeros(n), np.zeros(n))
    for _ in range(round(0.2 / dt)):
        limp.write(command)
        period(limp)
    assert speeds[round(0.2 / dt) - 1] < 0.5 * rms_joint_speed(limp)


def test_the_damping_drives_apply_kd_times_minus_the_joint_velocity(talos, talos_sim):
    stack = walking_stack(talos, robot_scenario(load_scenario("fig8"), talos), dt=talos_sim.control_dt)
    data = talos_sim.new_data(q=stack.q)
    body = SimRobot(talos_sim, data, stack.q[7:])
    actuation = talos_sim.actuation
    np.testing.assert_array_equal(talos_sim.model.actuator_gainprm[:, 0], actuation.kp)  # the servos, as built
    n = len(body.joint_names)
    rng = np.random.default_rng(3)
    data.qvel[talos_sim.dof_index] = rng.uniform(-2.0, 2.0, n)
    kd = np.linspace(5.0, 300.0, n)
    reference = rng.uniform(-0.5, 0.5, n)
    before = data.qvel[talos_sim.dof_index].copy()
    body.write(JointCommand(np.zeros(n), reference, np.zeros(n), np.zeros(n), kd))
    body.first_substep()  # the actuator forces of the state it started from
    expected = np.clip(kd * (reference - before), -actuation.effort_limit, actuation.effort_limit)
    np.testing.assert_allclose(data.actuator_force, expected, rtol=1e-12, atol=1e-9)
    assert (np.abs(expected) == actuation.effort_limit).any()  # the torque limit acted on some joint
    # A position command puts the servos back.
    body.write(JointCommand(stack.q[7:].copy(), np.zeros(n)))
    assert not body.damping
    np.testing.assert_array_equal(talos_sim.model.actuator_gainprm[:, 0], actuation.kp)
    np.testing.assert_array_equal(talos_sim.model.actuator_biasprm[:, 2], -actuation.kd)


def test_the_drives_refuse_bad_commands_and_change_nothing(talos_sim):
    data = talos_sim.new_data()
    q = data.qpos[talos_sim.qpos_index].copy()
    body = SimRobot(talos_sim, data, q)
    n = len(q)
    gains = talos_sim.model.actuator_gainprm[:, 0].copy()
    with pytest.raises(ValueError, match="kd must be"):
        body.write(JointCommand(q, np.zeros(n), None, np.zeros(n), -np.ones(n)))
    with pytest.raises(ValueError, match="kp must be"):
        body.write(JointCommand(q, np.zeros(n), None, np.ones(n - 1), np.ones(n)))
    with pytest.raises(ValueError, match="torques must be"):
        body.write(JointCommand(q, np.zeros(n), np.full(n, np.nan)))
    with pytest.raises(ValueError, match="positions must be"):
        body.write(JointCommand(np.full(n, np.inf), np.zeros(n), np.zeros(n)))
    assert not body.damping
    np.testing.assert_array_equal(talos_sim.model.actuator_gainprm[:, 0], gains)


class FailingEstimator:
    """The loop's estimator, raising a bad-input error from ``after`` (s) on."""

    def __init__(self, estimator, after: float) -> None:
        self.estimator, self.after = estimator, after
        self.reads_truth = estimator.reads_truth

    def reset(self) -> None:
        self.estimator.reset()

    def update(self, readings, truth):
        if (truth if readings is None else readings).t >= self.after:  # on the estimate or the truth
            raise ValueError("the left foot's contact wrench is out of the estimator's bounds")
        return self.estimator.update(readings, truth)


@pytest.fixture(scope="module")
def damped_run(talos, talos_sim, shorten):
    """A short fig8 walk whose estimator raises from 1 s on, run to its end or a fall."""
    walk = robot_scenario(shorten("fig8", 3), talos)
    level = make_controller("adaptive", walk.planner_config(), walk.strides(), walk.sole, robot_info(talos),
                            dt=talos_sim.control_dt)  # fmt: skip
    loop = ClosedLoop(talos_sim, level, LoopOptions(start_ramp=0.5, start_hold=0.3, after=0.3))
    loop.stack.estimator = FailingEstimator(loop.stack.estimator, after=1.0)
    while loop.step() and not loop.done:  # no exception: the run goes on, in damping, to its end or a fall
        pass
    return loop.result()


def test_a_fault_in_the_closed_loop_damps_and_goes_to_the_runs_outputs(damped_run):
    result = damped_run
    assert result.safety["damping"] and result.safety["counts"]["error"] == 1
    first = result.safety["first_event"]
    assert first["kind"] == "error" and first["t"] == pytest.approx(1.0)
    assert "out of the estimator's bounds" in first["detail"]
    json.dumps(result.summary())  # summary.json's values
    [damping] = [e for e in sim_events(result) if e["kind"] == "damping"]
    assert damping["t"] == pytest.approx(1.0) and damping["detail"].startswith("error: ValueError")
    after = result.times >= 1.0
    assert np.isnan(result.cog_planned[after]).all() and not np.isnan(result.cog_planned[~after]).any()


def test_a_damped_runs_files_say_so(damped_run, talos, tmp_path):
    """summary.json's safety record and the report line; the figure and the 3D replay draw a run without a plan after
    the trip."""
    pytest.importorskip("meshcat")
    extra = {"scenario": "fig8", "connection": "auto"}
    summary = write_sim_outputs(damped_run, tmp_path, replay=talos, extra=extra)
    assert {"zmp_sim.png", "replay.html", "summary.json"} <= set(summary["files"])
    written = json.loads((tmp_path / "summary.json").read_text())
    assert written["safety"]["first_event"]["kind"] == "error" and written["safety"]["damping"]
    assert "DAMPING from 1.000 s (error: ValueError" in sim_report(summary, tmp_path)


def test_a_normal_walk_never_trips(short_walk):
    _, result = short_walk
    assert result.safety_events == () and result.safety["events"] == 0 and not result.safety["damping"]
    assert result.summary()["safety"]["first_event"] is None
