"""The simulated joint drives: a :class:`~rtgait.interface.command.JointCommand` in, MuJoCo's actuator controls and
gains out, at every physics step.

Each drive applies, at every physics step of the control period, at that step's state,

    tau = tau_ff + kp (q_ref - q_enc) + kd (dq_ref - dq)                                               (N m)

clipped to the joint's torque limit or, with the motor model, to its motor's envelope at ``dq``
(:mod:`rtgait.sim.motors`); ``q_enc = q + o`` is the encoder's reading (``o``: the model error's joint zero offsets,
:mod:`rtgait.sim.model_error`), so a drive holding ``q_ref`` holds the joint at ``q_ref - o``. A command's gains left
``None`` are the drive's own (:class:`~rtgait.sim.actuation.Actuation`'s ``kp``, ``kd``: ``SimConfig.gains``), its
torque left ``None`` is zero.

**In MuJoCo**, one general actuator per joint computes ``force = g ctrl - kp q - kd dq`` (:func:`rtgait.sim.actuation.
add_actuators`; the ``-kd dq`` integrated implicitly). With the gains in the model's actuator parameters, the control
of each joint is

    g = kp,  ctrl = q_ref - o + (kd / kp) dq_ref + tau_ff / kp        (kp > 0: a position servo)
    g = kd,  ctrl = dq_ref + tau_ff / kd                               (kp = 0, kd > 0: damping)
    g = 1,   ctrl = tau_ff                                             (kp = kd = 0: torque only)

which makes ``force`` the law above. MuJoCo has no gains per ``MjData``: a :class:`Drives` sets them in the model, so
one drives a model at a time (a new one puts the model's own gains back).

**Over the control period** the controls are interpolated linearly between two commands' (substep ``i`` of ``n``
gets ``previous + (i + 1) / n (new - previous)``, the last exactly the new one): the references and torques move on
a line, as mc_mujoco feeds its servos. A command whose gains differ from the last one's applies from the first substep
on (a change of the control law: the old references under the new gains are neither command). Damping (Unitree's
damping mode, the stack's safety layer's command: ``kp`` all 0, ``kd`` > 0) is such a command.

**On the bus** a command can arrive ``command_delay`` control periods after it is written (``SimConfig.
command_delay``): until then the drives go on with the previous one, holding its last references.
"""

from __future__ import annotations

import math
from collections import deque
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from rtgait.interface.command import JointCommand

if TYPE_CHECKING:
    from rtgait.sim.model import SimModel

__all__ = ["Drives"]

_Entry = tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None, np.ndarray | None]  # q, dq, tau, kp, kd


