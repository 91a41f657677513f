"""Feed-forward torques through the MuJoCo loop: they reach the drives, they hold G1 up on its own soft gains where
position commands alone let it fall, and the run's summary reports the drives."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")

from rtgait.control.controller import make_controller
from rtgait.robot.controller_info import robot_info
from rtgait.robot.model import RobotModel
from rtgait.robot.motion import robot_scenario
from rtgait.scenario.loading import load_scenario
from rtgait.sim.drive_mode import TORQUE_GAIN_FRACTION, torque_gains
from rtgait.sim.loop import ClosedLoop, LoopOptions
from rtgait.sim.model import SimConfig, build_sim_model

HOLD = 2.0  # s standing at the walk's start


@pytest.fixture(scope="module")
def g1():
    return RobotModel.load("g1")


@pytest.fixture(scope="module")
def g1_robot_gains(g1):
    return build_sim_model(g1, SimConfig(meshes=False, gains="robot"))


def standing_loop(sim, **options):
    """A loop of fig8 on ``sim`` whose start transition holds the robot ``HOLD`` s after a 0.5 s ramp."""
    walk = robot_scenario(load_scenario("fig8"), sim.robot)
    controller = make_controller(
        "adaptive", walk.planner_config(), walk.strides(), walk.sole, robot_info(sim.robot), dt=sim.control_dt
    )
    return ClosedLoop(sim, controller, LoopOptions(start_ramp=0.5, start_hold=HOLD, **options))


def stand(loop) -> bool:
    """Step the start transition; whether the robot is still up at its end."""
    while loop.k < loop.k0:
        if not loop.step():
            return False
    return True


def test_feedforward_torques_reach_the_drives(g1_robot_gains):
    loop = standing_loop(g1_robot_gains)
    assert loop.stack.feedforward is not None, "the robot's gains feed torques forward by default"
    for _ in range(50):
        loop.step()
    drives = loop.robot.drives
    assert drives.tau is not None
    # The drives' law at the last physics step, from MuJoCo's own state: what the actuators applied.
    data, sim = loop.data, g1_robot_gains
    q, dq = data.qpos[sim.qpos_index], data.qvel[sim.dof_index]
    expected = drives.tau + drives.kp * (drives.q - q) + drives.kd * (drives.qd - dq)
    expected = np.clip(expected, -sim.actuation.effort_limit, sim.actuation.effort_limit)
    np.testing.assert_allclose(data.actuator_force, expected, atol=0.05 * np.abs(expected).max())
    # Standing still, the drives' torque is mostly the feed-forward's: the servos' share is small.
    knee = sim.joint_names.index("left_knee_joint")
    assert abs(drives.tau[knee]) > 5.0, "the knee carries the robot's weight"
    assert abs(data.actuator_force[knee] - drives.tau[knee]) < 0.3 * abs(drives.tau[knee])


def test_robot_gains_stand_with_feedforward_and_fall_without(g1_robot_gains):
    # G1's ankles at 40 N m/rad are softer than gravity's toppling stiffness: without feed-forward torques (and the
    # balance they carry) the robot falls within the hold, with them it stands.
    assert not stand(standing_loop(g1_robot_gains, feedforward=False))
    loop = standing_loop(g1_robot_gains)
    assert stand(loop)
    assert loop.base_position[2] > 0.9 * g1_robot_gains.qpos_half_sitting[2]


def test_torque_drive_gains_are_a_tenth_of_the_robots(g1_robot_gains):
    kp, kd = torque_gains(g1_robot_gains)
    np.testing.assert_allclose(kp, TORQUE_GAIN_FRACTION * g1_robot_gains.actuation.kp)
    np.testing.assert_allclose(kd, TORQUE_GAIN_FRACTION * g1_robot_gains.actuation.kd)
    loop = standing_loop(g1_robot_gains, drive="torque")
    loop.step()
    loop.step()
    np.testing.assert_allclose(loop.robot.drives.kp, kp)


def test_summary_reports_the_drives(g1_robot_gains):
    loop = standing_loop(g1_robot_gains)
    for _ in range(loop.k0 + 50):
        assert loop.step()
    result = loop.result()
    drive = result.summary()["drive"]
    assert drive["gains"] == "robot" and drive["drive"] == "position" and drive["feedforward"] is True
    assert 0.0 <= drive["feedforward_clipped_share"] <= 1.0
    assert 0.0 <= drive["drive_saturated_share"] <= 1.0
    peak = drive["peak_torque"]
    limit = g1_robot_gains.actuation.effort_limit
    ratios = np.abs(result.torque).max(axis=0) / limit
    assert peak["ratio"] == pytest.approx(ratios.max())
    assert peak["joint"] == g1_robot_gains.joint_names[int(np.argmax(ratios))]
    rms = drive["com_tracking_rms"]
    assert rms["vs_true"] is not None and 0.0 <= rms["vs_true"] < 0.05
    with pytest.raises(ValueError, match="drive"):
        LoopOptions(drive="current")
    with pytest.raises(ValueError, match="feed-forward"):
        LoopOptions(drive="torque", feedforward=False)


def test_summary_peak_envelope_is_the_motor_bound_at_the_joint_speed(g1):
    from rtgait.sim.drive_summary import ComTracking, drive_summary

    sim = build_sim_model(g1, SimConfig(meshes=False, gains="robot", motor_model=True))
    motors = sim.motors
    n = len(sim.joint_names)
    knee = sim.joint_names.index("left_knee_joint")
    torque, speed = np.zeros((3, n)), np.zeros((3, n))
    # Tick 1: the knee at 40 % of its peak torque while turning, along its torque, at a speed past its corner.
    w0, wc, peak = motors.no_load_speed[knee], motors.corner_speed[knee], motors.peak_torque[knee]
    speed[1, knee] = wc + 0.5 * (w0 - wc)
    torque[1, knee] = 0.4 * peak
    drive = drive_summary(sim, {}, torque, speed, None, 3, ComTracking())
    envelope = drive["peak_envelope"]
    bound = min(peak * 0.5, sim.actuation.effort_limit[knee])  # the envelope half-way down from the corner
    assert envelope["joint"] == "left_knee_joint" and envelope["tick"] == 1
    assert envelope["bound"] == pytest.approx(bound)
    assert envelope["ratio"] == pytest.approx(0.4 * peak / bound)
    assert drive["feedforward_clipped_share"] is None
    # Without the joints' speeds no envelope is known.
    assert drive_summary(sim, {}, torque, None, None, 3, ComTracking())["peak_envelope"] is None


def test_the_settle_holds_the_posture_under_the_robot_s_gains(g1_robot_gains):
    # Settled with the stiff gains, the knees are where half-sitting puts them (under G1's own 100 N m/rad, with no
    # feed-forward, they sagged by a quarter radian); the drives' own gains are back for the run.
    sim = g1_robot_gains
    data = sim.new_data()
    knee = sim.joint_names.index("left_knee_joint")
    q_half = sim.robot.q_half_sitting[7:]
    assert abs(data.qpos[sim.qpos_index][knee] - q_half[knee]) < 0.01
    np.testing.assert_allclose(sim.model.actuator_gainprm[:, 0], sim.actuation.kp)
    np.testing.assert_allclose(-sim.model.actuator_biasprm[:, 2], sim.actuation.kd)


def test_torque_drive_adds_the_tracking_damping_to_the_drives(g1_robot_gains):
    from rtgait.stack.measured_motion import MeasuredMotion

    tracking = MeasuredMotion(g1_robot_gains.robot)
    kp, kd = torque_gains(g1_robot_gains)
    kp_t, kd_t = torque_gains(g1_robot_gains, tracking)
    np.testing.assert_allclose(kp_t, kp)
    np.testing.assert_allclose(kd_t, kd + tracking.damping)
    loop = standing_loop(g1_robot_gains, drive="torque")
    assert loop.stack.feedforward.tracking is not None
    np.testing.assert_allclose(loop.drive_gains[1], kd_t)


def test_on_the_truth_the_feedforward_is_computed_at_the_true_joints(g1_robot_gains):
    # The truth's estimator reads no encoders: the loop gives the feed-forward the joints' true positions and
    # velocities, so that gravity's torques are those of where the robot is. At the IK's configuration instead, the
    # waist's 40 N m/rad nearly cancel against the upper body's toppling stiffness and the trunk sagged (fig8 on the
    # truth fell at 10.7 s). Standing, the state one physics step old is the state now to well under a milliradian.
    sim = g1_robot_gains
    loop = standing_loop(sim, state="truth")
    for _ in range(50):
        loop.step()
    sensed = loop.stack.feedforward.tracking.q  # the configuration the last tick's torques were computed at
    true = sim.pinocchio_from_qpos(loop.data.qpos)
    np.testing.assert_allclose(sensed[7:], true[7:], atol=1e-3)
    # The base placed from the true stance sole: where the robot's base is.
    np.testing.assert_allclose(sensed[:3], true[:3], atol=1e-3)
