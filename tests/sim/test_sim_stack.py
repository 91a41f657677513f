"""The controller stack on the simulated robot through the robot interface: one tick's data path, checked against
Pinocchio's kinematics and MuJoCo's state."""

from __future__ import annotations

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")
pin = pytest.importorskip("pinocchio")

from rtgait.control.controller import make_controller  # noqa: E402
from rtgait.estimation.ground_truth import GroundTruthEstimator  # noqa: E402
from rtgait.interface.command import JointCommand  # noqa: E402
from rtgait.interface.robot import GroundTruthSource, RobotInterface  # noqa: E402
from rtgait.interface.task_targets import IKTargets  # noqa: E402
from rtgait.robot.controller_info import robot_info  # noqa: E402
from rtgait.robot.ik import WholeBodyIK  # noqa: E402
from rtgait.robot.motion import robot_scenario  # noqa: E402
from rtgait.scenario import load_scenario  # noqa: E402
from rtgait.sim.robot import SimRobot  # noqa: E402
from rtgait.stack.setup import start_pose  # noqa: E402
from rtgait.stack.walking_stack import WalkingStack  # noqa: E402


@pytest.fixture
def standing(talos, talos_sim):
    """Talos standing in MuJoCo behind the robot interface, and a stack around an adaptive controller for fig8."""
    walk = robot_scenario(load_scenario("fig8"), talos)
    controller = make_controller(
        "adaptive", walk.planner_config(), walk.strides(), walk.sole, robot_info(talos), dt=talos_sim.control_dt
    )
    ik = WholeBodyIK(talos)
    cog, left, right = start_pose(controller.planner)
    q, _ = ik.solve(IKTargets(cog, left, right), talos.q_half_sitting, 200, 1e-9)
    data = talos_sim.new_data(q=q)
    robot = SimRobot(talos_sim, data, q[7:])
    estimator = GroundTruthEstimator(controller.planner.w, talos.mass * 9.81)
    return robot, WalkingStack(estimator, controller, ik, q), talos


def test_the_simulated_robot_offers_the_robot_interface_and_its_truth(standing):
    robot, _, talos = standing
    assert isinstance(robot, RobotInterface) and isinstance(robot, GroundTruthSource)
    readings = robot.read()
    assert readings.joint_positions.shape == readings.joint_velocities.shape == (len(robot.joint_names),)
    assert readings.imu is not None and readings.left_foot is not None and readings.right_foot is not None
    with pytest.raises(ValueError, match="kp must be"):  # a gain per joint, refused before anything changes
        gains = np.ones(len(talos.joint_names) + 1)
        robot.write(JointCommand(readings.joint_positions, readings.joint_velocities, kp=gains))


def test_one_tick_from_readings_to_the_joint_command(standing):
    robot, stack, talos = standing
    robot.first_substep()  # a physics step: contacts and forces of the start state
    truth = robot.ground_truth(t=0.0)
    measurement = stack.estimate(robot.read(), truth)
    assert measurement.normal_force == pytest.approx(talos.mass * 9.81, rel=0.05)
    stack.start(0.0, measurement)
    previous = stack.q[7:].copy()
    out = stack.control(0.0, measurement)
    # The command's joints are the IK's (ankle tilts aside), and its velocity their finite difference.
    np.testing.assert_allclose(out.command.velocities, (out.command.positions - previous) / stack.dt)
    # Pinocchio's COM of the IK's configuration is the controller's COM target, to the IK's one-iteration accuracy.
    data = talos.model.createData()
    com = pin.centerOfMass(talos.model, data, out.q)
    np.testing.assert_allclose(com, out.targets.com, atol=2e-3)
    # Written to the drives, the period's last substep ends at the command's reference (a servo's control is
    # q_ref + (kd / kp) dq_ref: rtgait.sim.drives).
    robot.write(out.command)
    robot.first_substep()
    for i in range(1, robot.substeps):
        robot.substep(i)
    lead = robot.sim.kd / robot.sim.kp
    np.testing.assert_array_equal(robot.data.ctrl, lead * out.command.velocities + out.command.positions)


def test_an_estimator_whose_dcm_frequency_is_not_the_planner_s_is_refused(standing):
    """The controller acts on the estimator's DCM as it is: made with another ``w``, it would not compare with the
    plan's, so the stack refuses it at once."""
    _, stack, talos = standing
    w = stack.controller.planner.w
    other = GroundTruthEstimator(1.01 * w, talos.mass * 9.81)
    with pytest.raises(ValueError, match="differs from the planner's w"):
        WalkingStack(other, stack.controller, stack.ik, stack.q)
    assert WalkingStack(GroundTruthEstimator(w, talos.mass * 9.81), stack.controller, stack.ik, stack.q).dt == stack.dt
