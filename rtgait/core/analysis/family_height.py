"""A family's chain of plans, and its vertical column: the COG height of every tick as a linear map of the footholds'
heights and the stances' support heights.

Every plan of a walk is ``G @ y``, ``y = [state, anchors]`` (:class:`~rtgait.core.planner.active_plan.PlanLayout`),
the state being the end state of the plan before (``S @ y_prev``) and, before the first, at rest over the standing
feet. :func:`plan_chain` makes that chain once for inputs given as coefficient arrays ``(n + 2, axes, P)`` over the
``P`` parameters of a family: the horizontal footprints ``F @ theta`` (:mod:`rtgait.core.analysis.walk_family`), or
the footholds' heights themselves.

Over height changes a plan has a vertical column (the 3D-DCM/VRP form, ``docs/method.md``): the same operator ``G``
applied to the vertical state ``[h, dh, c_z, dc_z]`` and the support heights under the anchors: a stance's ``h_i``
(:func:`~rtgait.core.geometry.support_height.stance_support_height`: its foothold's ``z_i``, lowered before a step
down) or the mean of two footholds' ``z`` between the final feet, where
:func:`~rtgait.core.planner.active_plan.height_column` starts the first plan at ``h = c_z = (z_0 + z_1) / 2`` at
rest. It is linear in the footholds' heights ``z = (z_0 .. z_n+1)`` and the stances' lowerings ``h - z`` (m), and
neither changes with a change of a stride's length or width (a stride keeps its rise), so the sampled COG height is

    c_z(t_k) = zc + R[k] . z + L[k] . (h - z),     R[k], L[k] = [V_j ch(w tau) + W_j sh(w tau) + sum_i A_ij tau^i]

per unit height with every stance at its foothold's height (``R``) and per unit lowering of one stance (``L``), with
``zc`` the scenario's COG height, ``j`` the segment of the plan being executed at tick ``k`` and ``tau`` the time into
it, as :meth:`~rtgait.core.planner.online.OnlinePlanner.sample` evaluates it. Where no step down follows a stance
``h = z`` and the ``L`` term is exactly zero. :class:`VerticalColumn` builds ``R`` and ``L`` (and the COG's vertical
acceleration alike) once per family; :func:`tick_rows` samples any chain so.

With the horizontal plans sampled the same way (ZMP, COG and its acceleration affine in ``theta``),
:func:`vertical_zmp_error` gives the error the vertical motion adds to the horizontal dynamics at every tick, the
full point-mass ZMP against the planned one (:mod:`rtgait.core.analysis.height_error`, ``docs/method.md`` eq. (1)):

    p_true = c - (c_z - p_z) c'' / (c_z'' + g)

with ``p_z`` the terrain's plane under the contact foot nearest to the planned ZMP, at the ZMP.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from rtgait.core.lipm.pattern import DEGREE
from rtgait.core.planner.active_plan import PlanLayout
from rtgait.core.planner.online import OnlinePlanner

__all__ = ["TickRows", "VerticalColumn", "contact_feet", "plan_chain", "tick_rows", "vertical_zmp_error"]

PlanData = dict[int, tuple[np.ndarray, PlanLayout]]
"""Per replan phase ``q`` (even): the plan's coefficients ``G @ y`` ``(rows, axes, P)`` and its layout."""


def plan_chain(
    planner: OnlinePlanner, n: int, prints_at: Callable[[int], np.ndarray], stances: np.ndarray | None = None
) -> PlanData:
    """The plans of a walk of ``n`` steps replanned at the start of every even phase, each from the end state of the
    one before: ``prints_at(q)`` gives the footprints the plan made at phase ``q`` sees, ``(n + 2, axes, P)``
    coefficient arrays (module docstring). ``planner`` (started) gives the layouts and the anchors' sources.
    ``stances`` ``(n + 2, axes, P)``: what a stance anchor on ``F[i]`` rests on instead of ``F[i]`` itself (its
    support height's part, :class:`VerticalColumn`)."""
    w = planner.w
    plans: PlanData = {}
    state = None
    for q in range(0, 2 * n + 1, 2):
        layout = planner.layout_for_replan(q)
        prints = prints_at(q)
        if state is None:  # at rest over the standing feet
            c0 = 0.5 * (prints[0] + prints[1])
            state = np.stack([c0, np.zeros_like(c0), c0, np.zeros_like(c0)])
        sources = planner.walk.relative_anchor_sources(q, layout.anchor_phases)
        i0 = q >> 1
        anchors = np.stack(
            [
                stances[i0 + a] if stances is not None and a == b else 0.5 * (prints[i0 + a] + prints[i0 + b])
                for a, b in sources
            ]
        )
        y = np.concatenate([state, anchors])  # (n_inputs, axes, P)
        plans[q] = (np.tensordot(layout.G, y, axes=(1, 0)), layout)
        if q + 2 <= 2 * n:
            state = np.tensordot(layout.end_state_rows(1, w), y, axes=(1, 0))
    return plans


