"""Piecewise polynomials in local time: the ZMP spline of eq. 1.

Segment ``j`` covers ``[breaks[j], breaks[j+1]]`` and holds ``p_j(tau) = sum_i coeffs[j, i] * tau**i`` with
``tau = t - breaks[j]`` in seconds. Coefficients carry a trailing axis for the horizontal directions (x, y),
so one spline describes both axes; lower-degree segments are padded with zeros.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def polynomial_derivative_rows(degree: int, tau: float, derivative: int) -> np.ndarray:
    """Row ``r`` with ``r @ coeffs`` = the ``derivative``-th time derivative at local time ``tau``.

    ``coeffs`` are ascending monomial coefficients of a polynomial of ``degree``; the row has
    ``degree + 1`` entries (unit: s^(i - derivative)).
    """
    row = np.zeros(degree + 1)
    for i in range(derivative, degree + 1):
        falling = 1.0
        for k in range(derivative):
            falling *= i - k
        row[i] = falling * tau ** (i - derivative)
    return row


def evaluate_polynomials(coeffs: np.ndarray, tau: np.ndarray, derivative: int = 0) -> np.ndarray:
    """Evaluate ascending-coefficient polynomials (or a derivative) by Horner's rule.

    ``coeffs`` has shape ``(k, n + 1, d)`` (one polynomial per sample), ``tau`` shape ``(k,)``;
    returns shape ``(k, d)``.
    """
    n = coeffs.shape[1] - 1
    result = np.zeros((coeffs.shape[0], coeffs.shape[2]))
    tau_col = tau[:, None]
    for i in range(n, derivative - 1, -1):
        factor = 1.0
        for k in range(derivative):
            factor *= i - k
        result = result * tau_col + factor * coeffs[:, i, :]
    return result


@dataclass(frozen=True)
class PiecewisePolynomial:
    """A spline of polynomial segments over absolute time (s), values in metres.

    Attributes:
        t0: absolute start time of the first segment (s).
        durations: segment durations, shape ``(m,)`` (s), all positive.
        coeffs: ascending coefficients per segment, shape ``(m, n + 1, d)`` (m / s^i).
    """

    t0: float
    durations: np.ndarray
    coeffs: np.ndarray

    def __post_init__(self) -> None:
        durations = np.asarray(self.durations, dtype=float)
        coeffs = np.asarray(self.coeffs, dtype=float)
        if durations.ndim != 1 or durations.size == 0:
            raise ValueError("durations must be a non-empty 1-D array of segment lengths (s)")
        if not np.all(np.isfinite(durations)) or np.any(durations <= 0.0):
            raise ValueError(f"durations must be finite and > 0 s, got {durations.tolist()}")
        if coeffs.ndim == 2:
            coeffs = coeffs[:, :, None]
        if coeffs.ndim != 3 or coeffs.shape[0] != durations.size:
            raise ValueError(
                f"coeffs must have shape (m, degree + 1, axes) with m = {durations.size}, got {coeffs.shape}"
            )
        if not np.all(np.isfinite(coeffs)):
            raise ValueError("coeffs must be finite")
        object.__setattr__(self, "durations", durations)
        object.__setattr__(self, "coeffs", coeffs)

    @property
    def breaks(self) -> np.ndarray:
        """Absolute segment boundaries, shape ``(m + 1,)`` (s)."""
        return self.t0 + np.concatenate(([0.0], np.cumsum(self.durations)))

    @property
    def t_end(self) -> float:
        """Absolute end time (s)."""
        return float(self.t0 + self.durations.sum())

    @property
    def degree(self) -> int:
        return self.coeffs.shape[1] - 1

    def locate(self, t: np.ndarray, side: str = "right") -> tuple[np.ndarray, np.ndarray]:
        """Segment index and local time for absolute times ``t``; times outside are clamped to the ends.

        ``side="left"`` places a time that falls on a boundary in the segment that ends there, which gives
        left limits at the joints.
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        breaks = self.breaks
        index = np.searchsorted(breaks, t, side=side) - 1
        index = np.clip(index, 0, self.durations.size - 1)
        tau = np.clip(t - breaks[index], 0.0, self.durations[index])
        return index, tau

    def evaluate(self, t: np.ndarray | float, derivative: int = 0, side: str = "right") -> np.ndarray:
        """Value (or time derivative) at absolute times ``t``: shape ``(len(t), d)``."""
        index, tau = self.locate(t, side)
        return evaluate_polynomials(self.coeffs[index], tau, derivative)
