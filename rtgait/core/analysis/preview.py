"""Baseline: ZMP preview control (Kajita et al., ICRA 2003) behind the planner's interface.

The cart-table model per horizontal axis, sampled every ``T`` = 5 ms with the COG jerk ``u`` as input::

    x = [c, c', c'']        x(k+1) = A x(k) + B u(k)        p(k) = C x(k),   C = [1, 0, -zc / g]

``p`` is the ZMP of the cart on the table (the same linear inverted pendulum as the analytical planner: at constant
height it is ``c - c'' zc / g``). The controller (Katayama's servo form, as in the paper) minimises
``sum Qe e(k)^2 + R du(k)^2`` with ``e = p - p_ref``, ``Qe = 1``, ``R = 1e-6``, and looks ``N`` = 1.6 s ahead::

    u(k) = -Gi sum_{i<=k} e(i) - Gx x(k) - sum_{j=1..N} Gd(j) p_ref(k + j)

with ``P`` the solution of the discrete algebraic Riccati equation of the augmented system
``([1, C A; 0, A], [C B; B])`` (:func:`scipy.linalg.solve_discrete_are`), ``[Gi, Gx] = (R + B~' P B~)^-1 B~' P A~``,
``Gd(1) = -Gi`` and ``Gd(j) = (R + B~' P B~)^-1 B~' X(j - 1)``, ``X(j) = Ac~' X(j - 1)``, ``X(0) = -Ac~' P I~``.

The reference ``p_ref`` is the footsteps' ZMP, the very reference the analytical planner connects to: held on the
stance ankle in single support and carried to the next anchor along the cubic ``3u^2 - 2u^3`` in double support
(``start``: from between the feet; ``end``: back between them). A footstep change reaches the preview only once it
is decided, at the real-time deadline (the changed step's lift-off, as for the real-time connection): from that tick
on the window sees the new footprints. The controller stands still for the preview time before the walk starts
(:data:`PREVIEW_TIME`, reference held between the feet), as it must to see the first step coming: started with the
walk, its best answer to a reference that moves at once is a ZMP swing of more than half a metre. **The ZMP
measured is the realised one**, ``p(k) = C x(k)``, the ZMP of the
COG motion the controller makes, sampled at its ticks over the walk (from its start, after the standing pre-roll; not
``p_ref``, which it only tracks); its signed margin to the support polygon of the phase is the outcome, as for the
analytical planner's ZMP.

:class:`PreviewPlanner` samples like :class:`~rtgait.core.planner.online.OnlinePlanner`, so
:func:`~rtgait.core.analysis.rollout.rollout` runs it; :func:`evaluate_preview` evaluates many straight walks at once
(the whole loop is linear in the footprints, so it is run once per parameter column and combined).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np
from scipy.linalg import solve_discrete_are

from rtgait.core.geometry.footsteps import Stride, Timeline
from rtgait.core.geometry.hull import outside_margin, sole_extents, two_box_hull, two_box_vertices
from rtgait.core.lipm.closed_form import omega
from rtgait.core.planner.config import PlannerConfig
from rtgait.core.planner.planner_walk import WalkQueries
from rtgait.core.planner.sample import SampleValues
from rtgait.core.walk.phases import PhaseInfo, phase_info
from rtgait.core.walk.walk import StepLimits, Walk

if TYPE_CHECKING:
    from rtgait.core.analysis.batch import StraightWalk

PREVIEW_PERIOD = 0.005
"""Control period of the preview controller (s), Kajita et al.'s."""
PREVIEW_TIME = 1.6
"""How far ahead it looks (s)."""
QE, R_INPUT = 1.0, 1e-6
"""Weights of the ZMP error and of the jerk increment."""


@dataclass(frozen=True, eq=False)
class PreviewGains:
    """The discrete cart-table model and the preview controller's gains (SI units)."""

    period: float
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    Gi: float
    Gx: np.ndarray
    Gd: np.ndarray

    @property
    def steps(self) -> int:
        """Preview length in ticks."""
        return len(self.Gd)


