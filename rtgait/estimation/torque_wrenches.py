"""The ground's wrench on each sole from the legs' joint torques, for a robot without foot force sensors (the G1's):
the legs' inverse dynamics with the measured motion, the residual torque mapped through the sole's Jacobian, and a
first-order low-pass.

**Dynamics.** A leg's joints obey ``M_l q'' + h_l = tau_l + J^T F`` (``M_l q''`` the inertia of the leg and of the
rotors, ``h_l`` its gravity, velocity and base-motion terms, ``J`` the sole frame's 6 x n Jacobian with respect to
the leg's joints, ``F`` the ground's wrench on the sole in that frame). With ``tau_id = M_l q'' + h_l``, the inverse
dynamics of the leg's measured motion with the sole free (:meth:`RobotKinematics.leg_dynamics
<rtgait.estimation.kinematics.RobotKinematics.leg_dynamics>`), a six-joint leg gives

    F = J^-T (tau_id - tau_l)                                                                (N, N m)

(least squares for other legs; :func:`~rtgait.estimation.sole_wrenches.torque_wrenches`). The motion, each tick of
``dt``: the joints' accelerations ``q'' = (q'_k - q'_k-1) / dt`` from the encoders' velocities; the base's angular
velocity ``w`` (the gyro, turned into the base frame) and acceleration ``w' = (w_k - w_k-1) / dt``; the base
origin's specific force from the accelerometer's ``f_I`` (base frame) at the IMU's point ``p_I``, moving at ``p_I'``
relative to the base:

    f_B = f_I - w' x p_I - w x (w x p_I) - 2 w x p_I'

(the IMU's own acceleration relative to the base, ``p_I''``, is left out: nothing for an IMU on the base's body, as
the G1's on its pelvis). The accelerometer's and the finite differences' values are means over the period (the
accelerometer's reading is, :mod:`rtgait.estimation.velocity_filter`), the torques' of the instant: the residual
then errs by the torque's change over half a period.

Leaving the dynamics out (``tau_id`` the gravity torques alone, the quasi-static estimate) errs on a swinging G1 leg
by 16 N RMS and up to 33 N, and by up to 86 N as the leg stops after an impact (``docs/estimation.md``); the base's
angular acceleration matters most at impacts, when the pelvis pitches and rolls with the swing leg hanging from it.

**Filters** (the default, ``momentum=False``). First-order low-passes, ``y_k = beta y_k-1 + (1 - beta) x_k``, ``beta =
exp(-2 pi f_c dt)``, one for each of the residual's two noises, whose spectra differ, and one for each use of the
result. The accelerations (the joints' ``q''`` and the base's ``w'``) are differences of noisy velocities: their noise,
``sqrt(2) sigma_v / dt`` per tick, rises with frequency (blue), and on G1 (0.02 rad/s at 500 Hz) it is most of the raw
wrench's (17 of 19 N RMS of vertical force on a swinging leg); the measured torques' noise is white (1 N m each: 7 N
RMS). The accelerations are low-passed at :data:`DEFAULT_ACCELERATION_CUTOFF` (a 5.3 ms time constant), the base
origin's specific force ``f_B`` (its linear acceleration) with them: the leg's balance holds between terms filtered
alike, where the accelerometer's jolt taken at once against the joints' filtered answer to it read as a force on a
free foot (G1 pushed back, its stance foot slapping the floor: up to 94 N, a touch-down in the air). The residual
wrench is then low-passed twice: at :data:`DEFAULT_WRENCH_CUTOFF` (5.3 ms) for the wrench the estimator reports (the
feet's forces, centres of pressure, ZMP and the anchors' weights), and at :data:`DEFAULT_CONTACT_CUTOFF` (2.7 ms) for
the forces the contact detection reads (:attr:`TorqueWrenches.contact_forces`): a lift-off's drop of the ground's force,
from tens of newtons to nothing in a tick, goes through with half the lag (one 30 Hz filter held a lift-off's decaying
estimate above the release force for up to 20 ms). On G1's fig8 at its described noise the swinging leg's vertical
contact force errs by 5.0 N RMS (three seeds), against 5.3 N for one 30 Hz filter on the unfiltered accelerations'
wrench. The reported wrench keeps the slower filter: the feet's forces, centres of pressure and the ZMP come out
smoother (on a backward walk of G1 in the shadow of a walk on the truth, the ZMP errs by 14.6 mm RMS with it, 16.9 mm
with the faster one). The accelerations pass two filters and the torques one: a torque that changes in a tick reads at
once, the acceleration that answers it lags (a swing hip's 20 N m feed-forward step read as 67-88 N on the free foot,
``docs/robots.md``). The observer below puts one filter on both.

**Momentum observer** (``momentum=True``, not the default; De Luca's generalized-momentum residual, the contact
estimator of torque-sensing robots). With ``p = M_l v`` the leg's rows of the generalized momentum (``v`` the base's
angular and the joints' velocities) and ``M_l' = C + C^T``, ``p' = tau_l + J^T F - n + M_l' v`` (``n`` the Coriolis,
gravity and base-acceleration terms), and the observer ``r = K (p - p(0) - integral(tau_l - n + M_l' v + r) dt)``
tends to ``J^T F`` as ``K / (s + K)`` without an acceleration. Over one period, with ``M_l' v`` the change of ``M_l``
times the period's mean velocity (trapezoid), ``(p_k - p_k-1) / dt - M_l' v = M_l (v_k - v_k-1) / dt`` exactly
(``M_l`` the period's mean inertia, here the tick's): the observer is the residual above with the finite-differenced
accelerations *unfiltered*, the torque's integral over the period (the trapezoid, ``(tau_k + tau_k-1) / 2``, what
the velocities' difference spans) and one first-order low-pass ``K = 2 pi cutoff`` on everything, whose output is
both the reported wrench and :attr:`TorqueWrenches.contact_forces`. A torque step that accelerates a free leg then
moves the momentum by as much as the torque's integral and reads as nothing (``tests/estimation/
test_torque_wrenches.py``): the filtered residual ("Filters" below) filters the accelerations and not the torque, so
the step passes at once and the acceleration that answers it lags. On G1's fig8 at its own gains (model error 1,
sensor seed 1; the run's estimator inputs replayed, the simulator's contact forces as truth) the largest vertical
force read on a swinging foot (from 30 ms after lift-off to the touch-down) was 110 N median over 9 swings, 170 N at
most, with the filtered residual, 15.6 and 17.5 N with the observer (its error 5.2 N RMS in swing; the landing
threshold is 26.2 N); the observer with the instant's torque instead of the trapezoid read 28 and 49 N, at 60 Hz 25
and 32 N (8.5 N RMS). In closed loop it removes the false touch-downs, yet G1's walks at its own gains lean on them
(its swing foot ends its swing above the floor) and fall sooner with it: it is not the default
(``docs/estimation.md``, "Contact from joint torques: the momentum observer").

**Friction.** A drive that measures its torque at the motor (G1's ``tau_est``, from the current) reads the torque
before its gears' friction: the links get ``tau_l = tau_m - tau_f(q')``. Left in, the friction of a swinging leg's
joints (1.2 to 2.4 N m each on G1) reads as a contact force of tens of newtons (39 N at a fig8 swing's end, beyond
the landing threshold: a touch-down detected while the foot is still 30 mm up). With ``friction`` the residual takes
``tau_m - tau_f(q')``, ``tau_f`` the identified friction at the encoders' velocities
(:class:`~rtgait.estimation.joint_friction.JointFriction`); a joint at rest keeps an unknown share within ``+-F_c``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from rtgait.estimation.joint_friction import JointFriction
from rtgait.estimation.kinematics import RobotKinematics
from rtgait.estimation.sole_wrenches import SoleWrench, torque_wrenches

__all__ = ["DEFAULT_ACCELERATION_CUTOFF", "DEFAULT_CONTACT_CUTOFF", "DEFAULT_WRENCH_CUTOFF", "TorqueWrenches"]

DEFAULT_WRENCH_CUTOFF = 30.0
"""Cut-off of the low-pass on the torque-estimated wrenches (Hz): a 5.3 ms time constant (module docstring)."""
DEFAULT_CONTACT_CUTOFF = 60.0
"""Cut-off of the low-pass on the forces the contact detection reads (Hz): 2.7 ms (module docstring)."""
DEFAULT_ACCELERATION_CUTOFF = 30.0
"""Cut-off of the low-pass on the finite-differenced accelerations (Hz): a 5.3 ms time constant (module docstring)."""

Vector = tuple[float, float, float]

_PERIODS_KEPT = 8
"""How many periods' values are kept: a clock's rounding gives a few periods (three on the simulator's 2 ms ticks),
which alternate; more are forgotten all at once."""


class _Period(NamedTuple):
    """A period's values: the rate ``1 / dt`` (1/s), as a number and an array of the joints' size; the accelerations'
    low-pass weights ``(beta, 1 - beta)`` as rows of that size and its ``beta``; the reported wrench's and the contact
    forces' ``beta``."""

    rate: float
    rates: np.ndarray
    weights: np.ndarray
    acceleration_beta: float
    beta: float
    contact_beta: float


class TorqueWrenches:
    """The soles' wrenches from the legs' joint torques (module docstring), one :meth:`update` a tick.

    Args:
        kinematics: the robot's kinematics, updated for the tick before :meth:`update`.
        cutoff: the reported wrench's low-pass's cut-off (Hz), > 0; ``inf``: no filter.
        acceleration_cutoff: the accelerations' low-pass's cut-off (Hz), > 0; ``inf``: no filter.
        contact_cutoff: the contact forces' low-pass's cut-off (Hz), > 0; ``inf``: no filter.
        friction: the joints' friction the measured (motor) torques carry and the links do not get (module
            docstring, "Friction"); ``None``: none, the measured torques act on the links.
        momentum: the generalized-momentum observer (module docstring, "Momentum observer"): the unfiltered
            accelerations, the torques' mean over the period and one low-pass at ``cutoff`` for both the reported
            wrench and :attr:`contact_forces` (``acceleration_cutoff`` and ``contact_cutoff`` unused); ``False``
            (default): the filtered accelerations' residual ("Filters").

    Raises:
        ValueError: a cut-off that is not > 0, or legs that are not two of as many joints.
    """

    def __init__(
        self, kinematics: RobotKinematics, cutoff: float = DEFAULT_WRENCH_CUTOFF,
        acceleration_cutoff: float = DEFAULT_ACCELERATION_CUTOFF, contact_cutoff: float = DEFAULT_CONTACT_CUTOFF,
        friction: JointFriction | None = None, momentum: bool = False,
    ) -> None:  # fmt: skip
        if not cutoff > 0.0:
            raise ValueError(f"the wrench filter's cut-off must be > 0 Hz, got {cutoff}")
        if not acceleration_cutoff > 0.0:
            raise ValueError(f"the accelerations' filter cut-off must be > 0 Hz, got {acceleration_cutoff}")
        if not contact_cutoff > 0.0:
            raise ValueError(f"the contact forces' filter cut-off must be > 0 Hz, got {contact_cutoff}")
        self.momentum = bool(momentum)
        if self.momentum:  # one filter, the observer's, on both sides of the dynamics and for both uses
            acceleration_cutoff, contact_cutoff = math.inf, cutoff
        self.acceleration_cutoff, self.contact_cutoff = float(acceleration_cutoff), float(contact_cutoff)
        legs = [list(leg) for leg in kinematics.leg_joints]
        if len(legs) != 2 or len(legs[0]) != len(legs[1]) or not legs[0]:
            raise ValueError(f"leg_joints must be two legs of as many joints, got {kinematics.leg_joints!r}")
        self.kinematics, self.cutoff = kinematics, float(cutoff)
        if friction is not None and friction.coulomb.shape != (kinematics.joint_count,):
            raise ValueError(f"the joint friction must have one value per joint ({kinematics.joint_count}), got "
                             f"{friction.coulomb.shape[0]}")  # fmt: skip
        self.friction = friction
        # One slice of the joint torques for both legs when the right leg's joints follow the left's, else indices.
        both = legs[0] + legs[1]
        consecutive = both == list(range(both[0], both[0] + len(both)))
        self._legs = slice(both[0], both[0] + len(both)) if consecutive else np.array(both)
        self._leg_shape = (2, len(legs[0]))
        self._leg_dynamics = kinematics.leg_dynamics
        n = kinematics.joint_count
        self._velocities = np.zeros(n)
        self._at_rest = np.zeros(n)  # the first tick's joint accelerations
        # The joints' accelerations: row 0 the low-passed ones (the filter's state), row 1 this tick's difference; the
        # rows' weights in the low-pass, ``(beta, 1 - beta)``, and the rate ``1 / dt`` as arrays for the period.
        self._motion = np.zeros((2, n))
        self._filtered_joints, self._difference = self._motion
        self._filter_accelerations = self.acceleration_cutoff != math.inf
        self._periods: dict[float, _Period] = {}
        self.reset()

    def reset(self) -> None:
        """Forget the state: the next update starts without accelerations or filter."""
        self._angular: Vector | None = None
        self._state: tuple[SoleWrench, SoleWrench] | None = None
        self.contact_forces: tuple[Vector, Vector] = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        """The soles' forces low-passed at ``contact_cutoff`` for the contact detection (N, sole frames)."""
        self._filtered_angular: Vector | None = None  # the low-passed angular acceleration; None: not started
        self._filtered_origin: Vector | None = None  # the base origin's low-passed specific force
        self._torques: np.ndarray | None = None  # the last tick's link torques, for the period's mean

    def _period(self, dt: float) -> _Period:
        """The rate and the filters' weights for the period ``dt`` (s), kept for the next ticks of that period."""
        periods = self._periods
        if len(periods) >= _PERIODS_KEPT:
            periods.clear()
        rate, n = 1.0 / dt, self._velocities.size
        accel_beta = math.exp(-2.0 * math.pi * self.acceleration_cutoff * dt)
        periods[dt] = period = _Period(
            rate, np.full(n, rate), np.array([np.full(n, accel_beta), np.full(n, 1.0 - accel_beta)]), accel_beta,
            math.exp(-2.0 * math.pi * self.cutoff * dt), math.exp(-2.0 * math.pi * self.contact_cutoff * dt),
        )  # fmt: skip
        return period

    @staticmethod
    def _base_acceleration(
        angular_acceleration: Vector, angular_velocity: Vector, specific_force: Vector, imu_position: Vector,
        imu_velocity: Vector,
    ) -> tuple[float, float, float, float, float, float]:  # fmt: skip
        """The base origin's specific force and the base's angular acceleration (base frame): ``f_B = f_I - w' x p_I -
        w x (w x p_I) - 2 w x p_I'`` (module docstring)."""
        ax, ay, az = angular_acceleration
        wx, wy, wz = angular_velocity
        (ox, oy, oz), (ux, uy, uz) = imu_position, imu_velocity
        cx, cy, cz = wy * oz - wz * oy, wz * ox - wx * oz, wx * oy - wy * ox  # w x p_I
        fx, fy, fz = specific_force
        fx -= ay * oz - az * oy + wy * cz - wz * cy + 2.0 * (wy * uz - wz * uy)
        fy -= az * ox - ax * oz + wz * cx - wx * cz + 2.0 * (wz * ux - wx * uz)
        fz -= ax * oy - ay * ox + wx * cy - wy * cx + 2.0 * (wx * uy - wy * ux)
        return fx, fy, fz, ax, ay, az

    def update(
        self, dt: float, joint_velocities: np.ndarray, torques: np.ndarray, angular_velocity: Vector,
        specific_force: Vector, imu_position: Vector, imu_velocity: Vector,
    ) -> tuple[SoleWrench, SoleWrench]:  # fmt: skip
        """The left and right soles' wrenches (sole frames, about their origins) after ``dt`` (s).

        Args:
            dt: time since the last update (s); ``<= 0`` (a repeated reading) returns the last wrenches.
            joint_velocities: the encoders' joint velocities (rad/s), the robot's joint order.
            torques: the joints' measured torques (N m), the robot's joint order.
            angular_velocity: the base's angular velocity (rad/s, base frame).
            specific_force: the accelerometer's specific force turned into the base frame (m/s^2).
            imu_position, imu_velocity: the IMU's point and its velocity relative to the base (m, m/s, base frame).
        """
        state = self._state
        if state is not None and dt <= 0.0:
            return state
        wx, wy, wz = angular_velocity
        origin = None  # the base origin's low-passed specific force, where the accelerations are filtered
        if state is None:  # no earlier tick: the motion's accelerations taken as zero
            ax = ay = az = 0.0
            accelerations = self._at_rest
        else:
            period = self._periods.get(dt) or self._period(dt)
            accelerations = self._difference
            np.subtract(joint_velocities, self._velocities, out=accelerations)
            accelerations *= period.rates
            rate = period.rate
            px, py, pz = self._angular  # type: ignore[misc]
            ax, ay, az = (wx - px) * rate, (wy - py) * rate, (wz - pz) * rate
            if self._filter_accelerations:
                # The base origin's specific force is the base's linear acceleration (less gravity): it goes through
                # the joints' and the angular accelerations' filter, or the balance of a leg whose hip jerks (the
                # accelerometer's jolt at once, the joints' answer to it filtered) reads as a force on a free foot.
                fx, fy, fz, _, _, _ = self._base_acceleration(
                    (ax, ay, az), angular_velocity, specific_force, imu_position, imu_velocity
                )
                filtered, angular = self._filtered_joints, self._filtered_angular
                if angular is None:  # the first difference starts the filter
                    filtered[:] = accelerations
                else:
                    # filtered <- beta filtered + (1 - beta) difference: both rows weighted at once, in place.
                    self._motion *= period.weights
                    filtered += accelerations
                    b = period.acceleration_beta
                    c = 1.0 - b
                    gx, gy, gz = angular
                    ax, ay, az = b * gx + c * ax, b * gy + c * ay, b * gz + c * az
                    sx, sy, sz = self._filtered_origin  # type: ignore[misc]
                    fx, fy, fz = b * sx + c * fx, b * sy + c * fy, b * sz + c * fz
                self._filtered_angular = (ax, ay, az)
                self._filtered_origin = origin = (fx, fy, fz)
                accelerations = filtered  # the legs are handed the filtered ones
        self._velocities[:] = joint_velocities
        self._angular = angular_velocity
        if origin is None:
            base = self._base_acceleration((ax, ay, az), angular_velocity, specific_force, imu_position, imu_velocity)
        else:
            base = (*origin, ax, ay, az)
        jacobians, needed = self._leg_dynamics(angular_velocity, base, accelerations)
        if self.friction is not None:  # the torque that reaches the links: the motors' less their gears' friction
            torques = torques - self.friction.torques(joint_velocities)
        torques = torques[self._legs].reshape(self._leg_shape)
        if self.momentum:  # the torques' mean over the period the velocities' difference spans (trapezoid)
            last = self._torques
            self._torques = torques.copy()
            if last is not None and state is not None:
                torques = 0.5 * (torques + last)
        left, right = torque_wrenches(jacobians, needed, torques)
        contact = (left, right)
        if state is None:
            self.contact_forces = (contact[0][0:3], contact[1][0:3])
        if state is not None and not self.momentum:  # the observer's contact forces are the reported wrench's
            b = period.contact_beta
            c = 1.0 - b
            (l0, l1, l2), (r0, r1, r2) = self.contact_forces
            (m0, m1, m2, *_), (n0, n1, n2, *_) = contact
            self.contact_forces = (
                (b * l0 + c * m0, b * l1 + c * m1, b * l2 + c * m2),
                (b * r0 + c * n0, b * r1 + c * n1, b * r2 + c * n2),
            )
        if state is not None and self.cutoff != math.inf:
            b = period.beta
            c = 1.0 - b
            (l0, l1, l2, l3, l4, l5), (r0, r1, r2, r3, r4, r5) = state
            left = (b * l0 + c * left[0], b * l1 + c * left[1], b * l2 + c * left[2], b * l3 + c * left[3],
                    b * l4 + c * left[4], b * l5 + c * left[5])  # fmt: skip
            right = (b * r0 + c * right[0], b * r1 + c * right[1], b * r2 + c * right[2], b * r3 + c * right[3],
                     b * r4 + c * right[4], b * r5 + c * right[5])  # fmt: skip
        self._state = (left, right)
        if self.momentum:
            self.contact_forces = (left[0:3], right[0:3])
        return left, right