class Drives:
    """The drives of a simulated robot's moving joints (module docstring).

    Args:
        sim: the simulated robot: its actuation (own gains, substeps), encoder offsets, motor model and delay.
        data: its MuJoCo state (the joints' velocities, for the motor model).
        q: the joint positions the drives hold at the start (rad); the velocity reference starts at 0.

    Attributes:
        n: physics substeps per control period.
        delay: control periods between :meth:`command` and the drives' applying the command.
        q, qd, tau: the references and feed-forward torques the drives apply now (rad, rad/s, N m; ``tau`` ``None``:
            none), in the controller's convention (its model's joint zeros).
        kp, kd: the gains the drives apply now (N m/rad, N m s/rad).
    """

    def __init__(self, sim: SimModel, data: mujoco.MjData, q: np.ndarray) -> None:
        actuation = sim.actuation
        self.n = actuation.substeps
        self.delay = int(sim.config.command_delay or 0)
        self._model = sim.model
        self._size = len(actuation.joint_names)
        self._offsets = sim.encoder_offsets
        self._own = (actuation.kp, actuation.kd)
        self._pending: deque[_Entry] = deque()
        self._motors = sim.motors
        if sim.motors is not None:
            ranges = sim.model.actuator_forcerange
            self._bounds = (sim.motors.bounds, *_velocities(data, sim.dof_index), ranges[:, 0], ranges[:, 1])
        self._gains(*self._own)
        if sim.motors is not None:
            sim.motors.standstill(sim.model.actuator_forcerange)
        self.q = np.array(q, dtype=float)
        self.qd = np.zeros_like(self.q)
        self.tau: np.ndarray | None = None
        self._ctrl = self._control(self.q, self.qd, None)  # the control of the period's last substep
        self._hold()

    # ----- commands ------------------------------------------------------------------------------------------------
    def command(self, command: JointCommand) -> None:
        """The controller's command for the coming control period (module docstring), applied now or, with a
        delay, ``delay`` periods later. Its arrays are kept, not copied, without a delay: pass new ones each period.

        Raises:
            ValueError: an array of the wrong shape or not finite, or gains that are not >= 0 (nothing changes).
        """
        if command.kp is None and command.kd is None and command.torques is None:
            entry: _Entry = (command.positions, command.velocities, None, None, None)
        else:
            entry = self._checked(command)
        if self.delay:
            kept = tuple(None if a is None else np.array(a, dtype=float) for a in entry)  # the caller may reuse them
            self._pending.append(kept)  # type: ignore[arg-type]
            if len(self._pending) <= self.delay:
                self._hold()
                return
            entry = self._pending.popleft()
        self._apply(*entry)

    def _checked(self, command: JointCommand) -> _Entry:
        """``command``'s arrays, checked: shapes ``(n,)``, finite values, gains >= 0."""
        n = self._size
        return (
            _array(command.positions, n, "positions", "rad"),
            _array(command.velocities, n, "velocities", "rad/s"),
            _array_or_none(command.torques, n, "torques", "N m"),
            _array_or_none(command.kp, n, "kp", "N m/rad", gain=True),
            _array_or_none(command.kd, n, "kd", "N m s/rad", gain=True),
        )

    def _apply(
        self, q: np.ndarray, qd: np.ndarray, tau: np.ndarray | None, kp: np.ndarray | None, kd: np.ndarray | None
    ) -> None:
        """Make a checked command the drives' own for this control period."""
        kp = self._own[0] if kp is None else kp
        kd = self._own[1] if kd is None else kd
        changed = not (_same(kp, self.kp) and _same(kd, self.kd))
        if changed:
            self._gains(kp.copy(), kd.copy())
        self.q, self.qd, self.tau = q, qd, tau
        previous, self._ctrl = self._ctrl, self._control(q, qd, tau)
        if changed:
            self._hold()
        else:
            self._ctrl_previous = previous
            if self.n > 1:
                self._ctrl_step = (self._ctrl - previous) * (1.0 / self.n)

    def _hold(self) -> None:
        """The control period's substeps all at the current control (no command this period, or new gains)."""
        self._ctrl_previous = self._ctrl
        self._ctrl_step = np.zeros(self._size)

    def _gains(self, kp: np.ndarray, kd: np.ndarray) -> None:
        """Set the drives' gains in the model's actuators (module docstring's ``g`` and bias) and the coefficients of
        the control."""
        self.kp, self.kd = kp, kd
        servo = kp > 0.0
        gain = np.where(servo, kp, np.where(kd > 0.0, kd, 1.0))
        model = self._model
        model.actuator_gainprm[:, 0] = gain
        model.actuator_biasprm[:, 1] = -kp
        model.actuator_biasprm[:, 2] = -kd
        self._all_servos = bool(servo.all())
        self._position = servo.astype(float)  # 1 where the control holds a position, else 0
        self._lead = kd / gain  # s where kp > 0; 1 in damping; 0 for torque only
        self._per_gain = 1.0 / gain
        offsets = self._offsets
        self._shift = None if offsets is None else self._position * offsets

    def _control(self, q: np.ndarray, qd: np.ndarray, tau: np.ndarray | None) -> np.ndarray:
        """The actuators' control for references ``q``, ``qd`` and torques ``tau`` under the current gains."""
        # Every drive a position servo: q itself (1 q, the same bits, one product less).
        ctrl = q + self._lead * qd if self._all_servos else self._position * q + self._lead * qd
        if self._shift is not None:  # the drives servo their encoders: the joint goes to q_ref - o
            ctrl -= self._shift
        if tau is not None:
            ctrl += tau * self._per_gain
        return ctrl

    @property
    def damping(self) -> bool:
        """Whether the drives hold no position (``kp`` all 0): damping, or torque only."""
        return not self.kp.any()

    # ----- physics -------------------------------------------------------------------------------------------------
    def apply(self, i: int, ctrl: np.ndarray) -> None:
        """Write the actuators' controls for physics substep ``i`` (0 to ``n - 1``) into ``ctrl`` (e.g.
        ``data.ctrl``) and, with the motor model, their force ranges at the joints' velocities now."""
        if i == self.n - 1:
            ctrl[:] = self._ctrl  # the last substep reaches the new command exactly
        else:
            np.add(self._ctrl_previous, (i + 1) * self._ctrl_step, out=ctrl)
        if self._motors is not None:
            bounds, qvel, index, lower, upper = self._bounds
            bounds(qvel if index is None else qvel[index], lower, upper)


def _velocities(data: mujoco.MjData, index: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """The joints' velocities in ``data.qvel``: a view when their addresses follow one another (no index needed),
    else ``qvel`` and the index to take."""
    start = int(index[0])
    if np.array_equal(index, np.arange(start, start + len(index))):
        return data.qvel[start : start + len(index)], None
    return data.qvel, index


def _array(value: object, n: int, name: str, unit: str, gain: bool = False) -> np.ndarray:
    """``value`` as an array of ``n`` finite floats (and, for a ``gain``, all >= 0), or ``ValueError`` naming the
    command's field ``name`` in ``unit``.

    The values' sum, as Python floats, is finite when they all are (a NaN or an infinity makes it NaN or infinite):
    the check costs a fifth of ``np.isfinite(array).all()``'s, and only a sum that overflows is looked at value by
    value."""
    array = np.asarray(value, dtype=float)
    if array.shape == (n,):
        values = array.tolist()
        finite = math.isfinite(sum(values)) or bool(np.isfinite(array).all())
        if finite and not (gain and n > 0 and min(values) < 0.0):
            return array
    rule = "finite gains >= 0" if gain else "finite values"
    raise ValueError(f"JointCommand.{name} must be {n} {rule} ({unit}), got {value!r}")


def _array_or_none(value: object, n: int, name: str, unit: str, gain: bool = False) -> np.ndarray | None:
    """:func:`_array`, ``None`` passing."""
    return None if value is None else _array(value, n, name, unit, gain)


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two gain arrays are equal (the same object, most ticks)."""
    return a is b or np.array_equal(a, b)
