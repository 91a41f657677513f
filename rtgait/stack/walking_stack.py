"""One control tick of a walking robot: estimator -> walking controller -> whole-body IK -> joint command.

    readings (and, in simulation, the truth)  --estimator-->  Measurement
    Measurement + planner                     --controller--> ControlTargets (COM, feet, lean, foot tilts)
    ControlTargets                            --IK-------->   q (free flyer + joints)
    q + the feet's tilts at the ankles        ------------->  JointCommand (q_ref, dq_ref)

The velocity reference is the joints' finite difference over the control period, ``dq_ref = (q_ref,k - q_ref,k-1)
/ dt``. The IK makes one Gauss-Newton iteration a tick from the last tick's solution (the targets move little in a
period). Between the estimate and the control a loop may act on the planner (footstep changes, velocity commands
due at this tick): :meth:`WalkingStack.estimate` and :meth:`WalkingStack.control` are the two halves of
:meth:`WalkingStack.tick`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from rtgait.interface.command import JointCommand
from rtgait.interface.task_targets import FootOffsets, IKTargets
from rtgait.robot.ankles import AnkleJoints, add_ankle_offsets, find_ankle_joints

if TYPE_CHECKING:
    from rtgait.control.controller import WalkingController
    from rtgait.control.settings import ControlTargets
    from rtgait.estimation.estimator import Estimator
    from rtgait.estimation.state import Measurement
    from rtgait.interface.readings import SensorReadings
    from rtgait.interface.truth import GroundTruth
    from rtgait.robot.ik import WholeBodyIK

__all__ = ["StackOutput", "WalkingStack"]

_new_tuple = tuple.__new__  # a NamedTuple from a tuple at once, without its generated __new__'s argument parsing


class StackOutput(NamedTuple):
    """What one tick of the stack made.

    Attributes:
        measurement: the walking state the controller acted on; ``None`` for a tick that only held IK targets.
        targets: the controller's output (:class:`~rtgait.control.settings.ControlTargets`); ``None`` for a tick
            that only held IK targets (:meth:`WalkingStack.hold`).
        q: the IK's configuration of the reduced model, free flyer first (m, quaternion, rad), shape ``(nq,)``.
        command: the joints' command (:class:`~rtgait.interface.command.JointCommand`), the feet's tilts added at
            the ankles.
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

    @property
    def q(self) -> np.ndarray:
        """The IK's last configuration (a new array each tick: keep it)."""
        return self._q

    def estimate(self, readings: SensorReadings | None, truth: GroundTruth | None = None) -> Measurement:
        """This tick's walking state (the first half of :meth:`tick`)."""
        return self.estimator.update(readings, truth)

    def start(self, t0: float, measurement: Measurement) -> None:
        """Start the walk at ``t0`` (s) from the measured state (the controller's and the planner's start)."""
        self.controller.start(t0, measurement)

    def control(self, t: float, measurement: Measurement) -> StackOutput:
        """The controller's targets at ``t`` (s) for ``measurement``, through the IK to the joints (the second half
        of :meth:`tick`)."""
        out = self.controller.tick(t, measurement)
        targets = _new_tuple(IKTargets, (out.com, out.left_foot, out.right_foot, out.lean))
        return self._command(targets, measurement, out, out.offsets)

    def tick(self, t: float, readings: SensorReadings | None, truth: GroundTruth | None = None) -> StackOutput:
        """One whole tick at ``t`` (s): estimate, control, IK, joint command."""
        return self.control(t, self.estimate(readings, truth))

    def hold(self, targets: IKTargets) -> StackOutput:
        """The joints for IK targets given directly, the controller left out (e.g. a start transition)."""
        return self._command(targets, None, None, None)

    def _command(
        self,
        targets: IKTargets,
        measurement: Measurement | None,
        out: ControlTargets | None,
        offsets: FootOffsets | None,
    ) -> StackOutput:
        q, _ = self.ik.solve(targets, self._q, max_iterations=1, tolerance=0.0, errors=False)
        self._q = q
        joints = q[7:]
        if offsets is not None and any(offsets):
            joints = joints.copy()
            add_ankle_offsets(joints, self.ankles, offsets)
        velocities = (joints - self._joints_previous) / self.dt
        self._joints_previous = joints
        return _new_tuple(StackOutput, (measurement, out, q, JointCommand(joints, velocities)))
