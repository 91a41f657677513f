"""A complementary filter on a point's velocity: the leg kinematics' velocity at low frequencies, the integrated
accelerometer at high frequencies.

With ``v_k`` the kinematic velocity (from the joints, the stance foot held still) and ``a_k`` the accelerometer's
acceleration in the world (gravity removed), each tick of ``dt`` makes

    v^_k = alpha (v^_k-1 + dt a_k) + (1 - alpha) v_k,      alpha = exp(-dt / tau),  tau = 1 / (2 pi f_c)

``a_k`` is the mean acceleration over the period that ends at tick ``k``, what an IMU reports (its accelerometer
sampled through an anti-aliasing filter, or integrated into a velocity increment over the sample period), so
``dt a_k`` is the velocity's change over the period exactly.

which is, in continuous time, ``V^(s) = 1 / (tau s + 1) V(s) + tau s / (tau s + 1) A(s) / s``: a first-order
low-pass on the kinematics plus the complementary high-pass on the integrated acceleration. Where both sources
agree (``a = v'``) the output is the velocity itself, without lag; where they disagree, each is trusted on its own
side of the cut-off ``f_c``. The kinematic velocity carries the impacts, the foot's rolling on its edge and the
encoders' differentiation noise; the integrated acceleration drifts with the accelerometer's bias and with the
gravity that an orientation error leaks in (``b tau`` of velocity error for a bias ``b``: 4.5 mm/s for 0.1 m/s^2 at
3.5 Hz). auto_stabilizer settled on 3.5 Hz on its robots (4 Hz oscillated after impacts, 3 Hz lagged): the default
:data:`DEFAULT_VELOCITY_CUTOFF`.

Without a kinematic velocity (no foot on the ground: a flight after a push, a fall) the filter integrates the
accelerometer alone, ``v^_k = v^_k-1 + dt a_k``: the legs then measure nothing, and their velocity, held to a foot
in the air, would pull the estimate toward the swinging feet's motion.
"""

from __future__ import annotations

import math

__all__ = ["DEFAULT_VELOCITY_CUTOFF", "ComplementaryVelocity"]

DEFAULT_VELOCITY_CUTOFF = 3.5
"""Cut-off of the complementary velocity filter (Hz), auto_stabilizer's."""


class ComplementaryVelocity:
    """The filter of the module docstring, on three axes, Python floats.

    Args:
        cutoff: the cut-off frequency ``f_c`` (Hz), > 0; ``inf``: the kinematic velocity alone.
    """

    def __init__(self, cutoff: float = DEFAULT_VELOCITY_CUTOFF) -> None:
        if not cutoff > 0.0:
            raise ValueError(f"the velocity filter's cut-off must be > 0 Hz, got {cutoff}")
        self.cutoff = float(cutoff)
        self.tau = 0.0 if math.isinf(cutoff) else 1.0 / (2.0 * math.pi * cutoff)
        self.reset()

    def reset(self) -> None:
        """Forget the state: the next update returns its kinematic velocity."""
        self._state: tuple[float, float, float] | None = None
        self._dt = -1.0
        self._alpha = 0.0

    def update(
        self, dt: float, velocity: tuple[float, float, float] | None, acceleration: tuple[float, float, float]
    ) -> tuple[float, float, float]:
        """The filtered velocity (m/s) after ``dt`` (s) from the kinematic ``velocity`` (m/s; ``None``: none, the
        accelerometer alone) and the mean ``acceleration`` (m/s^2, gravity removed) over that period; ``dt <= 0`` (a
        repeated reading) keeps the state."""
        state = self._state
        if state is None:
            out = (0.0, 0.0, 0.0) if velocity is None else velocity
        elif dt <= 0.0:
            return state
        elif velocity is None:
            out = (state[0] + dt * acceleration[0], state[1] + dt * acceleration[1], state[2] + dt * acceleration[2])
        else:
            if dt != self._dt:  # alpha for this period, recomputed only when the period changes
                self._dt, self._alpha = dt, (math.exp(-dt / self.tau) if self.tau > 0.0 else 0.0)
            a = self._alpha
            sx, sy, sz = state
            vx, vy, vz = velocity
            ax, ay, az = acceleration
            out = (
                a * (sx + dt * ax) + (1.0 - a) * vx,
                a * (sy + dt * ay) + (1.0 - a) * vy,
                a * (sz + dt * az) + (1.0 - a) * vz,
            )
        self._state = out
        return out
