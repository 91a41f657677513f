"""What a family of straight walks shares (:class:`FamilyKey`), and its footprints as affine maps of its parameters.

A family (:mod:`rtgait.core.analysis.walk_family`) fixes everything of a rollout but the numbers; its cases differ in
``theta = [1, step_length, step_width, change lengths..., change widths...]`` (m). A straight walk's strides are
relative, ``F[i] = F[i - 1] + (length_i, +-width_i)``, so every footprint is ``F @ theta`` with ``F`` a ``(2, P)``
coefficient array (:func:`affine_footprints`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from rtgait.core.geometry.footsteps import Side, SoleRect, Timing, other_side
from rtgait.core.planner.config import PlannerConfig

__all__ = ["ChangeShape", "FamilyKey", "affine_footprints", "family_key"]


class ChangeShape(NamedTuple):
    """Which strides a change sets, and when it is handed to the planner.

    Attributes:
        step: first step changed (1-based); through: last one.
        length, width: whether it sets the length / the width of those strides.
        decided_phase: handed over at the first tick at or after this phase's start (the rollout's deadline).
    """

    step: int
    through: int
    length: bool
    width: bool
    decided_phase: int


@dataclass(frozen=True)
class FamilyKey:
    """Everything a family's cases share (SI units): see :mod:`rtgait.core.analysis.walk_family`."""

    cog_height: float
    gravity: float
    timing: Timing
    horizon_steps: int
    first_degree: int
    first_side: Side
    sole: SoleRect
    dt: float
    steps: int
    changes: tuple[ChangeShape, ...]

    @property
    def n_params(self) -> int:
        return 3 + sum(int(c.length) + int(c.width) for c in self.changes)


def affine_footprints(key: FamilyKey, applied: list[int]) -> tuple[np.ndarray, list[Side]]:
    """Footprints ``F[0..n+1]`` as ``(n + 2, 2, P)`` coefficient arrays (``F @ theta`` in m) after the changes
    ``applied`` (indices into ``key.changes``, in the order they are handed over), and each one's side."""
    n, P = key.steps + 1, key.n_params
    unit = np.eye(P)
    lengths = [unit[1]] * key.steps + [np.zeros(P)]  # the closing step has length 0 and the nominal width
    widths = [unit[2]] * n
    column = 3
    columns = []
    for change in key.changes:
        columns.append((column if change.length else None, column + change.length if change.width else None))
        column += int(change.length) + int(change.width)
    for c in applied:
        change, (lc, wc) = key.changes[c], columns[c]
        for i in range(change.step, change.through + 1):
            if lc is not None:
                lengths[i - 1] = unit[lc]
            if wc is not None:
                widths[i - 1] = unit[wc]
    first = key.first_side
    y0 = 0.5 * unit[2] * (1.0 if first == "left" else -1.0)
    prints = [np.stack([np.zeros(P), y0]), np.stack([np.zeros(P), -y0])]
    sides: list[Side] = [first, other_side(first)]
    for i in range(n):
        landing = other_side(sides[-1])
        lateral = widths[i] if landing == "left" else -widths[i]
        prints.append(prints[-1] + np.stack([lengths[i], lateral]))
        sides.append(landing)
    return np.stack(prints), sides


def family_key(
    config: PlannerConfig, sole: SoleRect, dt: float, steps: int, changes: tuple[ChangeShape, ...]
) -> FamilyKey:
    """The :class:`FamilyKey` of walks planned with ``config`` (its step width and connection do not matter)."""
    return FamilyKey(
        cog_height=config.cog_height, gravity=config.gravity, timing=config.timing, horizon_steps=config.horizon_steps,
        first_degree=config.first_degree, first_side=config.first_side, sole=sole, dt=float(dt), steps=int(steps),
        changes=tuple(changes),
    )  # fmt: skip
