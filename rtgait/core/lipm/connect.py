"""Simultaneous COG/ZMP planning: a new plan that connects continuously to the one being executed (eqs. 13-16).

A plain BVP fixes the COG position at both ends but not the initial COG velocity, so splicing it onto a
running trajectory would make the velocity jump. Here the ZMP polynomial of the first segment (a double
support phase) is unknown as well. Its coefficients ``b`` join ``V_j, W_j`` as unknowns and the conditions are:

* ZMP position (and, for the quartic, velocity) at the start of segment 1 equals the current ZMP (eq. 13);
* ZMP position (and velocity) at the end of segment 1 equals the start of segment 2 (eq. 14);
* COG position and velocity at the start equal the current COG state (eqs. 8, 15);
* COG position and velocity continuous at every junction, COG position prescribed at the end (eqs. 9-12).

Optionally (``terminal_rest=True``) the plan also ends at rest. Prescribing only ``c(t_m) = c_end`` leaves the
COG moving at the end: on a last segment of duration ``T`` with the ZMP held at ``c_end``, ``c - c_end =
V cosh(w tau) + W sinh(w tau)`` and the BVP gives ``c'(T) = w (V sinh + W cosh) ~ 2 w W e^{-w T}``, which is
27 mm/s after a 0.3 s settle. One more unknown and one more row fix it:

* the last segment's ZMP becomes ``p_m(tau) = r_m(tau) + alpha s(tau)`` with the fixed quartic bump
  ``s(tau) = tau^2 (T - tau)^2 / T^4`` (:func:`rest_bump`), which vanishes with its first derivative at both
  ends: the ZMP position and velocity at the junction before and at the end are those of the reference;
* the row ``c'(t_m) = w (V_m sinh(w T_m) + W_m cosh(w T_m)) + A_m'(T_m) = 0``.

Why it is always solvable: with the convergent component ``zeta = c - c'/w``, the pendulum gives
``zeta' = -w (zeta - p)``, so ``zeta(T) = e^{-w T} zeta(0) + w int_0^T e^{-w (T - tau)} p(tau) dtau`` on the last
segment. At rest ``zeta(T) = c(T) = c_end``; ``alpha`` moves ``zeta(T)`` with the weight
``w int_0^T e^{-w (T - tau)} s(tau) dtau > 0`` (about ``w T / 30`` for short ``T``), while the divergent
component ``xi = c + c'/w`` is, as before, pinned by the end position. If the reference ends at ``c_end``
(``r_m(T_m) = c_end``, true for a settle phase over the final anchor) then also ``c''(t_m) = w^2 (c - p) = 0``.
The bump's amplitude grows like ``1 / T`` for short last segments (peak ``alpha / 16``); below
``w T_m = MIN_REST_W_T`` the plan is refused (see there).

Everything is linear in the inputs and the matrix depends on durations and ``w`` only, so each timing pattern
gets one dense solution operator ``S`` with ``unknowns = S @ inputs``: one matrix product per replan. This is the
readable formulation, one row per condition; :mod:`rtgait.core.lipm.pattern` builds the same solution for footstep
plans without a dense solve.
"""

from __future__ import annotations

import numpy as np

from rtgait.core.lipm.bvp import bvp_matrix
from rtgait.core.lipm.closed_form import CogTrajectory, particular_matrix
from rtgait.core.lipm.spline import PiecewisePolynomial, polynomial_derivative_rows

FIRST_SEGMENT_DEGREES = (2, 4)
"""Quadratic: the paper's minimal variant (ZMP positions only). Quartic: ZMP positions and velocities."""

STATE_INPUTS = 5
"""Leading inputs: current ZMP, current ZMP velocity, current COG, current COG velocity, terminal COG."""

