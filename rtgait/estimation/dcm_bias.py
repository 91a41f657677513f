"""DCM bias estimation: the constant offset between the estimated DCM and the one the feet's ZMP drives.

The estimator's COM is the robot model's (its masses and centres of mass, at the encoders' readings); a real robot's
links weigh and sit a little elsewhere, so the estimated COM, and with it the DCM, is off the true one by a bias ``b``
(m) that the estimate alone cannot show. The ZMP the feet's force sensors measure does not share it: the true DCM
``xi`` obeys the pendulum's ``xi' = w (xi - p)`` with the measured ZMP ``p``, and the estimate ``y = xi + b`` then
drifts from that law by ``w b``. A Kalman filter on the state ``(xi, b)`` per horizontal axis, after the DCM bias
estimator of mc_rtc's LIPM stabiliser (Benallegue's ``UnidimLipmDcmEstimator``, state-observation), separates them:

    xi[k+1] = e xi[k] - (e - 1) p[k] - h (p[k+1] - p[k]) + n_xi,    b[k+1] = b[k] + n_b,    y[k] = xi[k] + b[k] + v (1)

with ``e = exp(w dt)`` and ``h = (e - 1 - w dt) / (w dt)``: the pendulum's exact step for a ZMP that goes linearly
from one tick's measurement to the next (mc_rtc's filter takes the Euler step, ``1 + w dt`` and the held ZMP, whose
error over a walk's ZMP would read as a bias of a fraction of a millimetre); process noises ``n_xi`` (the measured
ZMP's error through the pendulum) and ``n_b`` (the bias's drift, a random walk) and measurement noise ``v``. Its
variances are densities, the same filter at any control period ``dt``: ``Var n_xi = w^2 s_p^2 dt_0 dt``, ``Var n_b =
s_b^2 dt``, ``Var v = s_y^2 dt_0 / dt`` with ``dt_0`` = 5 ms, at which ``s_p`` = 0.05 m, ``s_y`` = 0.01 m and
``s_b`` = 1.4 mm/sqrt(s) are mc_rtc's defaults (ZMP error 0.05 m, DCM error 0.01 m, bias drift 0.02 m per second per
tick, i.e. 0.02 dt_0 per tick). The bias is clamped to ``max_bias`` (mc_rtc's
``biasLimit``, 0.02 m). Both axes share the same matrices, so one covariance serves both (three numbers a tick).

The bias belongs to the robot's body, not to the world: when the robot turns by ``dpsi`` the estimated bias turns
with it (its mean; the covariance is isotropic between the axes and kept). The unbiased COM is ``c - b``, the
unbiased DCM ``y - b``: the controller feeds back and replans on them (as mc_rtc does with its estimated bias), and
the DCM law's integral and the COM admittance then move the COM target by what the IK's model puts the COM off.

What it also takes for a bias: anything that holds the measured ZMP off the pendulum's on average (an external force,
a ZMP error of the force sensors); whatever changes faster than its drift allows is left to the DCM feedback.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

__all__ = ["DcmBiasEstimator", "DcmBiasSettings"]

REFERENCE_PERIOD = 0.005
"""``dt_0`` (s): the control period at which the noises of :class:`DcmBiasSettings` are mc_rtc's per-tick values."""


@dataclass(frozen=True)
class DcmBiasSettings:
    """Noises and limit of :class:`DcmBiasEstimator` (module docstring, eq. (1); SI units).

    Attributes:
        zmp_error: ``s_p``, the measured ZMP's error at the reference period (m), > 0.
        dcm_error: ``s_y``, the estimated DCM's error at the reference period (m), > 0.
        bias_drift: ``s_b``, the bias's random walk (m/sqrt(s)), > 0.
        max_bias: largest bias on each axis (m), >= 0.
        initial_bias_error: the bias's standard deviation at the start (m), > 0.
    """

    zmp_error: float = 0.05
    dcm_error: float = 0.01
    bias_drift: float = 0.02 * math.sqrt(REFERENCE_PERIOD)
    max_bias: float = 0.02
    initial_bias_error: float = 0.02

    def __post_init__(self) -> None:
        for field in fields(self):
            value = getattr(self, field.name)
            number = isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)
            positive = field.name != "max_bias"
            if not (number and (value > 0.0 if positive else value >= 0.0) and value <= 1.0):
                bound = "(0, 1]" if positive else "[0, 1]"
                raise ValueError(f"DcmBiasSettings.{field.name} must be within {bound} m, got {value!r}")
            object.__setattr__(self, field.name, float(value))


