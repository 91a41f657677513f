"""One precomputed linear operator per timing pattern: from footstep anchors to a complete connected plan.

For a fixed sequence of phases (their kinds and durations) everything in a replan is linear in a handful of
numbers per axis: the current ZMP and COG state and the ZMP *anchors* (the points the reference ZMP rests on
or travels between). Single support and settling hold the ZMP at an anchor; double support carries it from one
anchor to the next along a cubic with zero end velocities. Composing that map with the
:class:`~rtgait.core.connect.ConnectionSolver` operator gives one matrix ``G``; a replan is ``G @ y``, and the
result already holds, per segment, the ZMP coefficients ``a``, the COG polynomial part ``A`` and ``V, W``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rtgait.core.connect import STATE_INPUTS, ConnectionSolver
from rtgait.core.footsteps import PhaseKind
from rtgait.core.lipm import particular_matrix

DEGREE = 4
"""Storage degree of every segment polynomial (the free quartic is the highest)."""
REFERENCE_DEGREE = 3
"""Degree of the reference ZMP segments (cubic transfers in double support)."""
SEGMENT_WIDTH = 2 * (DEGREE + 1) + 2
"""Per segment and axis: ``a_0..a_4, A_0..A_4, V, W``."""

MOVING_KINDS = frozenset({"start", "double", "end"})
"""Phases in which the reference ZMP travels to the next anchor."""


def transfer_cubic(start: np.ndarray, end: np.ndarray, duration: float) -> np.ndarray:
    """Coefficients ``(4, d)`` of the cubic from ``start`` to ``end`` (m) with zero end velocities."""
    delta = np.asarray(end, dtype=float) - np.asarray(start, dtype=float)
    return np.array([start, np.zeros_like(delta), 3.0 * delta / duration**2, -2.0 * delta / duration**3])


@dataclass(frozen=True)
class PatternKey:
    """What a plan operator depends on: phase kinds and durations (s), ``w`` (1/s), segment-1 degree."""

    kinds: tuple[PhaseKind, ...]
    durations: tuple[float, ...]
    w: float
    first_degree: int


class PlanOperator:
    """``G`` for one :class:`PatternKey`: ``segments = (G @ y).reshape(m, SEGMENT_WIDTH, d)``.

    ``y`` is ``[p0, dp0, c0, dc0, anchor_0, ..., anchor_{K-1}]`` per axis: current ZMP (m), ZMP velocity (m/s),
    COG (m), COG velocity (m/s), and the anchors (m); ``anchor_0`` is where segment 1 ends and the last anchor
    is also the terminal COG position.
    """

    def __init__(self, key: PatternKey) -> None:
        if key.kinds[0] not in MOVING_KINDS:
            raise ValueError(f"a plan must start with a double-support phase, got {key.kinds[0]!r}")
        self.key = key
        durations = np.asarray(key.durations, dtype=float)
        m = durations.size
        self.n_segments = m
        self.n_anchors = 1 + sum(kind in MOVING_KINDS for kind in key.kinds[1:])
        solver = ConnectionSolver(durations, key.w, degree=REFERENCE_DEGREE, first_degree=key.first_degree)
        E = self._anchor_map(durations, solver.n_inputs)
        G = np.zeros((m * SEGMENT_WIDTH, 4 + self.n_anchors))
        Q = particular_matrix(DEGREE, key.w)
        nb = key.first_degree + 1
        unknowns = solver.operator @ E  # (n_unknowns, 4 + K)
        for j in range(m):
            a = np.zeros((DEGREE + 1, G.shape[1]))
            if j == 0:
                a[:nb] = unknowns[:nb]
            else:
                start = STATE_INPUTS + (j - 1) * (REFERENCE_DEGREE + 1)
                a[: REFERENCE_DEGREE + 1] = E[start : start + REFERENCE_DEGREE + 1]
            block = G[j * SEGMENT_WIDTH : (j + 1) * SEGMENT_WIDTH]
            block[: DEGREE + 1] = a
            block[DEGREE + 1 : 2 * (DEGREE + 1)] = Q @ a
            block[-2] = unknowns[nb + 2 * j]
            block[-1] = unknowns[nb + 2 * j + 1]
        self.G = G
        self.durations = durations

    def _anchor_map(self, durations: np.ndarray, n_inputs: int) -> np.ndarray:
        """Matrix ``E`` from ``y`` to the connection solver's inputs."""
        n_cols = 4 + self.n_anchors
        E = np.zeros((n_inputs, n_cols))
        E[0:4, 0:4] = np.eye(4)
        anchor = 0  # index of the anchor the reference ZMP is at
        for j, kind in enumerate(self.key.kinds[1:], start=1):
            rows = slice(STATE_INPUTS + (j - 1) * 4, STATE_INPUTS + j * 4)
            here = np.zeros(n_cols)
            here[4 + anchor] = 1.0
            if kind in MOVING_KINDS:
                there = np.zeros(n_cols)
                there[4 + anchor + 1] = 1.0
                E[rows] = transfer_cubic(here, there, durations[j])
                anchor += 1
            else:
                E[rows.start] = here
        E[4, 4 + self.n_anchors - 1] = 1.0  # terminal COG over the last anchor
        return E

    def solve(self, y: np.ndarray) -> np.ndarray:
        """Per-segment data ``(m, SEGMENT_WIDTH, d)`` for stacked inputs ``y`` ``(4 + K, d)``."""
        return (self.G @ y).reshape(self.n_segments, SEGMENT_WIDTH, -1)
