"""Boundary-value solve for the homogeneous coefficients ``V_j, W_j`` (eqs. 8-12).

Unknowns are ordered ``[V_1, W_1, ..., V_m, W_m]``. Rows: the initial COG position, COG position and velocity
continuity at each of the ``m - 1`` junctions, the terminal COG position. The matrix depends on the segment
durations and ``w`` only, so it is factored once per timing pattern (:class:`BoundaryValueSolver`) and the
factorisation is reused for any ZMP spline of that timing, for both axes at once.

The same block-bidiagonal system also decouples exactly into two first-order recursions
(:func:`component_propagators`), which the plan operators of :mod:`rtgait.core.lipm.pattern` use to avoid a dense
solve: with the divergent and convergent components of the COG

    xi = c + c'/w = U_j e^{w tau} + (A_j + A_j'/w)(tau),      U_j = V_j + W_j,
    zeta = c - c'/w = S_j e^{-w tau} + (A_j - A_j'/w)(tau),    S_j = V_j - W_j,

COG position and velocity are continuous exactly when ``xi`` and ``zeta`` are. ``zeta`` decays forward in time
and ``xi`` backward, so ``S`` is swept forward from ``zeta(t_0)`` and ``U`` backward from ``xi(t_m)``, each with
weights ``e^{-w (later - earlier)} <= 1``: no growing exponential is ever formed, unlike shooting on ``c``.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy.linalg import lu_factor, lu_solve

from rtgait.core.lipm.closed_form import CogTrajectory, particular_matrix
from rtgait.core.lipm.spline import PiecewisePolynomial, evaluate_polynomials


def bvp_matrix(durations: np.ndarray, w: float) -> np.ndarray:
    """The ``2m x 2m`` matrix of eqs. 8-12 for segment ``durations`` (s) and frequency ``w`` (1/s)."""
    durations = np.asarray(durations, dtype=float)
    m = durations.size
    ch, sh = np.cosh(w * durations), np.sinh(w * durations)
    M = np.zeros((2 * m, 2 * m))
    M[0, 0] = 1.0
    for j in range(m - 1):
        v, wcol = 2 * j, 2 * j + 1
        row = 1 + 2 * j
        M[row, v], M[row, wcol], M[row, v + 2] = ch[j], sh[j], -1.0
        M[row + 1, v], M[row + 1, wcol], M[row + 1, wcol + 2] = w * sh[j], w * ch[j], -w
    M[-1, -2], M[-1, -1] = ch[-1], sh[-1]
    return M


@lru_cache(maxsize=64)
def _sweep_intervals(m: int) -> tuple[np.ndarray, np.ndarray]:
    """``(spans, K)``, read-only, for ``m`` segments: with durations ``T`` ``(..., m)``, ``T @ spans`` (reshaped to
    ``(..., 2, m, m)``) is the time between the two instants of each entry of ``[F, B]`` (a sum of durations),
    and ``K`` is 0 on the kept triangles and ``-inf`` on the discarded ones, whose entries come out exactly 0."""
    i, j, k = np.ogrid[:m, :m, :m]
    forward = (k <= i) & (i < j)  # F[j, k]: from t_k to t_j covers segments k..j-1
    backward = (j <= i) & (i <= k)  # B[j, k]: from t_j to t_{k+1} covers segments j..k
    spans = np.stack([forward, backward], axis=1).astype(float).reshape(m, 2 * m * m)
    jj, kk = np.ogrid[:m, :m]
    K = np.where(np.stack([kk <= jj, kk >= jj]), 0.0, -np.inf).reshape(2 * m * m)
    spans.setflags(write=False)
    K.setflags(write=False)
    return spans, K


@lru_cache(maxsize=256)
def _sweep_exponents(m: int, w: float) -> tuple[np.ndarray, np.ndarray]:
    """``(-w spans, K)`` of :func:`_sweep_intervals`: ``[F, B] = exp(T @ C + K)``."""
    spans, K = _sweep_intervals(m)
    C = -w * spans
    C.setflags(write=False)
    return C, K


def component_propagators(durations: np.ndarray, w: float) -> tuple[np.ndarray, np.ndarray]:
    """Forward and backward sweep matrices ``(F, B)``, each ``(..., m, m)``, for segment ``durations``
    ``(..., m)`` (s, positive; leading axes batch several timings) and frequency ``w`` (1/s).

    With ``t_j`` the start of segment ``j`` (0-based, ``t_0 = 0``, ``T_j = t_{j+1} - t_j``):

    * convergent part: ``S_0 = e_0`` and ``S_{j+1} = e^{-w T_j} S_j + e_{j+1}``, i.e. ``S = F @ e`` with
      ``F[j, k] = e^{-w (t_j - t_k)}`` for ``k <= j``. Here ``e_0 = zeta(t_0) - P^-_0(0)`` and
      ``e_k = P^-_{k-1}(T_{k-1}) - P^-_k(0)`` (jumps of the particular part ``P^- = A - A'/w``);
    * divergent part: ``U_{m-1} = e^{-w T_{m-1}} d_{m-1}`` and ``U_j = e^{-w T_j} (U_{j+1} + d_j)``, i.e.
      ``U = B @ d`` with ``B[j, k] = e^{-w (t_{k+1} - t_j)}`` for ``k >= j``. Here ``d_k = P^+_{k+1}(0) -
      P^+_k(T_k)`` for ``k < m - 1`` and ``d_{m-1} = xi(t_m) - P^+_{m-1}(T_{m-1})`` with ``P^+ = A + A'/w``.

    Every kept entry is ``e^{-w * (a sum of durations)}``, in ``(0, 1]``; ``B[-1, -1] = e^{-w T_{m-1}}``.
    """
    durations = np.asarray(durations, dtype=float)
    m = durations.shape[-1]
    C, K = _sweep_exponents(m, float(w))
    # Sums of durations, not differences of break times: no cancellation, however long the horizon.
    both = np.exp(durations @ C + K).reshape(*durations.shape[:-1], 2, m, m)
    return both[..., 0, :, :], both[..., 1, :, :]


def bvp_rhs_from_ends(
    start_pos: np.ndarray,
    start_vel: np.ndarray,
    end_pos: np.ndarray,
    end_vel: np.ndarray,
    c_start: np.ndarray,
    c_end: np.ndarray,
) -> np.ndarray:
    """Right-hand side ``(2m, d)`` from the particular solution's position and velocity at the start and end of
    every segment (each ``(m, d)``, m and m/s) and the prescribed COG positions at both ends (m).

    Any particular solution works (polynomial, Fourier): the homogeneous part makes up the difference.
    """
    m, d = start_pos.shape
    rhs = np.empty((2 * m, d))
    rhs[0] = np.asarray(c_start, dtype=float) - start_pos[0]
    rhs[1:-1:2] = start_pos[1:] - end_pos[:-1]
    rhs[2:-1:2] = start_vel[1:] - end_vel[:-1]
    rhs[-1] = np.asarray(c_end, dtype=float) - end_pos[-1]
    return rhs


def bvp_rhs(particular: np.ndarray, durations: np.ndarray, c_start: np.ndarray, c_end: np.ndarray) -> np.ndarray:
    """Right-hand side ``(2m, d)`` for polynomial parts ``particular`` ``(m, n + 1, d)`` and end positions (m)."""
    zeros = np.zeros(len(durations))
    return bvp_rhs_from_ends(
        start_pos=particular[:, 0],
        start_vel=evaluate_polynomials(particular, zeros, 1),  # A_1, or 0 for degree 0
        end_pos=evaluate_polynomials(particular, durations, 0),
        end_vel=evaluate_polynomials(particular, durations, 1),
        c_start=c_start,
        c_end=c_end,
    )


class BoundaryValueSolver:
    """Factored BVP of one timing pattern; :meth:`solve` then costs a pair of triangular solves.

    Args:
        durations: segment durations (s), all positive.
        w: pendulum frequency (1/s).
    """

    def __init__(self, durations: np.ndarray, w: float) -> None:
        durations = np.asarray(durations, dtype=float)
        if durations.ndim != 1 or durations.size == 0 or np.any(~np.isfinite(durations)) or np.any(durations <= 0):
            raise ValueError(f"durations must be finite and > 0 s, got {np.atleast_1d(durations).tolist()}")
        self.durations = durations
        self.w = float(w)
        self._lu = lu_factor(bvp_matrix(durations, self.w))

    def solve(self, zmp: PiecewisePolynomial, c_start: np.ndarray, c_end: np.ndarray) -> CogTrajectory:
        """COG through the ZMP spline with COG position ``c_start`` at its start and ``c_end`` at its end (m)."""
        if zmp.durations.shape != self.durations.shape or not np.allclose(
            zmp.durations, self.durations, rtol=1e-12, atol=0.0
        ):
            raise ValueError("the ZMP spline's durations differ from the factored timing pattern")
        for name, value in (("c_start", c_start), ("c_end", c_end)):
            if not np.all(np.isfinite(value)):
                raise ValueError(f"{name} must be a finite COG position (m), got {value}")
        A = np.einsum("ik,jkd->jid", particular_matrix(zmp.degree, self.w), zmp.coeffs)
        V, W = self.homogeneous(bvp_rhs(A, self.durations, c_start, c_end))
        return CogTrajectory(zmp=zmp, V=V, W=W, w=self.w)

    def homogeneous(self, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``V, W`` (each ``(m, d)``, m) for a right-hand side ``(2m, d)`` from :func:`bvp_rhs_from_ends`."""
        VW = lu_solve(self._lu, rhs)
        return VW[0::2], VW[1::2]
