"""One control tick of a walking robot: estimator -> walking controller -> whole-body IK -> joint command.

    readings (and, in simulation, the truth)  --estimator-->  Measurement
    Measurement + planner                     --controller--> ControlTargets (COM, feet, lean, foot tilts)
    ControlTargets                            --IK-------->   q (free flyer + joints)
    q + the feet's tilts at the ankles        ------------->  JointCommand (q_ref, dq_ref)
    q + the controller's ZMP split            --feed-forward-> JointCommand.torques (when asked for)

The velocity reference is the joints' finite difference over the control period, ``dq_ref = (q_ref,k - q_ref,k-1)
/ dt``. The IK makes one Gauss-Newton iteration a tick from the last tick's solution (the targets move little in a
period). With a :class:`~rtgait.stack.feedforward.FeedForward`, the command also carries the feed-forward torques of the
IK's motion with the wrenches the controller asks of the feet (whole-body inverse dynamics); without one (the
default) it carries none. A feed-forward that tracks from the sensed state (torque drive, its ``tracking`` set) gets
the tick's encoder readings (those :meth:`WalkingStack.estimate` was given) and estimate.

Between the estimate and the control a loop may act on the planner (footstep changes, velocity commands due at this
tick): :meth:`WalkingStack.estimate` and :meth:`WalkingStack.control` are the two halves of :meth:`WalkingStack.tick`.

The safety layer (:mod:`rtgait.stack.safety`) sits at both ends: it checks the readings and the estimate before the
controller acts on them, catches the ``ValueError`` and ``ArithmeticError`` the estimator, the controller, its planner
and the IK raise on bad input, clips every command to the joints' limits, and, once tripped, answers every tick with
the damping command (``kp = 0``, ``kd > 0``): no exception leaves a tick on bad readings. A tripped tick's
:class:`StackOutput` has no measurement and no targets; :meth:`WalkingStack.estimate` returns ``None`` once a fault is
found (it is logged, with the tick's time, by the :meth:`WalkingStack.control` that follows).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from rtgait.core.geometry.foot_tilt import is_tilted, tilted_feet
from rtgait.core.geometry.ground_height import changes_ground_height, ground_rise
from rtgait.core.geometry.toe_off import changes_height, toe_off_feet
from rtgait.estimation.kinematic_inertial import KinematicInertialEstimator
from rtgait.interface.command import JointCommand
from rtgait.interface.task_targets import FootOffsets, IKTargets
from rtgait.robot.ankles import AnkleJoints, add_ankle_offsets, find_ankle_joints
from rtgait.robot.joint_inertia import damping_gains
from rtgait.robot.joint_limits import joint_limits
from rtgait.stack.estimators import shared_kinematics
from rtgait.stack.safety import Fault, SafetyLayer

if TYPE_CHECKING:
    from collections.abc import Sequence

    from rtgait.control.controller import WalkingController
    from rtgait.control.settings import ControlTargets
    from rtgait.estimation.estimator import Estimator
    from rtgait.estimation.state import Measurement
    from rtgait.interface.readings import SensorReadings
    from rtgait.interface.truth import GroundTruth
    from rtgait.robot.ik import WholeBodyIK
    from rtgait.stack.feedforward import FeedForward

__all__ = ["StackOutput", "WalkingStack"]

_new_tuple = tuple.__new__  # a NamedTuple from a tuple at once, without its generated __new__'s argument parsing
_BAD_INPUT = (ValueError, ArithmeticError)  # what bad numbers raise inside a tick (the documented ValueErrors)


class StackOutput(NamedTuple):
    """What one tick of the stack made.

    Attributes:
        measurement: the walking state the controller acted on; ``None`` for a tick that only held IK targets or
            that damps.
        targets: the controller's output (:class:`~rtgait.control.settings.ControlTargets`); ``None`` for a tick
            that only held IK targets (:meth:`WalkingStack.hold`) or that damps (the safety layer tripped).
        q: the IK's configuration of the reduced model, free flyer first (m, quaternion, rad), shape ``(nq,)``.
        command: the joints' command (:class:`~rtgait.interface.command.JointCommand`), the feet's tilts added at
            the ankles, within the joints' limits; the damping command once the safety layer has tripped.
    """

    measurement: Measurement | None
    targets: ControlTargets | None
    q: np.ndarray
    command: JointCommand


class WalkingStack:
    """The control tick of module docstring, for a robot whose sensors ``estimator`` reads.

    Args:
        estimator: readings -> walking state (:class:`~rtgait.estimation.estimator.Estimator`).
        controller: the walking controller (:class:`~rtgait.control.controller.WalkingController`); its control
            period is the stack's.
        ik: the whole-body IK of the robot.
        q: the configuration the robot starts from (the IK's first solution), shape ``(nq,)``.
        ankles: where the feet's tilts go; default found from the robot's sole frames.
        safety: the safety layer; default one with the robot's joint limits and damping gains
            (:func:`rtgait.robot.joint_limits.joint_limits`, :func:`rtgait.robot.joint_inertia.damping_gains`), the
            planner's COM height and the default :class:`~rtgait.stack.safety.SafetySettings`.
        feedforward: the feed-forward torques of each tick's command; ``None``: none (``JointCommand.torques`` is
            ``None``).

    The controller acts on the measurement's DCM as the estimator made it, so an estimator that says its pendulum
    frequency (an ``omega`` attribute, 1/s) must make it with the planner's ``w``.
    """

    def __init__(
        self,
        estimator: Estimator,
        controller: WalkingController,
        ik: WholeBodyIK,
        q: np.ndarray,
        ankles: AnkleJoints | None = None,
        safety: SafetyLayer | None = None,
        feedforward: FeedForward | None = None,
    ) -> None:
        q = np.array(q, dtype=float)
        if q.shape != (ik.robot.model.nq,):
            raise ValueError(f"q must have the robot's {ik.robot.model.nq} coordinates, got shape {q.shape}")
        omega, w = getattr(estimator, "omega", None), controller.planner.w
        if omega is not None and omega != w:
            raise ValueError(f"the estimator's DCM omega {omega} 1/s differs from the planner's w {w} 1/s")
        self.estimator, self.controller, self.ik = estimator, controller, ik
        self.ankles = find_ankle_joints(ik.robot) if ankles is None else ankles
        self.dt = controller.dt
        self._q = q
        self._joints_previous = q[7:].copy()
        if safety is None:
            robot = ik.robot
            safety = SafetyLayer(joint_limits(robot), damping_gains(robot), controller.planner.config.cog_height)
        self.safety = safety
        self.feedforward = feedforward
        self._kinematics = shared_kinematics(estimator)  # the estimator's, for a feed-forward at the sensed state
        self._fault: Fault | None = None  # found by estimate(), logged by the control() of the same tick
        self._tilted = False  # whether the walk has sloped footholds (set at the start)
        self._toe_off = False  # whether a step changes height: toe-offs (set at the start)
        self._heights = False  # footholds at different heights, an estimator with a landing gate (at the start)
        self._readings: SensorReadings | None = None  # the last estimate's, for a feed-forward at the sensed state
        self.ik_feet: tuple[Sequence[float], Sequence[float]] | None = None
        """The feet targets last given to the IK (left, right): ``(x, y, z, yaw)``, or ``(x, y, z, yaw, pitch,
        roll)`` with the soles' tilts to sloped footholds and toe-offs (m, rad); ``None`` before the first command.
        A simulator compares the soles with them (the tilt they were commanded)."""
        self.toe_off: tuple[float, float] = (0.0, 0.0)
        """The toe-off pitch in those targets (left, right; rad, heel up: :mod:`rtgait.core.geometry.toe_off`), the
        part of their pitch the sole rolls through from its foothold's tilt."""

    @property
    def q(self) -> np.ndarray:
        """The IK's last configuration (a new array each tick: keep it)."""
        return self._q

    def estimate(self, readings: SensorReadings | None, truth: GroundTruth | None = None) -> Measurement | None:
        """This tick's walking state (the first half of :meth:`tick`); ``None`` when the safety layer finds a fault
        in the readings or the estimate, or has tripped before (module docstring)."""
        safety = self.safety
        self._readings = readings
        if self._kinematics is not None:  # the estimator's kinematics of these readings, or none if it does not run
            self._kinematics.last = None
        if safety.damping:
            safety.observe_joints(readings)
            return None
        fault = safety.check_readings(readings)
        if fault is None:
            try:
                measurement = self.estimator.update(readings, truth)
            except _BAD_INPUT as error:
                fault = _error(error)
            else:
                fault = safety.check_measurement(measurement)
                if fault is None:
                    return measurement
        self._fault = fault
        return None

    def start(self, t0: float, measurement: Measurement | None) -> None:
        """Start the walk at ``t0`` (s) from the measured state (the controller's and the planner's start); after a
        fault at the first estimate the safety layer trips instead."""
        if self._fault is not None or self.safety.damping:
            self._damp(t0)
            return
        try:
            self.controller.start(t0, measurement)
        except _BAD_INPUT as error:
            self._damp(t0, _error(error))
            return
        planner = self.controller.planner
        # On sloped footholds the soles turn to their surfaces (foot_tilt.py); a walk by command has none.
        self._tilted = planner.n_steps is not None and is_tilted(planner.footprints())
        # Before a step up or down the rear heel rolls onto its toe (toe_off.py).
        self._toe_off = planner.n_steps is not None and changes_height(planner.footprints())
        # The landing gate lets a foot down onto ground the plan has higher than the other foot's (ground_height.py).
        self._heights = (
            planner.n_steps is not None
            and changes_ground_height(planner.footprints())
            and isinstance(self.estimator, KinematicInertialEstimator)
        )
        if self._tilted or self._toe_off:  # sole levelling reads any tilt of a standing sole as the leg's error
            self.controller.off_level_ground()

    def control(self, t: float, measurement: Measurement | None) -> StackOutput:
        """The controller's targets at ``t`` (s) for ``measurement``, through the IK to the joints (the second half
        of :meth:`tick`); the damping command once the safety layer has tripped, or when the estimate found a fault
        (``measurement`` ``None``)."""
        if measurement is None or self.safety.damping:
            return self._damp(t, None if measurement is not None else ("error", "no measurement at this tick"))
        try:
            out = self.controller.tick(t, measurement)
            left, right = out.left_foot, out.right_foot
            if self._tilted or self._toe_off or self._heights:  # off the flat floor: the footholds shape the feet
                prints = self.controller.planner.footprints()
                if self._tilted:
                    left, right = tilted_feet(prints, left, right)
                if self._toe_off:
                    if not self._tilted:
                        left, right = (*left[:4], 0.0, 0.0), (*right[:4], 0.0, 0.0)
                    description = self.ik.robot.description
                    flat_left, flat_right = left[4], right[4]
                    left, right = toe_off_feet(
                        prints, description.sole.front, left, right, out.zmp_planned, description.toe_release
                    )
                    self.toe_off = (left[4] - flat_left, right[4] - flat_right)
                if self._heights:
                    self.estimator.ground_rise = ground_rise(prints, left, right)  # type: ignore[attr-defined]
            targets = _new_tuple(IKTargets, (out.com, left, right, out.lean))
            return self._command(t, targets, measurement, out, out.offsets)
        except _BAD_INPUT as error:
            return self._damp(t, _error(error))

    def tick(self, t: float, readings: SensorReadings | None, truth: GroundTruth | None = None) -> StackOutput:
        """One whole tick at ``t`` (s): estimate, control, IK, joint command (the damping command once tripped)."""
        return self.control(t, self.estimate(readings, truth))

    def hold(
        self,
        targets: IKTargets,
        t: float = math.nan,
        zmp_shift: tuple[float, float] | None = None,
        measurement: Measurement | None = None,
    ) -> StackOutput:
        """The joints for IK targets given directly, the controller left out (e.g. a start transition; ``t`` (s)
        stamps a fault); the damping command once the safety layer has tripped. ``zmp_shift`` (m): a balance law's
        ``p_cmd - p_ref``, which the feed-forward torques carry (:meth:`FeedForward.torques
        <rtgait.stack.feedforward.FeedForward.torques>`). ``measurement``: this tick's estimate (of
        :meth:`estimate`), for a feed-forward that tracks from the sensed state; the output carries none."""
        if self.safety.damping:
            return self._damp(t)
        try:
            return self._command(t, targets, None, None, None, zmp_shift, measurement)
        except _BAD_INPUT as error:
            return self._damp(t, _error(error))

    def _damp(self, t: float, fault: Fault | None = None) -> StackOutput:
        """The damping output at ``t`` (s), the safety layer tripped first by the fault the estimate found, else
        by ``fault`` (nothing is logged once it has tripped)."""
        fault = self._fault or fault
        if fault is not None:
            self._fault = None
            self.safety.trip(t, *fault)
        command = self.safety.damping_command(self._joints_previous)
        return _new_tuple(StackOutput, (None, None, self._q, command))

    def _command(
        self,
        t: float,
        targets: IKTargets,
        measurement: Measurement | None,
        out: ControlTargets | None,
        offsets: FootOffsets | None,
        zmp_shift: tuple[float, float] | None = None,
        sensed_state: Measurement | None = None,
    ) -> StackOutput:
        q, _ = self.ik.solve(targets, self._q, max_iterations=1, tolerance=0.0, errors=False)
        self.ik_feet = (targets.left_foot, targets.right_foot)
        joints = q[7:]
        if offsets is not None and any(offsets):
            joints = joints.copy()
            add_ankle_offsets(joints, self.ankles, offsets)
        previous, clip = self._joints_previous, self.safety.clip
        velocities = (joints - previous) / self.dt
        # The last joints are finite (checked here each tick): a NaN or infinite joint makes the difference one (the
        # sum as Python floats costs a third of numpy's on a few dozen values).
        if not math.isfinite(sum(velocities.tolist())):
            return self._damp(t, ("bad-command", "the joint command is NaN or infinite"))
        clipped = clip.positions(joints)
        if clipped is not joints:  # the velocity reference follows the clipped positions
            joints, velocities = clipped, (clipped - previous) / self.dt
        velocities = clip.velocities(velocities)
        torques = None
        feedforward = self.feedforward
        if feedforward is not None:
            sensed = None
            state, readings = measurement or sensed_state, self._readings
            if feedforward.tracking is not None and state is not None and readings is not None:
                body = None if self._kinematics is None else self._kinematics.last  # of this tick's encoder readings
                sensed = (joints, readings.joint_positions, readings.joint_velocities, state, body)
            torques = feedforward.torques(q, targets, out, zmp_shift, sensed, velocities)
            if not math.isfinite(sum(torques.tolist())):
                return self._damp(t, ("bad-command", "the feed-forward torques are NaN or infinite"))
            torques = clip.torques(torques)
        self._q = q
        self._joints_previous = joints
        return _new_tuple(StackOutput, (measurement, out, q, JointCommand(joints, velocities, torques)))


def _error(error: Exception) -> Fault:
    """An exception caught at the tick's boundary, as a fault."""
    return "error", f"{type(error).__name__}: {error}"