class DcmBiasEstimator:
    """The Kalman filter of eq. (1) on both horizontal axes (module docstring).

    Call :meth:`update` once per control tick with the estimated DCM, the measured ZMP and the robot's heading;
    :attr:`bias` is then ``b`` (m, world frame). The first call starts the filter at the measured DCM with no bias.

    Args:
        w: the pendulum's ``sqrt(g / z)`` (1/s), > 0.
        dt: the control period (s), > 0.
        settings: :class:`DcmBiasSettings`.
    """

    def __init__(self, w: float, dt: float, settings: DcmBiasSettings | None = None) -> None:
        if not (math.isfinite(w) and w > 0.0):
            raise ValueError(f"w must be > 0 (1/s), got {w}")
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f"dt must be a period > 0 s, got {dt}")
        self.settings = s = settings or DcmBiasSettings()
        self.w, self.dt = float(w), float(dt)
        a = w * dt
        self._a = math.exp(a)  # the DCM's transition; the ZMPs of the two ticks enter as in eq. (1)
        self._hold = math.expm1(a)
        self._ramp = (math.expm1(a) - a) / a
        self._q_dcm = w * w * s.zmp_error**2 * REFERENCE_PERIOD * dt
        self._q_bias = s.bias_drift**2 * dt
        self._r = s.dcm_error**2 * REFERENCE_PERIOD / dt
        self.reset()

    def reset(self) -> None:
        """Forget the state: the next :meth:`update` starts the filter again."""
        self._started = False
        self._dcm = [0.0, 0.0]
        self._bias = [0.0, 0.0]
        self._zmp = (0.0, 0.0)
        self._heading = 0.0
        p = self.settings.initial_bias_error**2
        # The covariance of (xi, b), one for both axes: the DCM as measured, less a bias not yet known.
        self._p = [self._r + p, -p, p]  # p_xx, p_xb, p_bb

    @property
    def bias(self) -> tuple[float, float]:
        """``b`` (m, world frame): the estimated DCM (and COM) less the true one."""
        return self._bias[0], self._bias[1]

    @property
    def dcm(self) -> tuple[float, float]:
        """The filter's DCM ``xi`` (m, world frame)."""
        return self._dcm[0], self._dcm[1]

    def update(self, dcm: tuple[float, float], zmp: tuple[float, float], heading: float) -> tuple[float, float]:
        """One tick: the estimated DCM ``y`` (m), the measured ZMP ``p`` (m; NaN when no foot is loaded: the
        prediction then holds the last one) and the robot's heading (rad). Returns :attr:`bias`."""
        yx, yy = dcm
        if not (math.isfinite(yx) and math.isfinite(yy)):
            raise ValueError(f"dcm must be finite (m), got {dcm!r}")
        bias = self._bias
        if not self._started:
            self._started = True
            self._dcm = [yx - bias[0], yy - bias[1]]
            self._heading = heading
            self._zmp = zmp if (math.isfinite(zmp[0]) and math.isfinite(zmp[1])) else (yx, yy)
            return self.bias
        # The bias turns with the body.
        turn = math.remainder(heading - self._heading, math.tau)
        self._heading = heading
        if turn != 0.0:
            c, s = math.cos(turn), math.sin(turn)
            bias[0], bias[1] = c * bias[0] - s * bias[1], s * bias[0] + c * bias[1]
        # Prediction over the last tick, the ZMP going from the last measurement to this one.
        a, hold, ramp = self._a, self._hold, self._ramp
        dcm_state = self._dcm
        px, py = self._zmp
        if math.isfinite(zmp[0]) and math.isfinite(zmp[1]):
            self._zmp = zmp
        qx, qy = self._zmp
        dcm_state[0] = a * dcm_state[0] - hold * px - ramp * (qx - px)
        dcm_state[1] = a * dcm_state[1] - hold * py - ramp * (qy - py)
        p_xx, p_xb, p_bb = self._p
        p_xx = a * a * p_xx + self._q_dcm
        p_xb = a * p_xb
        p_bb = p_bb + self._q_bias
        # Correction by y = xi + b.
        s = p_xx + 2.0 * p_xb + p_bb + self._r
        k_x = (p_xx + p_xb) / s
        k_b = (p_xb + p_bb) / s
        limit = self.settings.max_bias
        for axis, y in ((0, yx), (1, yy)):
            innovation = y - dcm_state[axis] - bias[axis]
            dcm_state[axis] += k_x * innovation
            value = bias[axis] + k_b * innovation
            bias[axis] = -limit if value < -limit else (limit if value > limit else value)
        # P - K C P (C = [1, 1]).
        c_x, c_b = p_xx + p_xb, p_xb + p_bb
        self._p = [p_xx - k_x * c_x, p_xb - k_x * c_b, p_bb - k_b * c_b]
        return self.bias
