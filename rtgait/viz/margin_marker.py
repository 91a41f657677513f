"""Which tick is *the* minimum ZMP margin of a walk (m), the one ``summary.json`` reports and the figures mark: both
must agree on it, and a minimum is often reached at many ticks (numpy only)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["MARGIN_TIE_TOLERANCE", "MarginMarker", "margin_marker"]

MARGIN_TIE_TOLERANCE = 1e-9
"""Margins (m) within this of the minimum are tied with it: far below anything physical, far above the round-off of
the margin computation and of the 10 significant digits the CSV files keep."""


@dataclass(frozen=True)
class MarginMarker:
    """The tick shown as the walk's minimum ZMP margin, and how many ticks share that minimum.

    Attributes:
        index: the tick marked (and reported as ``zmp_margin_min_time`` in ``summary.json``).
        tied: ticks whose margin is within :data:`MARGIN_TIE_TOLERANCE` of the minimum (1: a unique minimum).
        tied_duration: how long the margin stays at its minimum over the walk (s): ``tied`` ticks of ``dt``.
        reason: why this tick, for a figure's caption (empty for a unique minimum).
    """

    index: int
    tied: int
    tied_duration: float
    reason: str


def margin_marker(times: np.ndarray, margin: np.ndarray, change_times: Sequence[float] = ()) -> MarginMarker:
    """Which tick to mark (and report) as the minimum ZMP margin.

    The minimum is often reached at many ticks: a ZMP resting on the stance ankle in single support is the same
    half sole width from the edges at every such tick, in every step. The first of them (what ``argmin`` gives) is
    the first lift-off, which tells nothing about the walk. The rule:

    * one tick at the minimum: that tick;
    * several (within :data:`MARGIN_TIE_TOLERANCE`) and a footstep change decided in the walk: the first tied tick
      at or after the first change's decision, the instant the figures are about (the margin while the change is
      absorbed);
    * otherwise (no change, or no tie after it): the first tied tick.

    The minimum itself is ``margin.min()`` in every case.
    """
    margin = np.asarray(margin, dtype=float)
    times = np.asarray(times, dtype=float)
    tied = np.flatnonzero(margin <= margin.min() + MARGIN_TIE_TOLERANCE)
    dt = float(times[1] - times[0]) if len(times) > 1 else 0.0
    duration = len(tied) * dt
    if len(tied) == 1:
        return MarginMarker(int(tied[0]), 1, duration, "")
    if len(change_times):
        first_change = min(change_times)
        after = tied[times[tied] >= first_change - 1e-12]
        if len(after):
            return MarginMarker(int(after[0]), len(tied), duration, "first after the change")
    return MarginMarker(int(tied[0]), len(tied), duration, "first instant")