MIN_REST_W_T = 0.25
"""Shortest last segment, as ``w * T_m``, brought to rest here and by the plan operators (0.071 s at 0.8 m height).

Why: stopping the COG in ``T`` needs ``alpha ~ 30 (c_end - zeta) / (w T)`` (see the module docstring), and the
bump's monomial coefficients and COG polynomial part (``A_0 = 24 alpha / (w T)^4 + ...``) cancel against ``V``
and ``W``. Measured on walks at 0.3-1.2 m COG height: at ``w T = 0.2`` the end velocity is still zero to
~1e-9 m/s, but the bump already peaks at 6-7 times the COG's remaining offset (0.2-0.5 m: the ZMP leaves any
sole); at ``w T = 0.1`` the error reaches 1e-8 m/s and at 0.003 (1 ms) the plan is centimetres off the
pendulum and does not stop. Short settle phases are physically pointless anyway: the ZMP would leave the feet."""

REST_BUMP_DEGREE = 4
"""Degree of :func:`rest_bump`: the lowest that vanishes with its first derivative at both ends."""


def rest_bump(duration: float | np.ndarray) -> np.ndarray:
    """Ascending coefficients ``(..., 5)`` of ``s(tau) = tau^2 (T - tau)^2 / T^4`` for ``T = duration`` (s).

    ``s(0) = s'(0) = s(T) = s'(T) = 0`` and ``s(T/2) = 1/16``: dimensionless, so ``alpha s`` is in m.
    """
    T = np.asarray(duration, dtype=float)[..., None]
    zero = np.zeros_like(T)
    return np.concatenate([zero, zero, T**-2, -2.0 * T**-3, T**-4], axis=-1)


def check_rest_duration(duration: float, w: float) -> None:
    """ValueError if a last segment of ``duration`` (s) is too short to bring the COG to rest (:data:`MIN_REST_W_T`)."""
    if not w * duration >= MIN_REST_W_T:
        raise ValueError(
            f"settle duration (the last segment) must be at least {MIN_REST_W_T:g} / w = {MIN_REST_W_T / w:.3g} s "
            f"to bring the COG to rest at w = {w:.4g} 1/s, got {duration:.6g} s"
        )


