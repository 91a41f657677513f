"""One precomputed linear operator per timing pattern: from footstep anchors to a complete connected plan.

For a fixed sequence of phases (their kinds and durations) everything in a replan is linear in a handful of
numbers per axis: the current ZMP and COG state and the ZMP *anchors* (the points the reference ZMP rests on
or travels between). Single support and settling hold the ZMP at an anchor; double support carries it from one
anchor to the next along a cubic with zero end velocities. The first segment, of any kind (a whole double
support, or the remainder of whatever phase the robot is in when it replans), is the free polynomial of the
connection (:mod:`rtgait.core.lipm.connect`): it ends at ``anchor_0``. A plan whose last phase is ``"settle"`` also
ends at rest (COG velocity zero, hence acceleration zero too): the settle segment's ZMP gets the bump
``alpha tau^2 (T - tau)^2 / T^4`` (:func:`~rtgait.core.lipm.connect.rest_bump`). The composed map is one matrix
``G``; a replan is ``G @ y``, and the result already holds, per segment, the ZMP coefficients ``a``, the COG
polynomial part ``A`` and ``V, W``.

How ``G`` is built (the same solution as :class:`~rtgait.core.lipm.connect.ConnectionSolver` composed with the anchor
map, found without a dense solve):

1. ZMP coefficients, per segment ``j`` and per input column, are polynomials in ``1/T_j`` whose coefficient
   tensors depend on the phase kinds only: ``a_j = sum_k T_j^-k C_jk``. Two extra columns carry the two
   scalar unknowns per axis: ``beta``, the amplitude of the free first segment's shape that vanishes in its
   ZMP conditions (``tau^2 (T_1 - tau)^2 / T_1^4`` for the quartic, ``tau (T_1 - tau) / T_1^2`` for the
   quadratic), and ``gamma``: the rest bump's ``alpha`` when the plan ends in ``"settle"``, otherwise the
   terminal divergent component ``xi(t_m)``. So are ``A_j = Q a_j`` (eqs. 6-7) and the particular parts
   ``(A_j +- A_j'/w)`` at both ends of the segment, which are Laurent polynomials ``sum_p T_j^p D_jp``,
   ``p = -4..4``: ``D`` is cached per (kinds, first-segment degree, ``w``) and one product with the powers
   of the durations gives all of them.
2. The convergent part ``S_j = V_j - W_j`` is swept forward from ``zeta(t_0) = c0 - dc0/w`` and the divergent
   part ``U_j = V_j + W_j`` backward from ``xi(t_m)`` (:func:`~rtgait.core.lipm.bvp.component_propagators`): COG
   position and velocity are continuous by construction, and no growing exponential is formed.
3. Two conditions remain per column, linear in ``(beta, gamma)``: ``xi(t_0) = c0 + dc0/w`` (the initial COG
   velocity, eq. 15) and, at the end, ``zeta(t_m) = xi(t_m) = c_end`` (rest) or ``(xi + zeta)(t_m) / 2 =
   c_end`` (position only, eq. 12). A 2 x 2 solve per timing gives ``beta, gamma`` for every column.

Everything is vectorised over a leading batch of timings, so several operators for the same phase kinds (for
instance candidate first-segment durations) cost little more than one (:meth:`PlanOperator.for_first_durations`;
build costs in ``docs/design/planner.md``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import lru_cache
from typing import NamedTuple, get_args

import numpy as np

from rtgait.core.geometry.footsteps import PhaseKind
from rtgait.core.lipm.bvp import component_propagators
from rtgait.core.lipm.closed_form import particular_matrix
from rtgait.core.lipm.connect import FIRST_SEGMENT_DEGREES, check_rest_duration

DEGREE = 4
"""Storage degree of every segment polynomial (the free quartic and the rest bump are the highest)."""
SEGMENT_WIDTH = 2 * (DEGREE + 1) + 2
"""Per segment and axis: ``a_0..a_4, A_0..A_4, V, W``."""

MOVING_KINDS = frozenset({"start", "double", "end"})
"""Phases in which the reference ZMP travels to the next anchor."""
PHASE_KINDS = frozenset(get_args(PhaseKind))
"""Every phase kind a plan may hold (:data:`~rtgait.core.geometry.footsteps.PhaseKind`)."""
REST_KIND = "settle"
"""A plan whose last phase is of this kind ends at rest."""

_STATE_COLUMNS = 4
"""Leading columns of ``y``: ``p0, dp0, c0, dc0``; the anchors follow."""


@dataclass(frozen=True)
class PatternKey:
    """What a plan operator depends on: phase kinds and durations (s), ``w`` (1/s), segment-1 degree."""

    kinds: tuple[PhaseKind, ...]
    durations: tuple[float, ...]
    w: float
    first_degree: int


_ROWS = SEGMENT_WIDTH + 4
"""Rows computed per segment and column: the stored ``a_0..a_4, A_0..A_4, V, W`` (``V, W`` filled in after the
sweeps) and, of the particular part ``A`` (m), ``xi_start = (A + A'/w)(0), zeta_start = (A - A'/w)(0),
xi_end = (A + A'/w)(T), zeta_end = (A - A'/w)(T)``."""
_V, _W = SEGMENT_WIDTH - 2, SEGMENT_WIDTH - 1
_XI_START, _ZETA_START, _XI_END, _ZETA_END = range(SEGMENT_WIDTH, _ROWS)
LAURENT_POWERS = np.arange(-DEGREE, DEGREE + 1, dtype=float)
"""Every row is a Laurent polynomial ``sum_p T^p D_p`` in the segment duration, ``p = -4..4``."""


@lru_cache(maxsize=256)
def _zmp_tensor(kinds: tuple[str, ...], first_degree: int) -> np.ndarray:
    """``C[j, k, i, c]``: ZMP coefficient ``i`` of segment ``j`` per unit of column ``c`` is ``sum_k T_j^-k C``.

    Columns are ``y``'s (``4 + n_anchors``) followed by ``beta`` and ``gamma`` (module docstring).
    """
    m = len(kinds)
    n_cols = _STATE_COLUMNS + 1 + sum(kind in MOVING_KINDS for kind in kinds[1:])
    beta, gamma = n_cols, n_cols + 1
    p0, dp0, end0 = 0, 1, _STATE_COLUMNS  # columns of the current ZMP, its velocity, anchor_0
    C = np.zeros((m, DEGREE + 1, DEGREE + 1, n_cols + 2))

    # Segment 1, the free polynomial: a fixed part that meets the ZMP conditions plus beta times a shape that
    # vanishes in all of them, so that the ZMP conditions hold whatever beta the COG conditions ask for.
    C[0, 0, 0, p0] = 1.0
    if first_degree == 4:
        # Cubic Hermite: p(0) = p0, p'(0) = dp0, p(T) = anchor_0, p'(T) = 0 (every reference segment starts at
        # rest); p = p0 + dp0 tau + (3 D / T^2 - 2 dp0 / T) tau^2 + (-2 D / T^3 + dp0 / T^2) tau^3, D = a0 - p0.
        C[0, 2, 2, [p0, end0]] = -3.0, 3.0
        C[0, 3, 3, [p0, end0]] = 2.0, -2.0
        C[0, 0, 1, dp0] = 1.0
        C[0, 1, 2, dp0] = -2.0
        C[0, 2, 3, dp0] = 1.0
        C[0, [2, 3, 4], [2, 3, 4], beta] = 1.0, -2.0, 1.0  # tau^2 (T - tau)^2 / T^4
    else:
        # Positions only (the paper's minimal variant): the chord from p0 to anchor_0 plus beta tau (T - tau) / T^2.
        C[0, 1, 1, [p0, end0]] = -1.0, 1.0
        C[0, [1, 2], [1, 2], beta] = 1.0, -1.0

    # Reference segments: hold the current anchor, or carry it to the next one along the transfer cubic.
    anchor = end0
    for j, kind in enumerate(kinds[1:], start=1):
        C[j, 0, 0, anchor] = 1.0
        if kind in MOVING_KINDS:
            C[j, 2, 2, [anchor, anchor + 1]] = -3.0, 3.0
            C[j, 3, 3, [anchor, anchor + 1]] = 2.0, -2.0
            anchor += 1
    if kinds[-1] == REST_KIND:
        C[m - 1, [2, 3, 4], [2, 3, 4], gamma] = 1.0, -2.0, 1.0  # rest_bump: alpha tau^2 (T - tau)^2 / T^4
    C.setflags(write=False)
    return C


@lru_cache(maxsize=1)
def _laurent_maps() -> tuple[np.ndarray, np.ndarray]:
    """``(L0, L1)``, read-only: row ``r`` (:data:`_ROWS`) takes ``(L0 + L1 / w)[r, s, k, p]`` times the term
    ``T^-k`` of ``z_s``, ``z = [a_0..a_4, A_0..A_4]``, as a multiple of ``T^(p - DEGREE)``. Rows of ``a`` and
    ``A`` copy their coefficient; the start rows are ``A_0 +- A_1/w``; the end rows ``A(T) +- A'(T)/w =
    sum_i A_i (T^i +- i T^(i-1) / w)``. Split by powers of ``1/w`` so that a new ``w`` costs one sum."""
    n = DEGREE + 1
    L0 = np.zeros((_ROWS, 2 * n, n, 2 * DEGREE + 1))
    L1 = np.zeros_like(L0)
    for k in range(n):
        here = DEGREE - k  # index of T^-k
        for s in range(2 * n):
            L0[s, s, k, here] = 1.0
        L0[[_XI_START, _ZETA_START], n, k, here] = 1.0
        L1[[_XI_START, _ZETA_START], n + 1, k, here] = 1.0, -1.0
        for i in range(n):
            L0[[_XI_END, _ZETA_END], n + i, k, here + i] = 1.0
            if i >= 1:
                L1[[_XI_END, _ZETA_END], n + i, k, here + i - 1] = i, -i
    L0.setflags(write=False)
    L1.setflags(write=False)
    return L0, L1


@lru_cache(maxsize=64)
def _laurent_rows(w: float) -> np.ndarray:
    """The Laurent maps for one ``w`` acting on the ZMP coefficients ``a`` directly (``z = [a; Q a]``), flattened
    to ``((i, k), (r, p))``: ``rows[i * 5 + k, r * 9 + p]`` is what the term ``T^-k`` of ``a_i`` adds to row
    ``r`` at ``T^(p - DEGREE)`` (read-only)."""
    L0, L1 = _laurent_maps()
    z_of_a = np.vstack([np.eye(DEGREE + 1), particular_matrix(DEGREE, w)])
    rows = np.einsum("rskp,si->ikrp", L0 + L1 / w, z_of_a).reshape((DEGREE + 1) ** 2, -1)
    rows.setflags(write=False)
    return rows


class _Pattern(NamedTuple):
    """What a plan operator depends on besides the durations (cached per kinds, first degree and ``w``).

    ``laurent[j, p, r * (n_cols + 2) + c]``: row ``r`` (:data:`_ROWS`) of segment ``j`` per unit of column
    ``c`` is ``sum_p T_j^(p - 4) laurent[j, p, ...]``. The vectors (over the ``n_cols + 2`` columns) are the
    initial ``zeta`` and ``xi`` (``c0 -+ dc0/w``), the terminal ``xi`` and the end condition's target.
    """

    n_cols: int
    laurent: np.ndarray
    zeta0: np.ndarray
    xi0: np.ndarray
    xi_final: np.ndarray
    end_target: np.ndarray


@lru_cache(maxsize=256)
def _pattern(kinds: tuple[str, ...], first_degree: int, w: float) -> _Pattern:
    C = _zmp_tensor(kinds, first_degree)
    m, n_extended = C.shape[0], C.shape[-1]
    n_cols = n_extended - 2
    rest = kinds[-1] == REST_KIND
    by_coefficient = C.transpose(0, 3, 2, 1).reshape(m * n_extended, -1)  # ((j, c), (i, k))
    D = (by_coefficient @ _laurent_rows(w)).reshape(m, n_extended, _ROWS, 2 * DEGREE + 1)  # (j, c, r, p)
    laurent = np.ascontiguousarray(D.transpose(0, 3, 2, 1)).reshape(m, 2 * DEGREE + 1, _ROWS * n_extended)
    unit = np.eye(n_extended)
    c_end = unit[n_cols - 1]  # the last anchor
    # xi(t_m): c_end at rest; otherwise the unknown gamma, with the end condition (xi + zeta)(t_m) = 2 c_end.
    xi_final = c_end if rest else unit[n_cols + 1]
    end_target = c_end if rest else 2.0 * c_end - xi_final
    vectors = (unit[2] - unit[3] / w, unit[2] + unit[3] / w, xi_final, end_target)
    for array in (laurent, *vectors):
        array.setflags(write=False)
    return _Pattern(n_cols, laurent, *vectors)


def _validate(kinds: tuple[str, ...], durations: np.ndarray, w: float, first_degree: int) -> None:
    """ValueError naming the field of a pattern no operator exists for (plain Python: this runs per build)."""
    if len(kinds) < 2:
        raise ValueError(f"kinds: a plan needs at least 2 segments (the free one and a reference), got {kinds}")
    if not PHASE_KINDS.issuperset(kinds):
        raise ValueError(f"kinds must be among {sorted(PHASE_KINDS)}, got {kinds}")
    if durations.shape[-1] != len(kinds):
        raise ValueError(f"durations must have one entry per phase ({len(kinds)}), got shape {durations.shape}")
    values = durations.ravel().tolist()
    if not all(0.0 < value < math.inf for value in values):  # also false for NaN
        raise ValueError(f"durations must be finite and > 0 s, got {values}")
    if not 0.0 < w < math.inf:
        raise ValueError(f"w must be a finite frequency > 0 (1/s), got {w}")
    if first_degree not in FIRST_SEGMENT_DEGREES:
        raise ValueError(f"first_degree must be one of {FIRST_SEGMENT_DEGREES}, got {first_degree}")
    if kinds[-1] == REST_KIND:
        check_rest_duration(min(values[len(kinds) - 1 :: len(kinds)]), w)


def plan_operator_matrices(
    kinds: tuple[PhaseKind, ...], durations: np.ndarray, w: float, first_degree: int
) -> np.ndarray:
    """``G`` for every row of ``durations`` ``(B, m)`` (s): shape ``(B, m * SEGMENT_WIDTH, 4 + n_anchors)``.

    See the module docstring for the method; :class:`PlanOperator` wraps one ``G``.
    """
    durations = np.asarray(durations, dtype=float)
    if durations.ndim != 2:
        raise ValueError(f"durations must have shape (batch, {len(kinds)}), got {durations.shape}")
    w = float(w)
    _validate(tuple(kinds), durations, w, first_degree)
    return _matrices(_pattern(tuple(kinds), int(first_degree), w), durations, w)


def _matrices(pattern: _Pattern, durations: np.ndarray, w: float) -> np.ndarray:
    """The build itself, for validated ``durations`` ``(B, m)``: a few batched array operations."""
    batch, m = durations.shape
    n_cols = pattern.n_cols
    # 1. a, A and the particular parts of xi and zeta at both segment ends: (B, m, _ROWS, n_cols + 2).
    # One product of the durations' Laurent powers with the cached tensor: no per-segment Python work.
    data = (durations[..., None, None] ** LAURENT_POWERS) @ pattern.laurent
    data = data.reshape(batch, m, _ROWS, n_cols + 2)
    xi_start, zeta_start = data[:, :, _XI_START], data[:, :, _ZETA_START]
    xi_end, zeta_end = data[:, :, _XI_END], data[:, :, _ZETA_END]

    # 2. Sweeps: S = V - W forward from zeta(t_0), U = V + W backward from xi(t_m).
    forward, backward = component_propagators(durations, w)
    jumps = -zeta_start
    jumps[:, 0] += pattern.zeta0
    jumps[:, 1:] += zeta_end[:, :-1]
    defects = -xi_end
    defects[:, :-1] += xi_start[:, 1:]
    defects[:, -1] += pattern.xi_final
    S = forward @ jumps
    U = backward @ defects

    # 3. xi(t_0) = c0 + dc0/w and the end condition, linear in (beta, gamma): solve for them per column.
    residual = np.empty((batch, 2, n_cols + 2))
    np.subtract(U[:, 0] + xi_start[:, 0], pattern.xi0, out=residual[:, 0])
    zeta_final = S[:, -1] * backward[:, -1, -1:] + zeta_end[:, -1]  # backward[-1, -1] = e^{-w T_m}
    np.subtract(zeta_final, pattern.end_target, out=residual[:, 1])
    theta = np.linalg.solve(residual[..., n_cols:], -residual[..., :n_cols])  # (B, 2, n_cols)

    np.add(U, S, out=data[:, :, _V])
    np.subtract(U, S, out=data[:, :, _W])
    data[:, :, _V : _W + 1] *= 0.5  # V = (U + S) / 2, W = (U - S) / 2
    stored = data[:, :, :SEGMENT_WIDTH]
    G = stored[..., :n_cols] + stored[..., n_cols:] @ theta[:, None]
    return G.reshape(batch, m * SEGMENT_WIDTH, n_cols)


class PlanOperator:
    """``G`` for one :class:`PatternKey`: ``segments = (G @ y).reshape(m, SEGMENT_WIDTH, d)``.

    ``y`` is ``[p0, dp0, c0, dc0, anchor_0, ..., anchor_{K-1}]`` per axis: current ZMP (m), ZMP velocity (m/s),
    COG (m), COG velocity (m/s), and the anchors (m); ``anchor_0`` is where segment 1 ends (whatever its kind:
    for the remainder of a single support, the stance foot's anchor) and each later moving phase goes to the
    next anchor; the last anchor is also the terminal COG position. A plan whose last phase is ``"settle"`` ends
    with the COG at rest over it.
    """

    def __init__(self, key: PatternKey) -> None:
        durations = np.asarray(key.durations, dtype=float)
        G = plan_operator_matrices(key.kinds, durations[None], key.w, key.first_degree)[0]
        self._set(key, durations, G)

    def _set(self, key: PatternKey, durations: np.ndarray, G: np.ndarray) -> None:
        self.key = key
        self.durations = durations
        self.n_segments = durations.size
        self.n_anchors = G.shape[1] - _STATE_COLUMNS
        self.G = G

    @classmethod
    def for_durations(cls, key: PatternKey, durations: np.ndarray) -> list[PlanOperator]:
        """Operators of ``key``'s phase kinds for every row of ``durations`` ``(B, m)`` (s), built in one
        vectorised pass (for candidate step timings)."""
        durations = np.asarray(durations, dtype=float)
        Gs = plan_operator_matrices(key.kinds, durations, key.w, key.first_degree)
        operators = []
        for row, G in zip(durations, Gs, strict=True):
            operator = cls.__new__(cls)
            operator._set(replace(key, durations=tuple(row.tolist())), row, G)
            operators.append(operator)
        return operators

    @classmethod
    def for_first_durations(cls, key: PatternKey, first_durations: Sequence[float] | np.ndarray) -> list[PlanOperator]:
        """Operators of ``key`` with its first duration replaced by each of ``first_durations`` (s), built in
        one vectorised pass (for choosing a step timing, or the remainder of a phase, among candidates)."""
        first = np.atleast_1d(np.asarray(first_durations, dtype=float))
        if first.ndim != 1 or first.size == 0:
            raise ValueError(f"first_durations must be a non-empty 1-D sequence (s), got shape {first.shape}")
        durations = np.repeat(np.asarray(key.durations, dtype=float)[None], first.size, axis=0)
        durations[:, 0] = first
        Gs = plan_operator_matrices(key.kinds, durations, key.w, key.first_degree)
        operators = []
        for row, G in zip(durations, Gs, strict=True):
            operator = cls.__new__(cls)
            operator._set(replace(key, durations=(float(row[0]), *key.durations[1:])), row, G)
            operators.append(operator)
        return operators

    def solve(self, y: np.ndarray) -> np.ndarray:
        """Per-segment data ``(m, SEGMENT_WIDTH, d)`` for stacked inputs ``y`` ``(4 + K, d)``."""
        return (self.G @ y).reshape(self.n_segments, SEGMENT_WIDTH, -1)


def segment_zmp_rows(G: np.ndarray, duration: float, n_times: int, segment: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Times (s, local to the segment) and the matrix ``M`` ``(n_times, n_inputs)`` with ``zmp(t_i) = M[i] @ y``.

    ``G`` is a plan operator (:class:`~rtgait.core.lipm.pattern.PlanOperator`); ``y`` its inputs, one column per axis.
    """
    if n_times < 2:
        raise ValueError(f"n_times must be >= 2, got {n_times}")
    times = np.linspace(0.0, duration, n_times)
    powers = times[:, None] ** np.arange(DEGREE + 1)[None, :]  # (n_times, DEGREE + 1)
    rows = 12 * segment
    return times, powers @ G[rows : rows + DEGREE + 1]