@lru_cache(maxsize=32)
def preview_gains(
    cog_height: float, gravity: float, period: float = PREVIEW_PERIOD, preview: float = PREVIEW_TIME,
    qe: float = QE, r: float = R_INPUT,
) -> PreviewGains:  # fmt: skip
    """Gains of the preview controller (module docstring) for a COG ``cog_height`` (m) high under ``gravity``."""
    T = period
    A = np.array([[1.0, T, T * T / 2.0], [0.0, 1.0, T], [0.0, 0.0, 1.0]])
    B = np.array([[T**3 / 6.0], [T * T / 2.0], [T]])
    C = np.array([[1.0, 0.0, -cog_height / gravity]])
    At = np.block([[np.eye(1), C @ A], [np.zeros((3, 1)), A]])
    Bt = np.vstack([C @ B, B])
    It = np.array([[1.0], [0.0], [0.0], [0.0]])
    P = solve_discrete_are(At, Bt, np.diag([qe, 0.0, 0.0, 0.0]), np.array([[r]]))
    scale = r + float((Bt.T @ P @ Bt)[0, 0])
    K = (Bt.T @ P @ At) / scale
    Ac = At - Bt @ K
    n = round(preview / T)
    Gd = np.empty(n)
    Gd[0] = -K[0, 0]
    X = -Ac.T @ P @ It
    for j in range(1, n):
        Gd[j] = float((Bt.T @ X)[0, 0]) / scale
        X = Ac.T @ X
    return PreviewGains(T, A, B[:, 0], C[0], float(K[0, 0]), K[0, 1:].copy(), Gd)


