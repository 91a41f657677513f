"""The plan being executed, in the form a control tick reads, and the shape of a plan (its operator).

A replan is ``G @ y`` (:mod:`rtgait.core.lipm.pattern`): ``y`` holds the state the plan starts from and the anchors the
reference ZMP rests on. :class:`ActivePlan` keeps the result as Python floats per segment, evaluated lazily: one
sample is scalar arithmetic, cheaper than any numpy call.

Over height changes a plan has a vertical column too (``z``, ``None`` on level ground): the same operator applied to
the vertical state and the footholds' heights. It is the 3D-DCM/VRP form (Englsberger et al. 2015, ``docs/method.md``):
the virtual repellent point's height is the support height ``h(t)`` (anchors: the footholds' ``z``, carried between
them as the horizontal ZMP is) plus the constant ``zc = g / w^2``, so ``c_z - c_z'' / w^2 = h + zc`` is the
horizontal equation again, with the same ``w``, and the COG height above ``zc`` is its closed form.
"""

from __future__ import annotations

import math

import numpy as np

from rtgait.core.geometry.footsteps import Footstep
from rtgait.core.lipm.pattern import DEGREE, MOVING_KINDS, PlanOperator, segment_zmp_rows

EAGER_SEGMENTS = 1
"""Segments evaluated at replan time: the one that begins. Later ones are evaluated by the first sample that needs
them (a few microseconds, spread over the ticks instead of added to the replan's latency)."""


