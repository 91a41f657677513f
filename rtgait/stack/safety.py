"""The stack's safety layer: joint limits on every command, a watchdog on the readings and the estimate, a fall
detector, and the damping mode they put the robot in.

**Limits** (:mod:`rtgait.stack.command_limits`): every command's position, velocity and torque references within the
joints' limits, clipped ticks counted per joint.

**Watchdog**: each tick's inputs are checked before the controller acts on them; the first fault *trips* the layer
(a :class:`SafetyEvent`, and damping):

* ``stale-readings``: the readings' time stamp has not advanced for more than :attr:`SafetySettings.stale_periods`
  control periods in a row (a sensor bus or driver that stopped; a stamp that goes back counts as not advancing);
* ``bad-readings``: a reading that is NaN or infinite (encoders, joint torques, the IMU, the force sensors, the
  stamp), or joint arrays of the wrong length;
* ``bad-estimate``: the estimator's COM, COM velocity, DCM or a foot's pose is NaN or infinite;
* ``estimate-diverged``: the estimated COM is farther (horizontally) from the nearer sole than
  :attr:`SafetySettings.com_distance` (no leg reaches that far: the estimate or the robot is lost), or it moved
  more than :attr:`SafetySettings.com_jump` in one tick (beyond what a body moves in a period);
* ``fall``: the IMU tilted more than :attr:`SafetySettings.fall_tilt` from its attitude at the first reading (the
  robot starts upright; the IMU's mounting does not matter), or the COM is lower above the lower sole than
  :attr:`SafetySettings.fall_height` of the walking COM height;
* ``error``: a ``ValueError`` (the documented bad-input errors of the estimator, controller, planner and IK) or an
  ``ArithmeticError`` raised inside the tick, its message kept;
* ``bad-command``: a joint command that is NaN or infinite.

No exception leaves the tick on bad readings: the stack catches them at its boundary
(:class:`~rtgait.stack.walking_stack.WalkingStack`).

**Damping** (Unitree's damping mode): each joint gets ``kp = 0``, ``kd`` from
:func:`rtgait.robot.joint_inertia.damping_gains`, ``dq_ref = 0`` and no torque, so that the drive applies

    tau = kd (0 - dq)                                                                  (N m)

and the joints brake instead of following references computed from inputs that can no longer be trusted; ``q_ref``
is the last finite encoder reading (ignored at ``kp = 0``, reported). Damping **latches**: once tripped, the layer
stays in damping, whatever the inputs do next, until :meth:`SafetyLayer.reset` (an operator's decision: the robot is
lifted or set back on its feet and the controller restarted).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from rtgait.interface.command import JointCommand
from rtgait.stack.command_limits import POSITION_MARGIN, CommandLimits

if TYPE_CHECKING:
    from rtgait.estimation.state import Measurement
    from rtgait.interface.joint_limits import JointLimits
    from rtgait.interface.readings import SensorReadings

__all__ = ["FAULT_KINDS", "SafetyEvent", "SafetyLayer", "SafetySettings"]

FAULT_KINDS = (
    "stale-readings", "bad-readings", "bad-estimate", "estimate-diverged", "fall", "error", "bad-command",
)  # fmt: skip
"""What trips the safety layer (module docstring)."""

_TILT_FALL = math.radians(45.0)


@dataclass(frozen=True)
class SafetySettings:
    """The watchdog's and fall detector's thresholds (module docstring).

    Attributes:
        stale_periods: the readings' stamp may stay still this many control periods in a row; one more trips (a
            5-period default: 5 ms at Talos's 1 kHz, 10 ms at G1's 500 Hz, several times any latency of the
            simulated sensors, yet short next to a step).
        position_margin: how far inside the URDF range position references are kept (rad).
        fall_tilt: the IMU's tilt from its first attitude that counts as a fall (rad): 45 degrees, the simulator's
            own fall criterion (:class:`rtgait.sim.contact.FallLimits`).
        fall_height: the COM height above the lower sole, as a fraction of the walking COM height, below which the
            robot has fallen: a COM at half its walking height is a robot on its knees or on the floor.
        com_distance: the farthest the COM may be, horizontally, from the nearer sole (m); ``None``: the robot's leg
            length (the walking COM height).
        com_jump: the most the estimated COM may move in one tick (m): at 5 m/s a COM moves 5-10 mm in a 1-2 ms
            period, and the kinematic-inertial estimators cap their anchor's jumps at 0.05 m (BWC).
    """

    stale_periods: int = 5
    position_margin: float = POSITION_MARGIN
    fall_tilt: float = _TILT_FALL
    fall_height: float = 0.5
    com_distance: float | None = None
    com_jump: float = 0.05

    def __post_init__(self) -> None:
        if not (isinstance(self.stale_periods, int) and self.stale_periods >= 1):
            raise ValueError(f"SafetySettings.stale_periods must be a whole number >= 1, got {self.stale_periods}")
        if not (math.isfinite(self.position_margin) and self.position_margin >= 0.0):
            raise ValueError(f"SafetySettings.position_margin must be >= 0 rad, got {self.position_margin}")
        if not (math.isfinite(self.fall_tilt) and 0.0 < self.fall_tilt < math.pi):
            raise ValueError(f"SafetySettings.fall_tilt must be in (0, pi) rad, got {self.fall_tilt}")
        if not 0.0 < self.fall_height < 1.0:
            raise ValueError(f"SafetySettings.fall_height must be in (0, 1), got {self.fall_height}")
        for name in ("com_distance", "com_jump"):
            value = getattr(self, name)
            if value is not None and not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"SafetySettings.{name} must be > 0 m, got {value}")


class SafetyEvent(NamedTuple):
    """A fault that tripped the safety layer.

    Attributes:
        t: the tick's time (s).
        kind: one of :data:`FAULT_KINDS`.
        detail: what was wrong, in words (an exception's type and message for ``error``).
    """

    t: float
    kind: str
    detail: str


Fault = tuple[str, str]
"""A fault found by a check, ``(kind, detail)``, before it is stamped with the tick's time."""


class SafetyLayer:
    """Limits, watchdog, fall detector and damping of one robot (module docstring).

    Args:
        limits: the joints' limits.
        damping_kd: the damping mode's velocity gain per joint (N m s/rad), ``>= 0``.
        com_height: the walking COM height (m), the fall detector's and the default ``com_distance``'s scale.
        settings: the thresholds.

    Attributes:
        damping: whether the layer has tripped (latched until :meth:`reset`).
        events: the faults that tripped it, oldest first (one per trip: a latched layer checks nothing more).
        counts: the events per kind since the layer was made.
        clip: the command limits and their clipped-tick counts.
    """

    def __init__(
        self,
        limits: JointLimits,
        damping_kd: np.ndarray,
        com_height: float,
        settings: SafetySettings | None = None,
    ) -> None:
        settings = settings or SafetySettings()
        n = len(limits.names)
        kd = np.array(damping_kd, dtype=float)
        if kd.shape != (n,) or not (np.isfinite(kd).all() and (kd >= 0.0).all()):
            raise ValueError(f"damping_kd must be {n} finite gains >= 0 N m s/rad, got {damping_kd!r}")
        if not (math.isfinite(com_height) and com_height > 0.0):
            raise ValueError(f"com_height must be > 0 m, got {com_height}")
        self.settings, self.n, self.damping_kd = settings, n, kd
        self.clip = CommandLimits(limits, settings.position_margin)
        self._com_distance = com_height if settings.com_distance is None else settings.com_distance
        self._fall_height = settings.fall_height * com_height
        self._cos_tilt = math.cos(settings.fall_tilt)
        self._zeros = np.zeros(n)
        self.events: list[SafetyEvent] = []
        self.counts: dict[str, int] = dict.fromkeys(FAULT_KINDS, 0)
        self.reset()

    def reset(self) -> None:
        """Leave damping and forget the watchdog's memory (the last stamp, the IMU's upright attitude, the last
        COM); the events, their counts and the clipped-tick counts stay. The estimator and the controller are not
        reset here: restart the walk (:meth:`rtgait.stack.walking_stack.WalkingStack.start`) from the robot as it
        is then."""
        self.damping = False
        self._stamp = -math.inf
        self._still = 0  # ticks in a row the stamp has not advanced
        self._up: tuple[float, float, float] | None = None  # the world's up axis in the IMU frame, at the start
        self._com: tuple[float, float, float] | None = None
        self._joints: np.ndarray | None = None  # the last finite encoder reading

    # ----- the watchdog --------------------------------------------------------------------------------------------
    def check_readings(self, readings: SensorReadings | None) -> Fault | None:
        """This tick's readings' fault, or ``None`` (``None`` readings: nothing to check)."""
        if readings is None:
            return None
        q, dq = readings.joint_positions, readings.joint_velocities
        if q.shape != (self.n,) or dq.shape != (self.n,):
            return "bad-readings", f"joint arrays of shape {q.shape}, {dq.shape}, not ({self.n},)"
        if not math.isfinite(_readings_sum(readings)):
            return "bad-readings", f"{_non_finite_reading(readings)} is NaN or infinite"
        self._joints = q
        t = readings.t
        if t > self._stamp:
            self._stamp, self._still = t, 0
        else:
            self._still += 1
            if self._still > self.settings.stale_periods:
                return "stale-readings", (
                    f"the readings' stamp {t:.6g} s has not advanced for {self._still} periods (more than "
                    f"{self.settings.stale_periods})"
                )
        imu = readings.imu
        if imu is not None:
            w, x, y, z = imu.orientation
            up = (2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y))  # R^T e_z
            if self._up is None:
                self._up = up
            else:
                cos = up[0] * self._up[0] + up[1] * self._up[1] + up[2] * self._up[2]
                if cos < self._cos_tilt:
                    tilt = math.degrees(math.acos(max(-1.0, min(1.0, cos))))
                    return "fall", f"the IMU tilted {tilt:.0f} degrees from its first attitude"
        return None

    def check_measurement(self, m: Measurement) -> Fault | None:
        """The estimate's fault, or ``None`` (module docstring)."""
        cx, cy, cz = m.com
        lx, ly, lz, _ = m.left.pose
        rx, ry, rz, _ = m.right.pose
        if not math.isfinite(cx + cy + cz + lx + ly + lz + rx + ry + rz + sum(m.com_vel) + sum(m.dcm)):
            return "bad-estimate", "the estimated COM, its velocity, the DCM or a sole pose is NaN or infinite"
        previous, self._com = self._com, (cx, cy, cz)
        height = cz - min(lz, rz)
        if height < self._fall_height:
            return "fall", f"the COM is {height:.3f} m above the lower sole (below {self._fall_height:.3f} m)"
        reach = min(math.hypot(cx - lx, cy - ly), math.hypot(cx - rx, cy - ry))
        if reach > self._com_distance:
            return "estimate-diverged", (
                f"the COM is {reach:.3f} m from the nearer sole (more than {self._com_distance:.3f} m)"
            )
        if previous is not None:
            jump = math.dist(previous, (cx, cy, cz))
            if jump > self.settings.com_jump:
                return "estimate-diverged", (
                    f"the COM moved {jump:.3f} m in one tick (more than {self.settings.com_jump:.3f} m)"
                )
        return None

    def trip(self, t: float, kind: str, detail: str) -> None:
        """Log the fault at ``t`` (s) and latch damping (nothing happens once latched)."""
        if self.damping:
            return
        if kind not in self.counts:
            raise ValueError(f"unknown safety fault {kind!r}: one of {', '.join(FAULT_KINDS)}")
        self.damping = True
        self.events.append(SafetyEvent(float(t), kind, detail))
        self.counts[kind] += 1

    # ----- commands ------------------------------------------------------------------------------------------------
    def limit(self, command: JointCommand) -> JointCommand:
        """``command`` within the joints' limits (:mod:`rtgait.stack.command_limits`): itself when it is."""
        clip = self.clip
        q, dq = clip.positions(command.positions), clip.velocities(command.velocities)
        tau = clip.torques(command.torques)
        if q is command.positions and dq is command.velocities and tau is command.torques:
            return command
        return command._replace(positions=q, velocities=dq, torques=tau)

    def observe_joints(self, readings: SensorReadings | None) -> None:
        """Keep the encoders of ``readings`` when they are finite (damping's ``q_ref``, once tripped)."""
        if readings is not None and readings.joint_positions.shape == (self.n,):
            q = readings.joint_positions
            if math.isfinite(float(q.sum())):
                self._joints = q

    def damping_command(self, fallback: np.ndarray) -> JointCommand:
        """The damping mode's command (module docstring): ``q_ref`` the last finite encoder reading, else
        ``fallback`` (rad)."""
        q = self._joints if self._joints is not None else fallback
        zeros = self._zeros
        return JointCommand(q.copy(), zeros.copy(), zeros.copy(), zeros.copy(), self.damping_kd.copy())

    # ----- the record ----------------------------------------------------------------------------------------------
    def summary(self) -> dict[str, object]:
        """The layer's record as JSON-ready values: whether it tripped, the events per kind, the first event, the
        clipped ticks per quantity and joint."""
        first = self.events[0] if self.events else None
        return {
            "damping": self.damping,
            "events": len(self.events),
            "counts": dict(self.counts),
            "first_event": None if first is None else first._asdict(),
            "clipped_ticks": self.clip.counted(),
        }