class ConnectionSolver:
    """Solution operator of the connected plan for one timing pattern.

    Args:
        durations: segment durations (s); segment 1 is the free double-support segment; at least 2 segments.
        w: pendulum frequency (1/s).
        degree: polynomial degree of the given (reference) segments 2..m.
        first_degree: degree of the unknown segment-1 ZMP polynomial, 4 (default) or 2.
        terminal_rest: also bring the COG to rest at the end (``c'(t_m) = 0``) with the unknown amplitude
            ``alpha`` of :func:`rest_bump` added to segment ``m``'s ZMP (see the module docstring).

    Inputs, per axis, are ordered ``[p0, dp0, c0, dc0, c_end, a_2, ..., a_m]`` with ``a_j`` the
    ``degree + 1`` ascending coefficients of segment ``j``. Unknowns are ``[b_0..b_q, V_1, W_1, ..., V_m, W_m]``,
    followed by ``alpha`` (m) with ``terminal_rest``.
    """

    def __init__(
        self,
        durations: np.ndarray,
        w: float,
        degree: int = 3,
        first_degree: int = 4,
        terminal_rest: bool = False,
    ) -> None:
        durations = np.asarray(durations, dtype=float)
        if durations.ndim != 1 or durations.size < 2:
            raise ValueError("a connected plan needs at least 2 segments (the free one and a reference)")
        if np.any(~np.isfinite(durations)) or np.any(durations <= 0):
            raise ValueError(f"durations must be finite and > 0 s, got {durations.tolist()}")
        if first_degree not in FIRST_SEGMENT_DEGREES:
            raise ValueError(f"first_degree must be one of {FIRST_SEGMENT_DEGREES}, got {first_degree}")
        self.durations = durations
        self.w = float(w)
        self.degree = int(degree)
        self.first_degree = int(first_degree)
        self.terminal_rest = bool(terminal_rest)
        if self.terminal_rest:
            check_rest_duration(durations[-1], self.w)
        M, R = self._assemble()
        self.operator = np.linalg.solve(M, R)
        """Dense map from inputs to unknowns, shape ``(n_unknowns, n_inputs)``."""

    @property
    def n_inputs(self) -> int:
        return STATE_INPUTS + (self.durations.size - 1) * (self.degree + 1)

    @property
    def n_unknowns(self) -> int:
        return self.first_degree + 1 + 2 * self.durations.size + self.terminal_rest

    def _assemble(self) -> tuple[np.ndarray, np.ndarray]:
        m, n, q, w = self.durations.size, self.degree, self.first_degree, self.w
        nb = q + 1
        n_unknowns = self.n_unknowns
        M = np.zeros((n_unknowns, n_unknowns))
        R = np.zeros((n_unknowns, self.n_inputs))
        T1 = self.durations[0]
        a2 = slice(STATE_INPUTS, STATE_INPUTS + n + 1)  # inputs holding segment 2's coefficients

        # ZMP conditions on segment 1 (eqs. 13-14).
        row = 0
        M[row, :nb] = polynomial_derivative_rows(q, 0.0, 0)
        R[row, 0] = 1.0
        row += 1
        M[row, :nb] = polynomial_derivative_rows(q, T1, 0)
        R[row, a2] = polynomial_derivative_rows(n, 0.0, 0)
        row += 1
        if q >= 4:
            M[row, :nb] = polynomial_derivative_rows(q, 0.0, 1)
            R[row, 1] = 1.0
            row += 1
            M[row, :nb] = polynomial_derivative_rows(q, T1, 1)
            R[row, a2] = polynomial_derivative_rows(n, 0.0, 1)
            row += 1

        # COG conditions: the BVP rows (initial position, junctions, terminal) plus the initial velocity.
        cog_rows = slice(row, row + 2 * m)
        M[cog_rows, nb : nb + 2 * m] = bvp_matrix(self.durations, w)
        Qb = particular_matrix(q, w)
        Qa = particular_matrix(n, w)
        M[row, :nb] = Qb[0]  # c(0) = V_1 + A_0(b)
        R[row, 2] = 1.0
        # Junction 1: the polynomial part of segment 1 depends on b.
        M[row + 1, :nb] = polynomial_derivative_rows(q, T1, 0) @ Qb
        M[row + 2, :nb] = polynomial_derivative_rows(q, T1, 1) @ Qb
        for j in range(1, m):  # junction between segment j and j+1 (0-based j-1, j)
            nxt = slice(STATE_INPUTS + (j - 1) * (n + 1), STATE_INPUTS + j * (n + 1))
            R[row + 2 * j - 1, nxt] += Qa[0]
            R[row + 2 * j, nxt] += polynomial_derivative_rows(n, 0.0, 1) @ Qa  # A_1, also for degree 0
            if j >= 2:  # segment j (1-based) is a reference segment: its end values move to the rhs
                cur = slice(STATE_INPUTS + (j - 2) * (n + 1), STATE_INPUTS + (j - 1) * (n + 1))
                R[row + 2 * j - 1, cur] -= polynomial_derivative_rows(n, self.durations[j - 1], 0) @ Qa
                R[row + 2 * j, cur] -= polynomial_derivative_rows(n, self.durations[j - 1], 1) @ Qa
        last = row + 2 * m - 1
        R[last, 4] = 1.0
        R[last, STATE_INPUTS + (m - 2) * (n + 1) : STATE_INPUTS + (m - 1) * (n + 1)] -= (
            polynomial_derivative_rows(n, self.durations[-1], 0) @ Qa
        )
        # Initial COG velocity (eq. 15): dc(0) = w W_1 + A_1(b).
        vel_row = row + 2 * m
        M[vel_row, :nb] = Qb[1]
        M[vel_row, nb + 1] = w
        R[vel_row, 3] = 1.0
        if self.terminal_rest:
            self._assemble_terminal_rest(M, R, row)
        return M, R

    def _assemble_terminal_rest(self, M: np.ndarray, R: np.ndarray, row: int) -> None:
        """Column of ``alpha`` and the row ``c'(t_m) = 0``; ``row`` is the first COG row (initial position)."""
        m, n, w = self.durations.size, self.degree, self.w
        Tm = self.durations[-1]
        alpha = M.shape[1] - 1
        bump = particular_matrix(REST_BUMP_DEGREE, w) @ rest_bump(Tm)  # COG polynomial part per unit alpha
        # Junction m-1 | m: the BVP rows read "end of m-1 minus start of m = rhs"; the bump's start values sit
        # in segment m's polynomial part, so they enter with a minus sign. The bump itself is zero there, but
        # its COG polynomial part A = Q s is not: A_0 = 2 / (w T)^2 + 24 / (w T)^4, A_1 = -12 / (w^2 T^3).
        M[row + 2 * m - 3, alpha] = -bump[0]
        M[row + 2 * m - 2, alpha] = -bump[1]
        # Terminal position: V_m cosh + W_m sinh + A_m(T_m) + alpha A_s(T_m) = c_end.
        M[row + 2 * m - 1, alpha] = polynomial_derivative_rows(REST_BUMP_DEGREE, Tm, 0) @ bump
        # Terminal velocity: w (V_m sinh + W_m cosh) + A_m'(T_m) + alpha A_s'(T_m) = 0.
        rest_row = M.shape[0] - 1
        M[rest_row, alpha - 2] = w * np.sinh(w * Tm)
        M[rest_row, alpha - 1] = w * np.cosh(w * Tm)
        M[rest_row, alpha] = polynomial_derivative_rows(REST_BUMP_DEGREE, Tm, 1) @ bump
        last = slice(STATE_INPUTS + (m - 2) * (n + 1), STATE_INPUTS + (m - 1) * (n + 1))
        R[rest_row, last] = -polynomial_derivative_rows(n, Tm, 1) @ particular_matrix(n, w)

    def inputs(
        self,
        reference: np.ndarray,
        zmp: np.ndarray,
        zmp_vel: np.ndarray,
        cog: np.ndarray,
        cog_vel: np.ndarray,
        cog_end: np.ndarray,
    ) -> np.ndarray:
        """Stack the input vector ``(n_inputs, d)`` from reference coefficients ``(m - 1, degree + 1, d)``."""
        reference = np.asarray(reference, dtype=float)
        expected = (self.durations.size - 1, self.degree + 1)
        if reference.shape[:2] != expected:
            raise ValueError(f"reference coefficients must have shape {expected} + (axes,), got {reference.shape}")
        state = np.array([zmp, zmp_vel, cog, cog_vel, cog_end], dtype=float).reshape(STATE_INPUTS, -1)
        return np.concatenate([state, reference.reshape(-1, reference.shape[2])])

    def solve(
        self,
        t0: float,
        reference: np.ndarray,
        zmp: np.ndarray,
        zmp_vel: np.ndarray,
        cog: np.ndarray,
        cog_vel: np.ndarray,
        cog_end: np.ndarray,
    ) -> CogTrajectory:
        """Connected plan starting at absolute time ``t0`` (s) from the current ZMP/COG state (m, m/s).

        ``reference`` holds the ZMP coefficients of segments 2..m, shape ``(m - 1, degree + 1, d)``.
        """
        x = self.inputs(reference, zmp, zmp_vel, cog, cog_vel, cog_end)
        if not np.all(np.isfinite(x)):
            raise ValueError("connection inputs must be finite (NaN or inf in the state or reference)")
        u = self.operator @ x
        return self.trajectory(t0, u, np.asarray(reference, dtype=float))

    def trajectory(self, t0: float, unknowns: np.ndarray, reference: np.ndarray) -> CogTrajectory:
        """Assemble the :class:`CogTrajectory` from solved unknowns ``(n_unknowns, d)``."""
        nb = self.first_degree + 1
        width = max(nb, self.degree + 1, REST_BUMP_DEGREE + 1 if self.terminal_rest else 0)
        m, d = self.durations.size, unknowns.shape[1]
        coeffs = np.zeros((m, width, d))
        coeffs[0, :nb] = unknowns[:nb]
        coeffs[1:, : self.degree + 1] = reference
        if self.terminal_rest:
            coeffs[-1, : REST_BUMP_DEGREE + 1] += rest_bump(self.durations[-1])[:, None] * unknowns[-1]
        zmp = PiecewisePolynomial(t0, self.durations, coeffs)
        VW = unknowns[nb : nb + 2 * m]
        return CogTrajectory(zmp=zmp, V=VW[0::2], W=VW[1::2], w=self.w)
