"""The linear inverted pendulum in closed form (eqs. 3, 5-7).

With the ZMP a polynomial on a segment, the COG on that segment is exactly
``c(tau) = V cosh(w tau) + W sinh(w tau) + sum_i A_i tau^i``. ``A`` follows from the ZMP coefficients by a
triangular linear map (the back-substitution of eqs. 6-7); ``V`` and ``W`` are fixed by boundary conditions
(see :mod:`rtgait.core.lipm.bvp`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from rtgait.core.limits import MAX_COG_HEIGHT, MAX_GRAVITY, MIN_COG_HEIGHT, MIN_GRAVITY, check_range
from rtgait.core.lipm.spline import PiecewisePolynomial, evaluate_polynomials

GRAVITY = 9.81
"""Standard gravity used by default (m/s^2)."""


def omega(cog_height: float, gravity: float = GRAVITY) -> float:
    """Natural frequency ``w = sqrt(g / zc)`` of the pendulum (1/s); the paper's ``T_c``.

    ``cog_height`` must be within [0.05, 10] m and ``gravity`` within [0.1, 100] m/s^2
    (:mod:`rtgait.core.limits`): outside them no walking robot exists and the closed form loses its conditioning.
    """
    check_range("cog_height", cog_height, MIN_COG_HEIGHT, MAX_COG_HEIGHT, "m")
    check_range("gravity", gravity, MIN_GRAVITY, MAX_GRAVITY, "m/s^2")
    return math.sqrt(gravity / cog_height)


@lru_cache(maxsize=64)
def _particular_matrix_cached(degree: int, w: float) -> np.ndarray:
    Q = np.zeros((degree + 1, degree + 1))
    # A_i = a_i + (i + 1)(i + 2) A_{i+2} / w^2, from the top degree down (eqs. 6-7).
    for i in range(degree, -1, -1):
        Q[i, i] = 1.0
        if i + 2 <= degree:
            Q[i] += (i + 1) * (i + 2) / w**2 * Q[i + 2]
    Q.setflags(write=False)
    return Q


def particular_matrix(degree: int, w: float) -> np.ndarray:
    """Matrix ``Q`` with ``A = Q @ a``: ZMP coefficients to the COG's polynomial part (read-only)."""
    if degree < 0:
        raise ValueError(f"degree must be >= 0, got {degree}")
    return _particular_matrix_cached(int(degree), float(w))


@dataclass(frozen=True)
class CogTrajectory:
    """COG in closed form over a ZMP spline, per horizontal axis.

    Attributes:
        zmp: the ZMP spline (m), coefficients shape ``(m, n + 1, d)``.
        V, W: homogeneous coefficients per segment and axis, shape ``(m, d)`` (m).
        w: pendulum frequency (1/s).
    """

    zmp: PiecewisePolynomial
    V: np.ndarray
    W: np.ndarray
    w: float

    @property
    def particular(self) -> np.ndarray:
        """Polynomial part ``A`` of the COG per segment, shape ``(m, n + 1, d)``."""
        Q = particular_matrix(self.zmp.degree, self.w)
        return np.einsum("ik,jkd->jid", Q, self.zmp.coeffs)

    def evaluate(self, t: np.ndarray | float, side: str = "right") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """COG position (m), velocity (m/s) and acceleration (m/s^2) at absolute times, each ``(k, d)``."""
        index, tau = self.zmp.locate(t, side)
        A = self.particular[index]
        wt = self.w * tau[:, None]
        ch, sh = np.cosh(wt), np.sinh(wt)
        V, W = self.V[index], self.W[index]
        pos = V * ch + W * sh + evaluate_polynomials(A, tau, 0)
        vel = self.w * (V * sh + W * ch) + evaluate_polynomials(A, tau, 1)
        acc = self.w**2 * (V * ch + W * sh) + evaluate_polynomials(A, tau, 2)
        return pos, vel, acc

    def pendulum_residual(self, t: np.ndarray | float) -> np.ndarray:
        """``p - (c - c''/w^2)`` at absolute times (m): zero up to round-off for a correct solution."""
        pos, _, acc = self.evaluate(t)
        return self.zmp.evaluate(t) - (pos - acc / self.w**2)