def reference_segments(prints: np.ndarray, timeline: Timeline) -> tuple[np.ndarray, np.ndarray]:
    """Where the footsteps' ZMP starts and ends in every phase ``0..2n+1``: ``(2n + 2, 2, ...)`` each (m), for
    footprints ``prints`` ``(n + 2, 2, ...)`` (any trailing shape: coefficient columns)."""
    n = timeline.n_steps
    mid_start, mid_end = 0.5 * (prints[0] + prints[1]), 0.5 * (prints[n] + prints[n + 1])
    start, end = [mid_start], [prints[1]]
    for q in range(1, 2 * n + 2):
        kind = timeline.kind(q)
        if kind == "single":
            start.append(prints[(q + 1) // 2])
            end.append(prints[(q + 1) // 2])
        elif kind == "double":
            start.append(prints[q // 2])
            end.append(prints[q // 2 + 1])
        elif kind == "end":
            start.append(prints[n])
            end.append(mid_end)
        else:  # settle
            start.append(mid_end)
            end.append(mid_end)
    return np.stack(start), np.stack(end)


def reference_at(times: np.ndarray, timeline: Timeline, segments: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """The footsteps' ZMP at ``times`` (s from the walk's start): ``(len(times), 2, ...)`` (m); after the walk's end
    it stays between the feet."""
    last = timeline.last_phase
    starts = np.array([timeline.start_time(q) for q in range(last + 1)])
    durations = np.array([timeline.duration(q) for q in range(last + 1)])
    q = np.clip(np.searchsorted(starts, times, side="right") - 1, 0, last)
    u = np.clip((times - starts[q]) / durations[q], 0.0, 1.0)
    s = u * u * (3.0 - 2.0 * u)
    shape = (-1,) + (1,) * (segments[0].ndim - 1)
    return segments[0][q] + s.reshape(shape) * (segments[1][q] - segments[0][q])


class PreviewPlanner(WalkQueries):
    """ZMP preview control with the sampling interface of :class:`~rtgait.core.planner.online.OnlinePlanner` (what
    :func:`~rtgait.core.analysis.rollout.rollout` uses): ``start``, ``sample_values``, ``change_step`` (accepted until
    the step's lift-off), ``change_deadline``, ``contact_feet``, ``footprints``. It makes no plans (``plans`` stays
    empty); its samples' ``zmp`` is the realised cart-table ZMP, ``zmp_ref`` the footsteps' reference.

    Between two control ticks a sample holds the state of the last one (zero-order hold), so sample at multiples of
    :data:`PREVIEW_PERIOD` to see every tick.
    """

    def __init__(self, config: PlannerConfig, strides: Sequence[Stride]) -> None:
        self.config = config
        self.w = omega(config.cog_height, config.gravity)
        self.gains = preview_gains(config.cog_height, config.gravity)
        limits = StepLimits(config.max_step_length, config.max_step_lateral, config.max_step_turn)
        self._walk = Walk(config.timing, "real-time", config.step_width, limits, strides, first_side=config.first_side)
        self.plans: deque = deque()
        self.replan_count = 0
        self.change_log: deque[tuple[float, int]] = deque()
        self._t0 = math.nan

    # ----- the walk, as the planner shows it (WalkQueries: walk, timeline, n_steps, end_time, footprints, ...) ----
    def change_deadline(self, step: int) -> float:
        """The changed step's lift-off (s): when the preview window sees a change."""
        return self.phase_start(self._walk.deadline_phase(step))

    def change_step(self, step: int, *, length=None, width=None, turn=None, through=None) -> None:
        """Change strides ``step..through`` (as the planner's); the preview sees it from the next tick on."""
        if math.isfinite(self._t0) and self._latest_t > -math.inf:
            # The ticks up to the latest sample were decided before the change arrived: make them with the old
            # reference first (causality; the state of the latest sample is unchanged).
            latest = math.floor((self._latest_t - self._t0) / self.gains.period + 1e-9) + self._lead
            with self._walk.trial():
                self._walk.change_step(step, length=length, width=width, turn=turn, through=through)  # checks
            while self._k < latest:
                self._tick()
        self._walk.change_step(step, length=length, width=width, turn=turn, through=through)
        self.change_log.append((self._latest_t, step))
        self._reference = None
        self._phase = None

    # ----- control -----------------------------------------------------------------------------------------
    def start(self, t0: float = 0.0) -> None:
        """Stand still between the feet at ``t0`` (s)."""
        self._t0 = float(t0)
        self._walk.restart()
        self._x = np.zeros((3, 2))  # [c, c', c''] per axis
        mid = 0.5 * (self._walk.footprint(0).position + self._walk.footprint(1).position)
        self._x[0] = mid
        self._error = np.zeros(2)
        self._lead = self.gains.steps  # ticks of standing before the walk: tick i is at (i - lead) T from t0
        self._k = -1  # last control tick made
        self._latest_t = -math.inf
        self._reference: np.ndarray | None = None
        self._phase: PhaseInfo | None = None

    def _references(self) -> np.ndarray:
        """The footsteps' ZMP at every control tick of the walk and a preview window beyond (m), as decided now."""
        if self._reference is None:
            gains, timeline = self.gains, self.timeline
            ticks = self._lead + math.floor(timeline.end_time / gains.period + 1e-9) + 1 + gains.steps + 1
            prints = np.array([[f.x, f.y] for f in self._walk.footprints()])
            segments = reference_segments(prints, timeline)
            self._reference = reference_at((np.arange(ticks) - self._lead) * gains.period, timeline, segments)
        return self._reference

    def _tick(self) -> None:
        """One control period: the ZMP error is integrated, the jerk applied, the cart moves."""
        gains, k = self.gains, self._k + 1
        ref = self._references()
        end = min(k + 1 + gains.steps, len(ref))
        window = ref[k + 1 : end]
        preview = gains.Gd[: len(window)] @ window
        zmp = gains.C @ self._x
        self._error += zmp - ref[k]
        u = -gains.Gi * self._error - gains.Gx @ self._x - preview
        self._x = gains.A @ self._x + np.outer(gains.B, u)
        self._k = k

    def sample_values(self, t: float) -> tuple[SampleValues, str, int]:
        """The sample at ``t`` (s) (:class:`~rtgait.core.planner.sample.SampleValues`), its support and phase."""
        if not math.isfinite(self._t0):
            raise RuntimeError("call start() before sample()")
        rel = t - self._t0
        target = math.floor(rel / self.gains.period + 1e-9) + self._lead
        # The state after tick k is at time (k + 1) T: step until the tick at `target` is the current state.
        while self._k + 1 < target:
            self._tick()
        if t > self._latest_t:
            self._latest_t = t
        phase = self._phase
        if phase is None or not phase.start <= rel < phase.end:
            phase = self._phase = phase_info(self._walk, self.timeline, rel, None)
            self._walk.reach(phase.index)
        x = self._x  # rows: COG position, velocity, acceleration; columns: the axes
        (cog_x, cog_y), (cog_vx, cog_vy), (cog_ax, cog_ay) = x.tolist()
        zmp_x, zmp_y = (self.gains.C @ x).tolist()
        zmp_ref_x, zmp_ref_y = self._references()[max(target, 0)].tolist()
        dcm_x, dcm_y = (x[0] + x[1] / self.w).tolist()
        if phase.swing_from is None:  # both feet on the ground, left then right
            lfoot_x, lfoot_y, lfoot_z, lfoot_yaw, rfoot_x, rfoot_y, rfoot_z, rfoot_yaw = phase.feet
        else:
            swing = phase.swing(rel, self.config.step_height)
            left, right = (phase.feet, swing) if phase.support == "left" else (swing, phase.feet)
            lfoot_x, lfoot_y, lfoot_z, lfoot_yaw = left
            rfoot_x, rfoot_y, rfoot_z, rfoot_yaw = right
        values = SampleValues(
            cog_x=cog_x, cog_y=cog_y, cog_z=self.config.cog_height, cog_vx=cog_vx, cog_vy=cog_vy, cog_vz=0.0,
            cog_ax=cog_ax, cog_ay=cog_ay, cog_az=0.0, zmp_x=zmp_x, zmp_y=zmp_y, zmp_ref_x=zmp_ref_x,
            zmp_ref_y=zmp_ref_y, lfoot_x=lfoot_x, lfoot_y=lfoot_y, lfoot_z=lfoot_z, lfoot_yaw=lfoot_yaw,
            rfoot_x=rfoot_x, rfoot_y=rfoot_y, rfoot_z=rfoot_z, rfoot_yaw=rfoot_yaw, dcm_x=dcm_x, dcm_y=dcm_y,
        )  # fmt: skip
        return values, phase.support, phase.index


# ----- many walks at once --------------------------------------------------------------------------------------


def evaluate_preview(walk: StraightWalk, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The preview controller on the walks ``walk`` with parameters ``theta`` ``(B, P)`` (the layout of
    :meth:`~rtgait.core.analysis.batch.StraightWalk.parameters`): per case the smallest signed margin of the realised
    ZMP (m), its time (s; ties broken as ``rtgait plan`` does) and the largest ``|ZMP - p_ref|`` per axis over the walk
    (m), at the controller's ticks. Changes are decided at the real-time deadline, whatever ``walk``'s connection.

    The loop is linear in the footprints, hence in ``theta``: it runs once with one column per parameter, and the
    cases are combined from it.
    """
    from rtgait.core.analysis.family_key import ChangeShape, affine_footprints, family_key
    from rtgait.core.analysis.walk_family import TIE

    config, gains = walk.config, preview_gains(walk.config.cog_height, walk.config.gravity)
    theta = np.atleast_2d(np.asarray(theta, dtype=float))
    shapes = tuple(ChangeShape(s.step, s.through, s.length, s.width, 2 * s.step - 1) for s in walk.shapes())
    key = family_key(config, walk.sole, gains.period, walk.steps, shapes)
    n = walk.steps + 1
    timeline = Timeline(config.timing, n)
    T, N = gains.period, gains.steps
    lead = N  # standing ticks before the walk (module docstring); tick i is at (i - lead) T
    K = lead + math.floor(timeline.end_time / T + 1e-9) + 1
    times = (np.arange(K) - lead) * T
    starts = np.array([timeline.start_time(q) for q in range(2 * n + 2)])
    order = sorted(range(len(shapes)), key=lambda c: starts[shapes[c].decided_phase])
    handed = [int(np.searchsorted(times, starts[shapes[c].decided_phase])) for c in order]
    version = np.searchsorted(np.array(handed, dtype=int), np.arange(K), side="right")  # changes seen by tick k
    prints = [affine_footprints(key, order[:v]) for v in range(len(order) + 1)]
    extended = (np.arange(K + N + 1) - lead) * T
    refs = [reference_at(extended, timeline, reference_segments(p, timeline)) for p, _ in prints]  # (K+N+1, 2, P)
    previews = [_preview_terms(r, gains.Gd, K) for r in refs]
    ref_now = np.stack([refs[v][k] for k, v in enumerate(version)])  # (K, 2, P)
    preview = np.stack([previews[v][k] for k, v in enumerate(version)])
    # The closed loop, once per parameter column (its initial state is between the feet: linear in them too).
    final, sides = prints[-1]
    columns = final.shape[1] * final.shape[2]  # (axis, parameter) pairs, each an independent loop
    x = np.zeros((3, columns))
    x[0] = (0.5 * (prints[0][0][0] + prints[0][0][1])).ravel()
    error = np.zeros(columns)
    zmp = np.empty((K, columns))
    ref_flat, preview_flat = ref_now.reshape(K, columns), preview.reshape(K, columns)
    A, B, C, Gi, Gx = gains.A, gains.B[:, None], gains.C, gains.Gi, gains.Gx
    for k in range(K):
        zmp[k] = C @ x
        error += zmp[k] - ref_flat[k]
        u = -Gi * error - Gx @ x - preview_flat[k]
        x = A @ x + B * u
    zmp = zmp.reshape(K, *final.shape[1:])
    zmp, ref_now, times = zmp[lead:], ref_now[lead:], times[lead:]  # measured over the walk
    phase = np.clip(np.searchsorted(starts, times, side="right") - 1, 0, 2 * n + 1)
    change_time = min((starts[s.decided_phase] for s in shapes), default=None)
    margins, times_min, deviation = [], [], []
    for block in range(0, len(theta), 256):
        rows = theta[block : block + 256]
        z = np.einsum("kap,bp->bka", zmp, rows)
        margin = np.empty(z.shape[:2])
        for q in np.unique(phase):
            ticks = np.flatnonzero(phase == q)
            feet = walk_contacts(q, n)
            boxes = [np.array(sole_extents(walk.sole, sides[i] == "left")) + (rows @ final[i].T)[:, [0, 0, 1, 1]]
                     for i in feet]  # fmt: skip
            nx, ny, c = two_box_hull(boxes[0], boxes[-1])
            px, py = z[:, ticks, 0], z[:, ticks, 1]
            hp = np.full(px.shape, np.inf)
            for e in range(c.shape[1]):  # per edge line: (cases, ticks) arrays stay in cache
                np.minimum(hp, c[:, e : e + 1] - nx[:, e : e + 1] * px - ny[:, e : e + 1] * py, out=hp)
            out = hp < 0.0
            if out.any():
                hp = np.where(out, outside_margin(px, py, two_box_vertices(boxes[0], boxes[-1])), hp)
            margin[:, ticks] = hp
        best = margin.min(axis=1)
        tied = margin <= best[:, None] + TIE
        later = tied & (times >= (-np.inf if change_time is None else change_time - 1e-12))[None, :]
        pick = np.where(later.any(axis=1), np.argmax(later, axis=1), np.argmax(tied, axis=1))
        ref = np.einsum("kap,bp->bka", ref_now, rows)
        margins.append(best)
        times_min.append(times[pick])
        deviation.append(np.abs(z - ref).max(axis=1))
    return np.concatenate(margins), np.concatenate(times_min), np.concatenate(deviation)


def _preview_terms(ref: np.ndarray, Gd: np.ndarray, K: int) -> np.ndarray:
    """``f(k) = sum_{j=1..N} Gd(j) ref(k + j)`` for ``k < K``, per trailing column of ``ref`` ``(K + N + 1, ...)``."""
    flat = ref.reshape(len(ref), -1)
    out = np.stack([np.correlate(flat[1:, c], Gd, mode="valid")[:K] for c in range(flat.shape[1])], axis=1)
    return out.reshape(K, *ref.shape[1:])


def walk_contacts(q: int, n: int) -> tuple[int, ...]:
    """Footprint indices on the ground in phase ``q`` of a walk of ``n`` steps (:meth:`Walk.contact_feet`)."""
    if q % 2 == 1 and q < 2 * n:
        return ((q + 1) // 2,)
    i = min(q // 2, n)
    return (i, i + 1)


__all__ = [
    "PREVIEW_PERIOD",
    "PREVIEW_TIME",
    "PreviewGains",
    "PreviewPlanner",
    "evaluate_preview",
    "preview_gains",
    "reference_at",
    "reference_segments",
]