def _readings_sum(r: SensorReadings) -> float:
    """The sum of every number of ``r``: finite exactly when all of them are (short of an overflow to inf, itself a
    reading gone wrong). The arrays are summed as Python floats: a third of numpy's ``sum`` on a few dozen values."""
    total = r.t + sum(r.joint_positions.tolist()) + sum(r.joint_velocities.tolist())
    if r.joint_torques is not None:
        total += sum(r.joint_torques.tolist())
    imu = r.imu
    if imu is not None:
        total += sum(imu.orientation) + sum(imu.angular_velocity) + sum(imu.linear_acceleration)
    for foot in (r.left_foot, r.right_foot):
        if foot is not None:
            total += sum(foot.force) + sum(foot.torque)
    return total


def _non_finite_reading(r: SensorReadings) -> str:
    """Which reading of ``r`` is not finite (for the event's detail; the slow path of a tick that trips)."""
    fields: list[tuple[str, object]] = [
        ("the stamp", r.t), ("a joint position", r.joint_positions), ("a joint velocity", r.joint_velocities),
        ("a joint torque", r.joint_torques),
    ]  # fmt: skip
    if r.imu is not None:
        fields += [("the IMU's orientation", r.imu.orientation), ("the IMU's angular velocity", r.imu.angular_velocity),
                   ("the IMU's acceleration", r.imu.linear_acceleration)]  # fmt: skip
    for side, foot in (("left", r.left_foot), ("right", r.right_foot)):
        if foot is not None:
            fields.append((f"the {side} foot's wrench", (*foot.force, *foot.torque)))
    for name, value in fields:
        if value is not None and not np.isfinite(np.asarray(value, dtype=float)).all():
            return name
    return "a reading"  # pragma: no cover - only a sum that overflowed gets here
