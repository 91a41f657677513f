"""The hip strategy: the upper body's lean as a reaction wheel, for the centroidal moment pivot beyond the sole.

Once the DCM law's commanded ZMP reaches the support polygon's edge, the feet can do no more: a DCM outside the
polygon diverges whatever the ZMP (:mod:`rtgait.core.laws.feedback`). What moves the ground reaction's line of action
beyond the sole is a rate of angular momentum about the COM. With ``L`` the centroidal angular momentum (N m s),
the horizontal COM dynamics at height ``z_c`` become ``c'' = w^2 (c - p) + (z x L') / (m z_c)``, i.e. the
pendulum's with the ZMP ``p`` replaced by the centroidal moment pivot (CMP)

    cmp = p - (z x L') / (m g)        (m)                                                    (1)

and the DCM ``xi = c + c' / w`` obeys ``xi' = w (xi - cmp)``.

The upper body (pelvis and torso, rotated about the hips while the whole-body IK holds the COM and the feet)
makes that rate. Its lean ``lam`` is a horizontal vector (rad) in the heading frame (forward, left): the upper
body's top tilts by ``|lam|`` toward ``lam``. Leaning at acceleration ``lam''`` changes the angular momentum by
``L' = -I (z x lam'')`` with ``I`` the lean's effective inertia about each axis (kg m^2: the centroidal momentum
of a unit lean rate, :func:`rtgait.robot.lean.lean_inertia`), so by (1) the CMP moves toward the acceleration:

    cmp - p = I lam'' / (m g)                                                                 (2)

Law, per heading axis, at each control tick of period ``dt``:

* *Lean* while the DCM law is limited by more than ``deadband`` on that axis (its shortfall ``s = p_law - p_cmd``,
  the law's ZMP minus the one the polygon allows): at ``max_acceleration`` (rad/s^2; the hips' torque budget over
  ``I``) toward ``s``. Bang-bang, because what a lean recovers is ``int lam'' e^{-w t} dt`` (below): every tick
  spent below the limit while the DCM diverges is capacity lost (the shortfall itself grows only as the DCM runs
  away, so a lean that asks the CMP for ``s`` alone comes too late).
* *Stop* when nothing more is asked while the lean still moves away from upright: at ``max_acceleration``, so
  that a push the feet and a step soon answer leans no farther than it needed.
* *Return* otherwise: ``lam'' = -w_r^2 lam - 2 w_r lam'``, critically damped at ``return_rate`` ``w_r`` (1/s),
  at most ``return_acceleration``: slow, so that the CMP it costs, ``I w_r^2 lam / (m g)``, stays a few
  millimetres the feet absorb.
* *Range*: ``|lam| <= max_lean`` on each axis, braking at ``max_acceleration`` in time to stop at the limit.

What the lean buys. Integrating ``xi' = w (xi - cmp)`` against ``e^{-w t}``, a lean profile recovers a DCM
offset of ``(I / (m g)) w int lam'' e^{-w t} dt = (I w / (m g)) w int lam e^{-w t} dt``: at most ``I max_lean /
(m z_c)`` for a lean made at once and held, i.e. an impulse of ``w I max_lean / z_c`` (N s) beyond what the sole
stands; less with the acceleration limit (a bang-bang lean to ``max_lean`` in ``2 t_1`` gives ``(tau / w)(1 -
e^{-w t_1})^2 / z_c`` with ``tau = I max_acceleration``). The upper body then returns while the feet hold the
DCM.

*Servo*: on drives whose position servos are soft for the upper body (a robot at its own low gains), the lean above
is the target of a reference shaped by the servo's own dynamics (:class:`~rtgait.core.laws.servo_reference.
ServoReference`, at ``servo_bandwidth`` ``sqrt(kp / I)`` per axis): the lean sent to the IK is that reference, its
acceleration at most ``min(w_s^2 max_lean, max_acceleration)`` and its rate ``w_s max_lean``, and the CMP shift (2)
is the reference's acceleration, the one the servo can make, not the bang-bang one it could not follow.

Pure float arithmetic, explicit state (:meth:`HipStrategy.reset`), a few microseconds per tick.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

from rtgait.core.laws.servo_reference import ServoReference

__all__ = ["HipStrategy", "HipStrategyLimits", "LeanOutput"]


@dataclass(frozen=True)
class HipStrategyLimits:
    """The lean's limits and rates (SI units); see the module docstring.

    Attributes:
        inertia: effective inertia of the lean about the lateral axis (a forward lean) and about the forward axis
            (a sideways lean), ``(I_forward, I_lateral)`` (kg m^2).
        max_acceleration: largest lean acceleration ``(forward, lateral)`` (rad/s^2).
        max_lean: largest lean on each axis (rad).
        deadband: shortfall of the DCM law's ZMP the feet's own limits leave unanswered before the upper body
            leans (m): the law saturates for a few ticks at landings, which a walk does not need a lean for.
        return_rate: the return's natural frequency ``w_r`` (1/s).
        return_acceleration: largest acceleration of the return (rad/s^2).
        servo_bandwidth: the closed-loop natural frequency ``sqrt(kp / I)`` (1/s) of the joints that make the lean
            ``(forward, lateral)``, whose servo-shaped reference is sent (module docstring, *Servo*); ``None``: the
            lean itself (stiff servos that follow it).
    """

    inertia: tuple[float, float]
    max_acceleration: tuple[float, float]
    max_lean: float = 0.25
    deadband: float = 0.01
    return_rate: float = 2.0
    return_acceleration: float = 2.0
    servo_bandwidth: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        for name in ("inertia", "max_acceleration", "servo_bandwidth"):
            pair = getattr(self, name)
            if pair is None and name == "servo_bandwidth":
                continue
            if len(pair) != 2 or not all(math.isfinite(v) and v > 0.0 for v in pair):
                raise ValueError(f"HipStrategyLimits.{name} must be two finite values > 0, got {pair!r}")
        for name, high in (("max_lean", 1.0), ("deadband", 0.5), ("return_rate", 100.0),
                           ("return_acceleration", 1e4)):  # fmt: skip
            value = getattr(self, name)
            if not (math.isfinite(value) and 0.0 < value <= high) and not (name == "deadband" and value == 0.0):
                raise ValueError(f"HipStrategyLimits.{name} must be within (0, {high}], got {value}")

    def recoverable_offset(self, mass: float, omega: float, gravity: float = 9.81) -> tuple[float, float]:
        """How far past the sole's edge (m) the DCM may be and still be brought back by the lean alone, per heading
        axis ``(forward, lateral)``: the bang-bang lean of the module docstring to ``max_lean`` at
        ``max_acceleration`` ``a``, ``(I a / (m g)) (1 - e^{-w t_1})^2`` with ``t_1 = sqrt(max_lean / a)``.

        An upper bound: the lean starts at once and the return is free. Times ``m w`` it is the impulse (N s) the
        lean adds to what the sole alone withstands. ``mass`` in kg, ``omega`` the pendulum's ``w`` (1/s),
        ``gravity`` in m/s^2.
        """
        if not (math.isfinite(omega) and omega > 0.0):
            raise ValueError(f"omega must be > 0 1/s, got {omega}")
        if not (math.isfinite(mass) and mass > 0.0):
            raise ValueError(f"mass must be > 0 kg, got {mass}")
        offsets = []
        for inertia, acceleration in zip(self.inertia, self.max_acceleration, strict=True):
            t1 = math.sqrt(self.max_lean / acceleration)
            offsets.append(inertia * acceleration / (mass * gravity) * (1.0 - math.exp(-omega * t1)) ** 2)
        return offsets[0], offsets[1]


class LeanOutput(NamedTuple):
    """One tick of :class:`HipStrategy` (world frame).

    Attributes:
        lean: the upper body's lean as a rotation vector (rad), horizontal: rotate the upright torso and pelvis
            by it (``(0, 0, 0)``: upright).
        cmp_offset: the CMP shift the lean's acceleration makes by eq. (2) (m).
        leaning: whether the lean is answering a shortfall at this tick (else returning or at rest).
    """

    lean: tuple[float, float, float]
    cmp_offset: tuple[float, float]
    leaning: bool


_UPRIGHT = LeanOutput((0.0, 0.0, 0.0), (0.0, 0.0), False)


class HipStrategy:
    """The lean law of the module docstring for a robot of ``mass`` (kg), ticked every ``dt`` (s)."""

    def __init__(self, limits: HipStrategyLimits, mass: float, dt: float, gravity: float = 9.81) -> None:
        if not (math.isfinite(mass) and mass > 0.0):
            raise ValueError(f"mass must be > 0 kg, got {mass}")
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f"dt must be > 0 s, got {dt}")
        self.limits, self.mass, self.dt, self.gravity = limits, float(mass), float(dt), float(gravity)
        self._to_cmp = tuple(i / (mass * gravity) for i in limits.inertia)
        bandwidth = limits.servo_bandwidth
        self._servo = (
            None
            if bandwidth is None
            else tuple(
                ServoReference(w, limits.max_lean, a, dt)
                for w, a in zip(bandwidth, limits.max_acceleration, strict=True)
            )
        )
        self.reset()

    def reset(self) -> None:
        """Upright and at rest."""
        self._lean = [0.0, 0.0]  # heading frame: forward, left (rad)
        self._rate = [0.0, 0.0]  # rad/s
        for servo in self._servo or ():
            servo.reset()

    @property
    def lean(self) -> tuple[float, float]:
        """The lean in the heading frame ``(forward, left)`` (rad) after the last tick (the law's, before any servo
        reference)."""
        return self._lean[0], self._lean[1]

    @property
    def at_rest(self) -> bool:
        """Upright and still (within 1e-6 rad and rad/s)."""
        (l0, l1), (r0, r1) = self._lean, self._rate  # every tick of a walk: no generator
        law = abs(l0) < 1e-6 and abs(l1) < 1e-6 and abs(r0) < 1e-6 and abs(r1) < 1e-6
        return law and (self._servo is None or (self._servo[0].at_rest and self._servo[1].at_rest))

    def update(self, shortfall: tuple[float, float], yaw: float) -> LeanOutput:
        """One tick: the lean for the DCM law's shortfall ``p_law - p_cmd`` (m, world frame) at heading ``yaw``
        (rad). Each heading axis leans while its part of the shortfall exceeds the deadband, and returns
        otherwise: an axis with nothing asked never keeps drifting at the rate a past tick gave it."""
        sx, sy = shortfall
        limits = self.limits
        band = limits.deadband
        if abs(sx) <= band and abs(sy) <= band and self.at_rest:
            return _UPRIGHT
        c, s = math.cos(yaw), math.sin(yaw)
        along, across = c * sx + s * sy, -s * sx + c * sy  # heading frame
        dt, max_lean, wr = self.dt, limits.max_lean, limits.return_rate
        offsets = [0.0, 0.0]
        leaning = False
        for axis, part in ((0, along), (1, across)):
            lam, rate = self._lean[axis], self._rate[axis]
            brake = limits.max_acceleration[axis]
            if abs(part) > band:  # lean: the CMP asked beyond the deadband, eq. (2)
                leaning = True
                high = brake
                acc = math.copysign(brake, part)
            elif rate * lam > 0.0:  # nothing asked while leaning farther: stop at once, the lean is not needed
                high = brake
                acc = -math.copysign(min(brake, abs(rate) / dt), rate)
            else:  # return, critically damped
                high = limits.return_acceleration
                acc = -wr * wr * lam - 2.0 * wr * rate
            acc = -high if acc < -high else (high if acc > high else acc)
            # Brake in time, and only as hard as needed: stepped as below (rate, then angle), a deceleration ``a``
            # from rate ``r`` stops within ``r^2 / (2 a) - |r| dt / 2``; solved for the room left to the limit, that
            # is the deceleration that comes to rest at the limit. Braking starts once it needs 90 % of the largest,
            # so that it never needs more (a late brake would end in a hard stop at the limit).
            if rate != 0.0:
                room = max_lean - lam * math.copysign(1.0, rate)
                needed = rate * rate / (2.0 * max(room + 0.5 * abs(rate) * dt, 1e-12))
                if needed >= 0.9 * brake:
                    acc = -math.copysign(min(needed, brake), rate)
            rate += acc * dt
            lam += rate * dt
            if abs(lam) >= max_lean:
                lam = math.copysign(max_lean, lam)
                rate = 0.0
            self._lean[axis], self._rate[axis] = lam, rate
            offsets[axis] = self._to_cmp[axis] * acc
        sent = self._lean
        if self._servo is not None:  # what the soft servos can follow, and the CMP its acceleration makes
            sent = [servo.step(target) for servo, target in zip(self._servo, self._lean, strict=True)]
            offsets = [k * servo.acceleration for k, servo in zip(self._to_cmp, self._servo, strict=True)]
        # Heading frame -> world: a lean toward the heading frame's u = (forward, left) rotates about z x u.
        fx = c * sent[0] - s * sent[1]
        fy = s * sent[0] + c * sent[1]
        ox, oy = offsets
        return LeanOutput((-fy, fx, 0.0), (c * ox - s * oy, s * ox + c * oy), leaning)
