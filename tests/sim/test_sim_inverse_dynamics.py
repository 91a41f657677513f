"""The feed-forward torques of whole-body inverse dynamics against MuJoCo's joint torques (the position servos'
actuator forces) on a slow motion of Talos: the COM moved over the left foot in double support, the right foot lifted,
the COM swayed over the left sole in single support.

Two comparisons, leg joints only (the torso joints have 1 N m of dry friction that no inverse dynamics models):

* inverse dynamics with the contact wrenches MuJoCo measures, over the whole motion: the dynamics themselves;
* the stack's feed-forward (the wrenches it distributes itself) in single support, where the wrench on the stance
  foot is the motion's: what a drive would be given. In double support the split between the feet is not the
  motion's (stiff position servos share the load their own way): there only the sum of the feet's wrenches is.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")

from rtgait.control.settings import ControlTargets  # noqa: E402
from rtgait.interface.command import JointCommand  # noqa: E402
from rtgait.interface.task_targets import FootOffsets, IKTargets  # noqa: E402
from rtgait.robot.controller_info import robot_info  # noqa: E402
from rtgait.robot.drives import joint_drives  # noqa: E402
from rtgait.robot.ik import WholeBodyIK  # noqa: E402
from rtgait.robot.inverse_dynamics import InverseDynamics  # noqa: E402
from rtgait.sim.actuation import resolve_actuation  # noqa: E402
from rtgait.sim.robot import SimRobot  # noqa: E402
from rtgait.stack.feedforward import FeedForward  # noqa: E402

SHIFT, LIFT, SETTLE, SWAY = (0.2, 2.2), (2.2, 3.7), 5.2, 8.2  # s: the phases of the motion
LIFT_HEIGHT = 0.03  # m
SWAY_AMPLITUDE = (0.015, 0.01)  # m, COM over the stance sole: forward, sideways
SWAY_PERIOD = 3.0  # s
LEGS = slice(0, 12)


def _smooth(x: float) -> float:
    """A quintic from 0 to 1 over [0, 1], flat at both ends."""
    x = min(max(x, 0.0), 1.0)
    return x * x * x * (10.0 - 15.0 * x + 6.0 * x * x)


@pytest.fixture(scope="module")
def slow_motion(talos, talos_sim):
    """Run the motion; per tick: time, support, the feed-forward, the inverse dynamics with MuJoCo's wrenches, the
    actuator forces, the required wrench and MuJoCo's total contact wrench (world, about the origin)."""
    sim, dt = talos_sim, talos_sim.control_dt
    sole = robot_info(talos).sole
    ik = WholeBodyIK(talos)
    half = 0.5 * talos.step_width
    height = talos.description.cog_height
    left, right = (0.0, half, 0.0, 0.0), (0.0, -half, 0.0, 0.0)
    q, _ = ik.solve(IKTargets((0.0, 0.0, height), left, right), talos.q_half_sitting, 200, 1e-9)
    data = sim.new_data(q=q)
    robot = SimRobot(sim, data, q[7:])
    feedforward = FeedForward(talos, sole, dt)
    measured = InverseDynamics(talos, sole)
    rows = []
    for k in range(round(SWAY / dt)):
        t = k * dt
        sway = _smooth((t - SETTLE) / 1.0)
        phase = 2.0 * math.pi * (t - SETTLE) / SWAY_PERIOD
        com = (
            SWAY_AMPLITUDE[0] * sway * math.sin(phase),
            half * _smooth((t - SHIFT[0]) / (SHIFT[1] - SHIFT[0])) + SWAY_AMPLITUDE[1] * sway * math.sin(phase),
            height,
        )
        lifted = (right[0], right[1], LIFT_HEIGHT * _smooth((t - LIFT[0]) / (LIFT[1] - LIFT[0])), right[3])
        targets = IKTargets(com, left, lifted)
        q, _ = ik.solve(targets, q, max_iterations=1, tolerance=0.0, errors=False)
        support = "double" if t < LIFT[0] else "left"
        out = ControlTargets(
            t, com, left, lifted, FootOffsets(), com[:2], com[:2], (0.0, 0.0), support, 0, ()
        )  # the controller's output as far as the feed-forward reads it: the support (the ZMP only in double)
        tau = feedforward.torques(q, targets, out if support != "double" else None)
        robot.write(JointCommand(q[7:].copy(), np.zeros(len(q) - 7)))
        truth = robot.ground_truth(t)
        robot.first_substep()
        measured.update(q, feedforward.rates.velocity, feedforward.rates.acceleration)
        wrenches = np.array([
            measured.sole_wrench(i, np.concatenate([foot.force, foot.moment]))
            for i, foot in enumerate((truth.left, truth.right))
        ])  # fmt: skip
        total = np.concatenate([
            np.add(truth.left.force, truth.right.force), np.add(truth.left.moment, truth.right.moment)
        ])  # fmt: skip
        required = feedforward.dynamics.required
        rows.append((t, support, tau, measured.torques(wrenches), data.actuator_force.copy(),
                     np.concatenate([required.force, required.moment]), total))  # fmt: skip
    return rows


def _columns(rows, window):
    """Times, feed-forward, inverse dynamics with MuJoCo's wrenches, actuator forces, required and measured total
    wrenches of the ticks in ``window`` (s)."""
    chosen = [row for row in rows if window[0] <= row[0] < window[1]]
    return tuple(np.array([row[i] for row in chosen]) for i in (0, 2, 3, 4, 5, 6))


def _rms(error):
    """Each leg joint's RMS error (N m)."""
    return np.sqrt((error**2).mean(axis=0))


def test_inverse_dynamics_with_the_measured_wrenches_gives_the_actuator_forces(slow_motion):
    # The whole motion, double and single support: RNEA, the armature, the soles' Jacobians and frames.
    _, _, with_wrenches, actuators, _, _ = _columns(slow_motion, (SHIFT[0], SWAY))
    legs = actuators[:, LEGS]
    rms = _rms(with_wrenches[:, LEGS] - legs)
    assert rms.max() < 0.01 * np.abs(legs).max(), f"RMS errors {np.round(rms, 2)} N m"


def test_the_feed_forward_gives_the_stance_leg_torques_in_single_support(slow_motion):
    # From the sway's start: the lift's load transfer has rung down by then (the sole's rocking on its soft contact).
    _, feedforward, _, actuators, _, _ = _columns(slow_motion, (SETTLE, SWAY))
    legs = actuators[:, LEGS]
    rms = _rms(feedforward[:, LEGS] - legs)
    assert rms.max() < 0.03 * np.abs(legs).max(), f"RMS errors {np.round(rms, 2)} N m"


def test_the_required_wrench_is_the_measured_contact_wrench_in_double_support(talos, slow_motion):
    # The motion's wrench, which the feed-forward's wrenches sum to, against the sum MuJoCo's contacts give: the
    # same weight and ZMP to within what the servos' compliance moves the real COM from the commanded one.
    _, _, _, _, required, total = _columns(slow_motion, (SHIFT[0], LIFT[0]))
    np.testing.assert_allclose(required[:, 2], total[:, 2], atol=0.01 * talos.mass * 9.81)
    zmp_required = np.column_stack([-required[:, 4], required[:, 3]]) / required[:, 2:3]
    zmp_measured = np.column_stack([-total[:, 4], total[:, 3]]) / total[:, 2:3]
    np.testing.assert_allclose(zmp_required, zmp_measured, atol=0.005)


def test_the_drives_armature_is_the_simulated_drives(talos, talos_sim):
    np.testing.assert_allclose(joint_drives(talos)[1], resolve_actuation(talos, talos_sim.control_dt).armature)