class ActivePlan:
    """The plan being executed, in the form the per-tick evaluation reads.

    ``segment(j)`` is ``(x, y)``, each ``[a0..a4, A0..A4, V, W]`` of segment ``j`` as Python floats: scalar
    arithmetic on floats beats numpy calls for one sample.
    """

    __slots__ = (
        "durations", "elapsed", "first_reference", "layout", "offsets", "phase0", "reference_offset", "segments",
        "t_start", "y", "z", "z_segments",
    )  # fmt: skip

    def __init__(
        self,
        t_start: float,
        phase0: int,
        layout: PlanLayout,
        y: np.ndarray,
        first_reference,
        reference_offset: float,
        elapsed: float = 0.0,
        z: np.ndarray | None = None,
    ) -> None:
        self.t_start = t_start
        self.z = z  # the vertical column (h0, dh0, cz0, dcz0, heights...), None on level ground
        self.z_segments: list | None = None if z is None else [None] * len(layout.durations)
        self.phase0 = phase0
        self.elapsed = elapsed  # time into phase0 at which the plan starts (s): 0 unless made mid-phase
        self.layout = layout
        self.y = y
        self.durations = layout.durations
        self.offsets = layout.offsets  # segment starts relative to t_start (s)
        self.first_reference = first_reference  # [axis] -> cubic coefficients of segment 1's reference ZMP
        self.reference_offset = reference_offset  # time into that cubic at which segment 1 starts (s)
        segments: list = [None] * len(layout.durations)
        eager = layout.eager_out  # EAGER_SEGMENTS = 1: the rows of segment 0, into the layout's scratch array
        np.matmul(layout.G_eager, y, out=eager)
        segments[0] = eager.T.tolist()  # copied out as floats, so the scratch array is free again at once
        self.segments = segments

    def segment(self, j: int) -> list[list[float]]:
        seg = self.segments[j]
        if seg is None:
            seg = self.segments[j] = (self.layout.G[12 * j : 12 * j + 12] @ self.y).T.tolist()
        return seg

    def z_segment(self, j: int) -> list[float]:
        """The vertical column's ``[h0..h4, A0..A4, V, W]`` of segment ``j`` (``z`` must be set)."""
        seg = self.z_segments[j]
        if seg is None:
            seg = self.z_segments[j] = (self.layout.G[12 * j : 12 * j + 12] @ self.z).tolist()
        return seg

    def height_at(self, j: int, tau: float, w: float) -> tuple[float, float, float, float, float]:
        """``(h, dh, cz, dcz, ddcz)`` on segment ``j`` at local time ``tau``: the support height under the VRP and
        the COG height above ``zc`` with its rates (m, m/s, m/s^2); zeros on level ground."""
        if self.z is None:
            return (0.0, 0.0, 0.0, 0.0, 0.0)
        a0, a1, a2, a3, a4, A0, A1, A2, A3, A4, V, W = self.z_segment(j)
        e = math.exp(w * tau)
        ch, sh = 0.5 * (e + 1.0 / e), 0.5 * (e - 1.0 / e)
        hom = V * ch + W * sh
        return (
            a0 + tau * (a1 + tau * (a2 + tau * (a3 + tau * a4))),
            a1 + tau * (2.0 * a2 + tau * (3.0 * a3 + tau * 4.0 * a4)),
            hom + A0 + tau * (A1 + tau * (A2 + tau * (A3 + tau * A4))),
            w * (V * sh + W * ch) + A1 + tau * (2.0 * A2 + tau * (3.0 * A3 + tau * 4.0 * A4)),
            w * w * hom + 2.0 * A2 + tau * (6.0 * A3 + tau * 12.0 * A4),
        )

    def height_state(self, t: float, w: float) -> list[float]:
        """``[h, dh, cz, dcz]`` at absolute time ``t`` (s): where a new plan's vertical column starts from."""
        if self.z is None:
            return [0.0, 0.0, 0.0, 0.0]
        if t == self.t_start:
            return self.z[:4].tolist()
        j, tau = self.locate(t)
        if j > 0 and tau < 1e-12:  # a phase start (every regular replan): the precomputed end rows, as end_state
            return (self.layout.end_state_rows(j - 1, w) @ self.z).tolist()
        return list(self.height_at(j, tau, w)[:4])

    def locate(self, t: float) -> tuple[int, float]:
        """Segment index and local time of absolute time ``t`` (s), clamped to the plan."""
        rel = t - self.t_start
        offsets = self.offsets
        j = len(offsets) - 1
        while j > 0 and rel < offsets[j]:
            j -= 1
        tau = min(max(rel - offsets[j], 0.0), self.durations[j])
        return j, tau

    def end_state(self, j: int, w: float) -> list[float]:
        """:meth:`state` at the end of segment ``j``: one precomputed product, as every replan needs it (Python
        floats: the replan goes on with scalar arithmetic)."""
        return (self.layout.end_state_rows(j, w) @ self.y).ravel().tolist()

    def cog_at(self, t: float, w: float) -> tuple[float, float, float, float]:
        """COG ``(cx, cy, dcx, dcy)`` at absolute time ``t`` (s, clamped to the plan; m, m/s): :meth:`state`'s COG
        part, with the same arithmetic, for the measured-state connection (which needs nothing else)."""
        j, tau = self.locate(t)
        e = math.exp(w * tau)
        ch, sh = 0.5 * (e + 1.0 / e), 0.5 * (e - 1.0 / e)
        (_, _, _, _, _, Ax0, Ax1, Ax2, Ax3, Ax4, Vx, Wx), (_, _, _, _, _, Ay0, Ay1, Ay2, Ay3, Ay4, Vy, Wy) = (
            self.segment(j)
        )
        return (
            Vx * ch + Wx * sh + Ax0 + tau * (Ax1 + tau * (Ax2 + tau * (Ax3 + tau * Ax4))),
            Vy * ch + Wy * sh + Ay0 + tau * (Ay1 + tau * (Ay2 + tau * (Ay3 + tau * Ay4))),
            w * (Vx * sh + Wx * ch) + Ax1 + tau * (2.0 * Ax2 + tau * (3.0 * Ax3 + tau * 4.0 * Ax4)),
            w * (Vy * sh + Wy * ch) + Ay1 + tau * (2.0 * Ay2 + tau * (3.0 * Ay3 + tau * 4.0 * Ay4)),
        )

    def state(self, j: int, tau: float, w: float) -> list[float]:
        """``[px, py, dpx, dpy, cx, cy, dcx, dcy]`` on segment ``j`` at local time ``tau`` (m, m/s)."""
        e = math.exp(w * tau)
        ch, sh = 0.5 * (e + 1.0 / e), 0.5 * (e - 1.0 / e)
        state = [0.0] * 8
        for axis, coeffs in enumerate(self.segment(j)):
            a0, a1, a2, a3, a4, A0, A1, A2, A3, A4, V, W = coeffs
            state[axis] = a0 + tau * (a1 + tau * (a2 + tau * (a3 + tau * a4)))
            state[2 + axis] = a1 + tau * (2.0 * a2 + tau * (3.0 * a3 + tau * 4.0 * a4))
            state[4 + axis] = V * ch + W * sh + A0 + tau * (A1 + tau * (A2 + tau * (A3 + tau * A4)))
            state[6 + axis] = w * (V * sh + W * ch) + A1 + tau * (2.0 * A2 + tau * (3.0 * A3 + tau * 4.0 * A4))
        return state


def height_column(
    previous: ActivePlan | None,
    t_start: float,
    w: float,
    heights: list[float] | None,
    n_anchors: int,
    standing: tuple[Footstep, Footstep],
) -> np.ndarray | None:
    """The vertical column of a plan starting at ``t_start`` (s): the vertical state of the plan before at that time
    (continuous across replanning, as the horizontal one; before the first plan, at rest over the standing feet) and
    the footholds' ``heights`` (m) under its ``n_anchors`` anchors (``None``: all 0); ``None`` while both are zero
    (level ground: the plan needs no vertical column)."""
    if previous is not None:
        state = previous.height_state(t_start, w)
    else:
        h0 = 0.5 * (standing[0].z + standing[1].z)
        state = [h0, 0.0, h0, 0.0]
    if heights is None:
        if not any(state):
            return None
        heights = [0.0] * n_anchors
    return np.array([*state, *heights])


