"""Angular-momentum compensation (the paper's Appendix A, method.md section 6).

The rate of angular momentum about the COG, divided by ``M g``, shifts the ZMP away from the pendulum's
``c - c''/w^2`` (eq. 4). To cancel that shift the COG gets a correction ``dc`` with

    dc - dc'' / w^2 = f(t),     f = Ldot_y / (M g) along x,   f = -Ldot_x / (M g) along y.

On each segment ``f`` is expanded in a truncated Fourier series of the segment's own period ``T_j`` (eqs.
A.1-A.3); each harmonic ``cos(W_i tau)``, ``sin(W_i tau)`` with ``W_i = 2 pi i / T_j`` has the closed-form
particular solution ``coefficient / (1 + (W_i / w)^2)`` (eqs. A.5-A.6), and cosh/sinh terms whose ``V, W`` come
from the same boundary-value problem as the COG (eqs. 8-12), with ``dc = 0`` at both ends of the walk so the
corrected COG starts and stops where the plan does.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rtgait.core.lipm.bvp import BoundaryValueSolver, bvp_rhs_from_ends

DEFAULT_ORDER = 3
"""Fourier order used by the paper (n = 3)."""


def angular_zmp_offset(angular_momentum_rate: np.ndarray, mass: float, gravity: float) -> np.ndarray:
    """The ZMP shift to cancel, ``f`` (m) per axis ``(k, 2)``, from the rate of angular momentum about the COG
    ``(k, 3)`` (N m) of a robot of ``mass`` (kg) under ``gravity`` (m/s^2)."""
    rate = np.asarray(angular_momentum_rate, dtype=float)
    return np.stack([rate[:, 1], -rate[:, 0]], axis=1) / (mass * gravity)


def _harmonics(tau: np.ndarray, period: float, order: int) -> np.ndarray:
    """Design matrix ``(k, 2 order + 1)``: 1, cos(W_1 tau), sin(W_1 tau), ..., cos(W_n tau), sin(W_n tau)."""
    omega = 2.0 * np.pi * np.arange(1, order + 1) / period
    phase = tau[:, None] * omega[None, :]
    columns = np.empty((len(tau), 2 * order + 1))
    columns[:, 0] = 1.0
    columns[:, 1::2] = np.cos(phase)
    columns[:, 2::2] = np.sin(phase)
    return columns


@dataclass(frozen=True)
class FourierCorrection:
    """The COG correction ``dc`` in closed form: Fourier particular part plus cosh/sinh per segment.

    Attributes:
        breaks: absolute segment boundaries, shape ``(m + 1,)`` (s).
        w: pendulum frequency (1/s).
        order: Fourier order ``n``.
        series: fitted coefficients of ``f`` per segment, ``(m, 2n + 1, d)`` (m), ordered as ``_harmonics``.
        V, W: homogeneous coefficients per segment, ``(m, d)`` (m).
    """

    breaks: np.ndarray
    w: float
    order: int
    series: np.ndarray
    V: np.ndarray
    W: np.ndarray

    def _particular_gain(self, period: float) -> np.ndarray:
        """Per harmonic column, the factor turning an ``f`` coefficient into a ``dc`` coefficient."""
        omega = 2.0 * np.pi * np.arange(1, self.order + 1) / period
        gain = np.ones(2 * self.order + 1)
        gain[1::2] = gain[2::2] = 1.0 / (1.0 + (omega / self.w) ** 2)
        return gain

    def offset(self, t: np.ndarray) -> np.ndarray:
        """The fitted ZMP shift ``f`` at absolute times ``t``, ``(k, d)`` (m)."""
        return self._evaluate(t, with_gain=False)[0]

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``dc``, ``dc'``, ``dc''`` at absolute times ``t``, each ``(k, d)`` (m, m/s, m/s^2)."""
        return self._evaluate(t, with_gain=True)

    def _evaluate(self, t: np.ndarray, with_gain: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        t = np.atleast_1d(np.asarray(t, dtype=float))
        m = len(self.breaks) - 1
        index = np.clip(np.searchsorted(self.breaks, t, side="right") - 1, 0, m - 1)
        d = self.series.shape[2]
        pos, vel, acc = (np.zeros((len(t), d)) for _ in range(3))
        for j in np.unique(index):
            mask = index == j
            period = self.breaks[j + 1] - self.breaks[j]
            tau = np.clip(t[mask] - self.breaks[j], 0.0, period)
            coeffs = self.series[j] * (self._particular_gain(period)[:, None] if with_gain else 1.0)
            basis = _harmonics(tau, period, self.order)
            omega = np.repeat(2.0 * np.pi * np.arange(1, self.order + 1) / period, 2)
            # d/dtau of [cos, sin] = omega * [-sin, cos]; second derivative = -omega^2 * [cos, sin].
            d_basis = np.zeros_like(basis)
            d_basis[:, 1::2] = -basis[:, 2::2] * omega[0::2]
            d_basis[:, 2::2] = basis[:, 1::2] * omega[1::2]
            dd_basis = np.zeros_like(basis)
            dd_basis[:, 1:] = -basis[:, 1:] * omega**2
            pos[mask] = basis @ coeffs
            vel[mask] = d_basis @ coeffs
            acc[mask] = dd_basis @ coeffs
            if with_gain:
                wt = self.w * tau[:, None]
                ch, sh = np.cosh(wt), np.sinh(wt)
                pos[mask] += self.V[j] * ch + self.W[j] * sh
                vel[mask] += self.w * (self.V[j] * sh + self.W[j] * ch)
                acc[mask] += self.w**2 * (self.V[j] * ch + self.W[j] * sh)
        return pos, vel, acc


def fit_correction(
    times: np.ndarray, offset: np.ndarray, breaks: np.ndarray, w: float, order: int = DEFAULT_ORDER
) -> FourierCorrection:
    """Fit ``f`` per segment by least squares on its samples and solve for the COG correction ``dc``.

    Args:
        times: sample times (s), shape ``(k,)``, covering ``[breaks[0], breaks[-1]]``.
        offset: ``f`` at those times, ``(k, d)`` (m), e.g. from :func:`angular_zmp_offset`.
        breaks: segment boundaries (s), e.g. the walk's phase boundaries.
        w: pendulum frequency (1/s).
        order: Fourier order (>= 0); each segment needs at least ``2 order + 1`` samples.
    """
    times = np.asarray(times, dtype=float)
    offset = np.asarray(offset, dtype=float)
    breaks = np.asarray(breaks, dtype=float)
    if offset.ndim == 1:
        offset = offset[:, None]
    if not isinstance(order, int) or order < 0:
        raise ValueError(f"Fourier order must be an integer >= 0, got {order!r}")
    if times.shape[0] != offset.shape[0]:
        raise ValueError(f"times ({times.shape[0]}) and offset ({offset.shape[0]}) must have the same length")
    if not (np.all(np.isfinite(offset)) and np.all(np.isfinite(times))):
        raise ValueError("times and offset must be finite")
    durations = np.diff(breaks)
    if breaks.ndim != 1 or len(breaks) < 2 or np.any(durations <= 0.0):
        raise ValueError("breaks must be increasing segment boundaries (s)")
    m, d = len(durations), offset.shape[1]
    series = np.zeros((m, 2 * order + 1, d))
    index = np.clip(np.searchsorted(breaks, times, side="right") - 1, 0, m - 1)
    for j in range(m):
        mask = index == j
        if mask.sum() < 2 * order + 1:
            raise ValueError(
                f"segment {j} ({breaks[j]:.3f}-{breaks[j + 1]:.3f} s) has {mask.sum()} samples; a Fourier fit of "
                f"order {order} needs {2 * order + 1}"
            )
        basis = _harmonics(times[mask] - breaks[j], durations[j], order)
        series[j] = np.linalg.lstsq(basis, offset[mask], rcond=None)[0]
    shell = FourierCorrection(breaks, float(w), order, series, np.zeros((m, d)), np.zeros((m, d)))
    # The particular part is periodic on each segment: the same value and slope at both of its ends.
    start_pos, start_vel = np.empty((m, d)), np.empty((m, d))
    for j in range(m):
        pos, vel, _ = shell._evaluate(np.array([breaks[j]]), with_gain=True)
        start_pos[j], start_vel[j] = pos[0], vel[0]
    rhs = bvp_rhs_from_ends(start_pos, start_vel, start_pos, start_vel, np.zeros(d), np.zeros(d))
    V, W = BoundaryValueSolver(durations, w).homogeneous(rhs)
    return FourierCorrection(breaks, float(w), order, series, V, W)
