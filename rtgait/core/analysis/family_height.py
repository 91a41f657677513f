"""A family's chain of plans, and its vertical column: the COG height of every tick as a linear map of the footholds'
heights.

Every plan of a walk is ``G @ y``, ``y = [state, anchors]`` (:class:`~rtgait.core.planner.active_plan.PlanLayout`),
the state being the end state of the plan before (``S @ y_prev``) and, before the first, at rest over the standing
feet. :func:`plan_chain` makes that chain once for inputs given as coefficient arrays ``(n + 2, axes, P)`` over the
``P`` parameters of a family: the horizontal footprints ``F @ theta`` (:mod:`rtgait.core.analysis.walk_family`), or
the footholds' heights themselves.

Over height changes a plan has a vertical column (the 3D-DCM/VRP form, ``docs/method.md``): the same operator ``G``
applied to the vertical state ``[h, dh, c_z, dc_z]`` and the heights under the anchors (a foothold's ``z``, or the
mean of two), where :func:`~rtgait.core.planner.active_plan.height_column` starts the first plan at
``h = c_z = (z_0 + z_1) / 2`` at rest. It is linear in the footholds' heights ``z = (z_0 .. z_n+1)`` (m), and they do
not change with a change of a stride's length or width (a stride keeps its rise), so the sampled COG height is

    c_z(t_k) = zc + R[k] . z,      R[k] = [V_j ch(w tau) + W_j sh(w tau) + sum_i A_ij tau^i]     (per unit height)

with ``zc`` the scenario's COG height, ``j`` the segment of the plan being executed at tick ``k`` and ``tau`` the
time into it, as :meth:`~rtgait.core.planner.online.OnlinePlanner.sample` evaluates it. :func:`height_rows` builds
``R`` ``(ticks, n + 2)``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from rtgait.core.lipm.pattern import DEGREE
from rtgait.core.planner.active_plan import PlanLayout
from rtgait.core.planner.online import OnlinePlanner

__all__ = ["height_rows", "plan_chain"]

PlanData = dict[int, tuple[np.ndarray, PlanLayout]]
"""Per replan phase ``q`` (even): the plan's coefficients ``G @ y`` ``(rows, axes, P)`` and its layout."""


def plan_chain(planner: OnlinePlanner, n: int, prints_at: Callable[[int], np.ndarray]) -> PlanData:
    """The plans of a walk of ``n`` steps replanned at the start of every even phase, each from the end state of the
    one before: ``prints_at(q)`` gives the footprints the plan made at phase ``q`` sees, ``(n + 2, axes, P)``
    coefficient arrays (module docstring). ``planner`` (started) gives the layouts and the anchors' sources."""
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
        anchors = np.stack([0.5 * (prints[i0 + a] + prints[i0 + b]) for a, b in sources])
        y = np.concatenate([state, anchors])  # (n_inputs, axes, P)
        plans[q] = (np.tensordot(layout.G, y, axes=(1, 0)), layout)
        if q + 2 <= 2 * n:
            state = np.tensordot(layout.end_state_rows(1, w), y, axes=(1, 0))
    return plans


def height_rows(
    planner: OnlinePlanner, n: int, times: np.ndarray, starts: np.ndarray, tick_phase: np.ndarray
) -> np.ndarray:
    """``R`` ``(len(times), n + 2)``: the COG height above ``zc`` at each tick ``times`` (s) per unit height of each
    foothold ``F[0..n+1]`` (module docstring); ``starts`` are the phases' start times (s), ``tick_phase`` each tick's
    phase."""
    unit = np.eye(n + 2)[:, None, :]  # F[i]'s height is parameter i
    plans = plan_chain(planner, n, lambda q: unit)
    w = planner.w
    rows = np.empty((len(times), n + 2))
    for q in np.unique(tick_phase).tolist():
        ticks = np.flatnonzero(tick_phase == q)
        plan_q = min(q - (q & 1), 2 * n)
        j = q - plan_q
        coefficients, layout = plans[plan_q]
        block = coefficients[12 * j : 12 * j + 12, 0]  # [a0..a4, A0..A4, V, W] by parameter
        tau = np.minimum(times[ticks] - starts[plan_q] - layout.offsets[j], layout.durations[j])
        powers = tau[:, None] ** np.arange(DEGREE + 1)
        homogeneous = np.outer(np.cosh(w * tau), block[-2]) + np.outer(np.sinh(w * tau), block[-1])
        rows[ticks] = homogeneous + powers @ block[DEGREE + 1 : 2 * DEGREE + 2]
    return rows
