"""Simultaneous COG/ZMP planning: a new plan that connects continuously to the one being executed (eqs. 13-16).

A plain BVP fixes the COG position at both ends but not the initial COG velocity, so splicing it onto a
running trajectory would make the velocity jump. Here the ZMP polynomial of the first segment (a double
support phase) is unknown as well. Its coefficients ``b`` join ``V_j, W_j`` as unknowns and the conditions are:

* ZMP position (and, for the quartic, velocity) at the start of segment 1 equals the current ZMP (eq. 13);
* ZMP position (and velocity) at the end of segment 1 equals the start of segment 2 (eq. 14);
* COG position and velocity at the start equal the current COG state (eqs. 8, 15);
* COG position and velocity continuous at every junction, COG position prescribed at the end (eqs. 9-12).

Everything is linear in the inputs and the matrix depends on durations and ``w`` only, so each timing pattern
gets one dense solution operator ``S`` with ``unknowns = S @ inputs``: one matrix product per replan.
"""

from __future__ import annotations

import numpy as np

from rtgait.core.bvp import bvp_matrix
from rtgait.core.lipm import CogTrajectory, particular_matrix
from rtgait.core.spline import PiecewisePolynomial, polynomial_derivative_rows

FIRST_SEGMENT_DEGREES = (2, 4)
"""Quadratic: the paper's minimal variant (ZMP positions only). Quartic: ZMP positions and velocities."""

STATE_INPUTS = 5
"""Leading inputs: current ZMP, current ZMP velocity, current COG, current COG velocity, terminal COG."""


class ConnectionSolver:
    """Solution operator of the connected plan for one timing pattern.

    Args:
        durations: segment durations (s); segment 1 is the free double-support segment; at least 2 segments.
        w: pendulum frequency (1/s).
        degree: polynomial degree of the given (reference) segments 2..m.
        first_degree: degree of the unknown segment-1 ZMP polynomial, 4 (default) or 2.

    Inputs, per axis, are ordered ``[p0, dp0, c0, dc0, c_end, a_2, ..., a_m]`` with ``a_j`` the
    ``degree + 1`` ascending coefficients of segment ``j``. Unknowns are ``[b_0..b_q, V_1, W_1, ..., V_m, W_m]``.
    """

    def __init__(self, durations: np.ndarray, w: float, degree: int = 3, first_degree: int = 4) -> None:
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
        M, R = self._assemble()
        self.operator = np.linalg.solve(M, R)
        """Dense map from inputs to unknowns, shape ``(n_unknowns, n_inputs)``."""

    @property
    def n_inputs(self) -> int:
        return STATE_INPUTS + (self.durations.size - 1) * (self.degree + 1)

    def _assemble(self) -> tuple[np.ndarray, np.ndarray]:
        m, n, q, w = self.durations.size, self.degree, self.first_degree, self.w
        nb = q + 1
        n_unknowns = nb + 2 * m
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
        M[cog_rows, nb:] = bvp_matrix(self.durations, w)
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
        return M, R

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
        width = max(nb, self.degree + 1)
        m, d = self.durations.size, unknowns.shape[1]
        coeffs = np.zeros((m, width, d))
        coeffs[0, :nb] = unknowns[:nb]
        coeffs[1:, : self.degree + 1] = reference
        zmp = PiecewisePolynomial(t0, self.durations, coeffs)
        return CogTrajectory(zmp=zmp, V=unknowns[nb::2], W=unknowns[nb + 1 :: 2], w=self.w)