class TickRows(NamedTuple):
    """A chain of plans sampled at every tick, per axis and parameter (each ``(ticks, axes, P)``, m and m/s^2 per unit
    parameter): the ZMP (or the support height), the COG above its constant part, and the COG's acceleration."""

    zmp: np.ndarray
    cog: np.ndarray
    acc: np.ndarray


def tick_rows(
    plans: PlanData, n: int, times: np.ndarray, starts: np.ndarray, tick_phase: np.ndarray, w: float
) -> TickRows:
    """``plans`` (:func:`plan_chain`) sampled at ``times`` (s) as the planner samples them: at each tick the plan made
    at the start of the even phase it is in (the last one after the walk), ``tau`` into its segment (held at the
    segment's end after it); ``starts`` are the phases' start times (s), ``tick_phase`` each tick's phase."""
    shape = (len(times), *next(iter(plans.values()))[0].shape[1:])
    zmp, cog, acc = np.empty(shape), np.empty(shape), np.empty(shape)
    exponents = np.arange(DEGREE + 1)
    for q in np.unique(tick_phase).tolist():
        ticks = np.flatnonzero(tick_phase == q)
        plan_q = min(q - (q & 1), 2 * n)
        j = q - plan_q
        coefficients, layout = plans[plan_q]
        block = coefficients[12 * j : 12 * j + 12]  # [a0..a4, A0..A4, V, W] (12, axes, P)
        tau = np.minimum(times[ticks] - starts[plan_q] - layout.offsets[j], layout.durations[j])
        powers = tau[:, None] ** exponents
        # d^2/dtau^2 tau^i = i (i - 1) tau^(i - 2): the particular part's acceleration.
        curvature = exponents * (exponents - 1) * tau[:, None] ** np.maximum(exponents - 2, 0)
        homogeneous = np.cosh(w * tau)[:, None, None] * block[-2] + np.sinh(w * tau)[:, None, None] * block[-1]
        particular = block[DEGREE + 1 : 2 * DEGREE + 2]
        zmp[ticks] = np.tensordot(powers, block[: DEGREE + 1], axes=(1, 0))
        cog[ticks] = homogeneous + np.tensordot(powers, particular, axes=(1, 0))
        acc[ticks] = w * w * homogeneous + np.tensordot(curvature, particular, axes=(1, 0))
    return TickRows(zmp, cog, acc)


class VerticalColumn:
    """The vertical column of a family's walks at every tick (module docstring), built once and kept: ``R`` per unit
    height of each foothold ``F[0..n+1]``, and ``L`` per unit lowering of each stance, made when a walk first needs it
    (each a :class:`TickRows`, ``(ticks, 1, n + 2)``: the support height, the COG height above ``zc`` and its
    acceleration). ``planner`` (started), ``times``, ``starts`` and ``tick_phase`` as for :func:`tick_rows`."""

    def __init__(
        self, planner: OnlinePlanner, n: int, times: np.ndarray, starts: np.ndarray, tick_phase: np.ndarray
    ) -> None:
        self._sample = (planner, n, times, starts, tick_phase)
        self._heights: TickRows | None = None
        self._lowering: TickRows | None = None

    def _rows(self, stances: bool) -> TickRows:
        planner, n, times, starts, tick_phase = self._sample
        unit = np.eye(n + 2)[:, None, :]  # F[i]'s height (or stance F[i]'s lowering) is parameter i
        if not stances:
            return tick_rows(plan_chain(planner, n, lambda q: unit), n, times, starts, tick_phase, planner.w)
        zero = np.zeros_like(unit)  # only the stance anchors move: the footholds and the first state stay at 0
        return tick_rows(plan_chain(planner, n, lambda q: zero, unit), n, times, starts, tick_phase, planner.w)

    def motion(self, heights: np.ndarray, support: np.ndarray, cog_height: float) -> tuple[np.ndarray, np.ndarray]:
        """The planned COG height ``c_z`` (m) and its acceleration ``c_z''`` (m/s^2), each ``(B, ticks)``, of walks
        whose footholds ``F[0..n+1]`` stand at ``heights`` and whose stances hold the support heights ``support``
        (each ``(B, n + 2)``, m; ``support == heights`` where no step down follows), with ``cog_height`` ``zc`` (m)."""
        if self._heights is None:
            self._heights = self._rows(stances=False)
        rows = self._heights
        cog_z = cog_height + heights @ rows.cog[:, 0, :].T
        acc_z = heights @ rows.acc[:, 0, :].T
        lowering = support - heights
        if np.any(lowering):  # otherwise the L term is exactly zero: leave R's numbers as they are
            if self._lowering is None:
                self._lowering = self._rows(stances=True)
            cog_z += lowering @ self._lowering.cog[:, 0, :].T
            acc_z += lowering @ self._lowering.acc[:, 0, :].T
        return cog_z, acc_z


