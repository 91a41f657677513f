"""The other single-support durations of a step being adjusted, for step adjustment's timing.

Step timing (Morisawa et al. 2006), with ``adapt_timing``: the single support of the step being adjusted may also
end sooner, a landing sooner moving the ZMP's anchors sooner, or (with ``max_single_support``) later, which gives
the stance sole longer to catch a push toward its outside. A new duration changes the plan's operator, not its
inputs, so each candidate duration ``d`` has its own rows ``M_d`` (built in one batch, ahead where the durations
are known ahead, and kept with the plan's layout); the landings are then weighed against every duration at once,
``(D, C)`` margins, and the choice minimises ``|delta|^2 + (time_cost * (d - d_nominal))^2`` among the candidates
that reach the margin (``docs/closed_loop.md``).

Candidate durations are spread evenly on each side of the nominal one and rounded to 1 ns (they key the operator
cache).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

if TYPE_CHECKING:
    from rtgait.core.laws.stepping import StepAdjustment

__all__ = ["TimingOptions", "remainder_options", "single_support_options"]


def single_support_options(adjust: StepAdjustment, nominal: float) -> tuple[float, ...] | None:
    """Candidate single supports (s) of a step that has not lifted off, nominal ``nominal`` (s): ``durations``
    evenly spaced from ``min_single_support`` to the nominal one and, with ``max_single_support``, as many from the
    nominal one to it; the nominal one left out (it is the plan as made); rounded to 1 ns (they key the operator
    cache). ``None`` if the step can neither be shortened nor lengthened."""
    limits = adjust.limits
    return _both_sides(adjust, limits.min_single_support, nominal, limits.max_single_support)


def remainder_options(adjust: StepAdjustment, elapsed: float, remainder: float) -> tuple[float, ...] | None:
    """Candidate rests (s) of a single support ``elapsed`` s old with ``remainder`` s to go: from the latest of
    ``min_time_to_touchdown`` and ``min_single_support - elapsed`` up to the nominal rest and, with
    ``max_single_support``, on to ``max_single_support - elapsed``, as in :func:`single_support_options`."""
    limits = adjust.limits
    low = max(limits.min_time_to_touchdown, limits.min_single_support - elapsed)
    high = None if limits.max_single_support is None else limits.max_single_support - elapsed
    return _both_sides(adjust, low, remainder, high)


def _both_sides(adjust: StepAdjustment, low: float, nominal: float, high: float | None) -> tuple[float, ...] | None:
    """The shorter candidates from ``low`` and the longer ones up to ``high`` (``None``: none), nominal left out."""
    shorter = _evenly(low, nominal, adjust.durations, keep_low=True)
    longer = None if high is None else _evenly(nominal, high, adjust.durations, keep_low=False)
    if longer is None:
        return shorter
    return longer if shorter is None else shorter + longer


def _evenly(low: float, high: float, count: int, keep_low: bool) -> tuple[float, ...] | None:
    """``count - 1`` values of the ``count`` evenly spaced from ``low`` to ``high``: all but ``high``
    (``keep_low``), else all but ``low``; rounded to 1 ns. ``None`` if ``low`` is not at least 1 ms below ``high``
    (plain floats: this runs at every decision and replan)."""
    if low > high - 1e-3:
        return None
    step = (high - low) / (count - 1)
    first = 0 if keep_low else 1
    return tuple(round(low + i * step, 9) for i in range(first, first + count - 1))


class TimingOptions(NamedTuple):
    """Other single-support durations the step being adjusted may take, as the planner evaluates them.

    Attributes:
        single_support: each candidate's single-support duration of the step (s), ``(D,)``.
        rows: each candidate plan's free-segment ZMP rows ``M_d`` (``zmp = M_d @ y``), ``(D, T, n_inputs)``.
        zmp: each candidate plan's free-segment ZMP with the nominal landing, ``(D, T, 2)`` (m).
    """

    single_support: np.ndarray
    rows: np.ndarray
    zmp: np.ndarray
