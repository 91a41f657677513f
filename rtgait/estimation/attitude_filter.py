"""A complementary filter on the IMU's orientation: its own filter's attitude at low frequencies, the gyro's
integration at high frequencies.

With ``q`` the IMU filter's orientation and ``w`` the gyro (IMU frame), each tick of ``dt`` makes

    q^- = q^_k-1 (1, w dt / 2) / |.|,        q^_k = (alpha q^- + (1 - alpha) q) / |.|,        alpha = exp(-dt / tau)

(quaternions ``(w, x, y, z)``, the body-frame increment to first order, the blend a normalised linear
interpolation taken on the same hemisphere as ``q^-``): a first-order low-pass of the filter's attitude, its lag
filled in by the gyro. Where the attitude's error is white noise of standard deviation ``sigma`` and the gyro has a
bias ``b``, the blend's error is about ``b tau + sigma sqrt(dt / (2 tau))``, least at
``tau = (sigma^2 dt / (2 b^2))^(1/3)``: 0.21 s for the Talos sensors' values and 0.20 s for the G1's
(``docs/robots.md``, "Sensors": roll and pitch noise 4.4 and 8.7 mrad, gyro bias 1 and 3 mrad/s, at 1 and 2 ms).
Hence the default :data:`DEFAULT_ATTITUDE_CUTOFF`, ``1 / (2 pi 0.2 s)``. A tilt error of ``e`` moves the COM
estimate by about ``e`` times its height above the feet, 0.85 mm per milliradian on Talos.
"""

from __future__ import annotations

import math

__all__ = ["DEFAULT_ATTITUDE_CUTOFF", "AttitudeFilter"]

DEFAULT_ATTITUDE_CUTOFF = 1.0 / (2.0 * math.pi * 0.2)
"""Cut-off of the attitude filter (Hz): a 0.2 s time constant (module docstring)."""


class AttitudeFilter:
    """The filter of the module docstring, on Python floats.

    Args:
        cutoff: the cut-off frequency (Hz), > 0; ``inf``: the IMU filter's attitude as it is.
    """

    def __init__(self, cutoff: float = DEFAULT_ATTITUDE_CUTOFF) -> None:
        if not cutoff > 0.0:
            raise ValueError(f"the attitude filter's cut-off must be > 0 Hz, got {cutoff}")
        self.cutoff = float(cutoff)
        self.tau = 0.0 if math.isinf(cutoff) else 1.0 / (2.0 * math.pi * cutoff)
        self.reset()

    def reset(self) -> None:
        """Forget the state: the next update returns the IMU filter's attitude."""
        self._state: tuple[float, float, float, float] | None = None
        self._dt = -1.0
        self._alpha = 0.0

    def update(
        self, dt: float, orientation: tuple[float, float, float, float], gyro: tuple[float, float, float]
    ) -> tuple[float, float, float, float]:
        """The filtered orientation ``(w, x, y, z)`` after ``dt`` (s) from the IMU filter's ``orientation`` and the
        gyro's angular velocity (rad/s, IMU frame); ``dt <= 0`` (a repeated reading) keeps the state."""
        state = self._state
        if state is None or self.tau == 0.0:
            w, x, y, z = orientation
            n = 1.0 / math.sqrt(w * w + x * x + y * y + z * z)
            self._state = out = (w * n, x * n, y * n, z * n)
            return out
        if dt <= 0.0:
            return state
        if dt != self._dt:  # alpha for this period, recomputed only when the period changes
            self._dt, self._alpha = dt, math.exp(-dt / self.tau)
        # The gyro's increment, q^- = q^ (1, w dt / 2): the body-frame rotation of one tick.
        sw, sx, sy, sz = state
        h = 0.5 * dt
        gx, gy, gz = gyro[0] * h, gyro[1] * h, gyro[2] * h
        pw = sw - sx * gx - sy * gy - sz * gz
        px = sx + sw * gx + sy * gz - sz * gy
        py = sy + sw * gy + sz * gx - sx * gz
        pz = sz + sw * gz + sx * gy - sy * gx
        # The blend toward the IMU filter's attitude, on the predicted quaternion's hemisphere.
        a = self._alpha
        w, x, y, z = orientation
        b = 1.0 - a if pw * w + px * x + py * y + pz * z >= 0.0 else a - 1.0
        w, x, y, z = a * pw + b * w, a * px + b * x, a * py + b * y, a * pz + b * z
        n = 1.0 / math.sqrt(w * w + x * x + y * y + z * z)
        self._state = out = (w * n, x * n, y * n, z * n)
        return out