def contact_feet(tick_phase: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Per tick, the indices of the footprints on the ground ``(first, second)`` (``second == first`` in single
    support) of a walk of ``n`` steps: ``F[i]`` and ``F[i + 1]`` in the double support ``q = 2i`` (and in the final
    settling, ``q = 2n + 1``), ``F[i]`` alone in the single support ``q = 2i - 1``, as the rollout lists them."""
    single = (tick_phase & 1).astype(bool) & (tick_phase < 2 * n + 1)
    first = np.where(single, (tick_phase + 1) >> 1, np.minimum(tick_phase >> 1, n))
    return first, np.where(single, first, first + 1)


def vertical_zmp_error(
    horizontal: TickRows,
    vertical: tuple[np.ndarray, np.ndarray],
    feet: tuple[np.ndarray, np.ndarray],
    theta: np.ndarray,
    footprints: np.ndarray,
    planes: np.ndarray,
    gravity: float,
) -> np.ndarray:
    """``|p_true - p|`` ``(B, ticks)`` (m): the error the vertical motion adds to the horizontal ZMP, as
    :func:`~rtgait.core.analysis.height_error.zmp_error` measures it on a rollout, for walks ``theta`` ``(B, P)`` with
    the COG height and its acceleration ``vertical`` (:meth:`VerticalColumn.motion`), their final footprints
    ``footprints`` ``(B, n + 2, 2)`` (m, heading +x) and the terrain's plane under each, ``planes``
    ``(B, n + 2, 3)`` (height m, pitch, roll rad). ``p_z`` is the plane of the contact foot nearest to the planned
    ZMP (the first listed on a tie), at the ZMP."""
    B, ticks = len(theta), len(horizontal.zmp)

    def per_axis(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # (ticks, 2, P) rows -> x, y (B, ticks)
        values = theta @ rows.reshape(ticks * 2, -1).T
        return values[:, 0::2], values[:, 1::2]

    (zmp_x, zmp_y), (cog_x, cog_y), (acc_x, acc_y) = (per_axis(r) for r in horizontal)
    cog_z, acc_z = vertical
    first, second = feet
    foot_x, foot_y = footprints[..., 0], footprints[..., 1]
    to_first = (foot_x[:, first] - zmp_x) ** 2 + (foot_y[:, first] - zmp_y) ** 2
    to_second = (foot_x[:, second] - zmp_x) ** 2 + (foot_y[:, second] - zmp_y) ** 2
    nearest = np.where(to_first <= to_second, first, second)  # (B, ticks)

    def under(values: np.ndarray) -> np.ndarray:  # a value per footprint (B, n + 2) -> the nearest's per tick
        return np.take_along_axis(values, nearest, axis=1)

    dx, dy = zmp_x - under(foot_x), zmp_y - under(foot_y)
    z, tan_pitch, tan_roll = planes[..., 0], np.tan(planes[..., 1]), np.tan(planes[..., 2])
    surface_z = under(z) - under(tan_pitch) * dx + under(tan_roll) * dy
    scale = (cog_z - surface_z) / (acc_z + gravity)
    return np.hypot(cog_x - scale * acc_x - zmp_x, cog_y - scale * acc_y - zmp_y).reshape(B, ticks)