class PlanLayout:
    """What a replan needs to know about one plan shape: its operator and where its anchors come from."""

    __slots__ = (
        "G", "G_eager", "_end_rows", "_variants", "_zmp_rows", "anchor_phases", "anchor_sources", "durations",
        "eager_out", "first_kind", "key", "kinds", "offsets", "transfer",
    )  # fmt: skip

    def __init__(self, operator: PlanOperator, kinds: tuple[str, ...]) -> None:
        self.key = operator.key
        self.kinds = kinds
        self._variants: dict[tuple, tuple[list[PlanLayout], dict[int, np.ndarray]]] = {}
        self.G = operator.G
        self.G_eager = np.ascontiguousarray(operator.G[: 12 * EAGER_SEGMENTS])
        self.eager_out = np.empty((12 * EAGER_SEGMENTS, 2))  # scratch for the product each replan makes
        self.durations = operator.durations.tolist()
        self.offsets = np.concatenate(([0.0], np.cumsum(operator.durations[:-1]))).tolist()
        self.first_kind = kinds[0]
        # The reference transfer over the first segment, p0 + (3 / T^2) D tau^2 - (2 / T^3) D tau^3: its gains.
        first = self.durations[0]
        self.transfer = (3.0 / first**2, -2.0 / first**3)
        # Phases (relative to the plan's first) at whose end the reference ZMP rests on an anchor: the first
        # phase always (its free polynomial ends there), then every phase in which the reference travels.
        self.anchor_phases = (0, *(k for k, kind in enumerate(kinds) if k > 0 and kind in MOVING_KINDS))
        self._zmp_rows: dict[int, np.ndarray] = {}
        self._end_rows: dict[int, np.ndarray] = {}
        self.anchor_sources: tuple[tuple[int, int], ...] | None = None  # relative to F[q // 2], set on first use

    def end_state_rows(self, j: int, w: float) -> np.ndarray:
        """``S`` ``(4, n_inputs)``: ``S @ y`` holds ZMP, ZMP velocity, COG and COG velocity (rows, axes as columns)
        at the end of segment ``j`` (m, m/s)."""
        rows = self._end_rows.get(j)
        if rows is None:
            T = self.durations[j]
            powers = T ** np.arange(DEGREE + 1)
            slopes = np.arange(DEGREE + 1) * np.concatenate(([0.0], powers[:-1]))
            ch, sh = math.cosh(w * T), math.sinh(w * T)
            block = self.G[12 * j : 12 * j + 12]
            a, A, V, W = block[: DEGREE + 1], block[DEGREE + 1 : 2 * DEGREE + 2], block[-2], block[-1]
            rows = np.array([powers @ a, slopes @ a, ch * V + sh * W + powers @ A, w * (sh * V + ch * W) + slopes @ A])
            self._end_rows[j] = rows
        return rows

    def variants(self, segment: int, durations: tuple[float, ...]) -> list[PlanLayout]:
        """This plan shape with segment ``segment`` lasting each of ``durations`` (s) instead: candidate step
        timings. Built in one vectorised pass on first use and kept (a few per layout)."""
        found = self._variants.get((segment, durations))
        if found is None:
            table = np.repeat(np.asarray(self.durations)[None], len(durations), axis=0)
            table[:, segment] = durations
            layouts = [PlanLayout(op, self.kinds) for op in PlanOperator.for_durations(self.key, table)]
            found = self._variants[(segment, durations)] = (layouts, {})
        return found[0]

    def variant_zmp_rows(self, segment: int, durations: tuple[float, ...], samples: int) -> np.ndarray:
        """The :meth:`zmp_rows` of every :meth:`variants` layout, stacked ``(D, samples, n_inputs)`` (kept)."""
        layouts = self.variants(segment, durations)
        stacked = self._variants[(segment, durations)][1]
        rows = stacked.get(samples)
        if rows is None:
            rows = stacked[samples] = np.stack([layout.zmp_rows(samples) for layout in layouts])
        return rows

    def zmp_rows(self, samples: int) -> np.ndarray:
        """``M`` ``(samples, n_inputs)``: the first segment's ZMP at ``samples`` evenly spaced times is ``M @ y``."""
        rows = self._zmp_rows.get(samples)
        if rows is None:
            rows = self._zmp_rows[samples] = segment_zmp_rows(self.G, self.durations[0], samples)[1]
        return rows
