"""A walk rolled out as :func:`rtgait.core.analysis.rollout.rollout` does, reacting to each obstacle when it is seen.

Each obstacle gets an :class:`~rtgait.core.obstacle.avoid.ObstacleReaction`, called at the first tick at or after
its ``seen_at``; scheduled footstep changes are handed over at their deadlines as usual. Without obstacles the
rollout is exactly the plain one.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import NamedTuple

from rtgait.core.analysis.rollout import Rollout, ScheduledChange, rollout
from rtgait.core.geometry.footsteps import SoleRect, Stride
from rtgait.core.obstacle.avoid import Avoidance, ObstacleReaction
from rtgait.core.obstacle.box import Obstacle
from rtgait.core.planner.config import PlannerConfig
from rtgait.core.planner.online import OnlinePlanner


class ObstacleRun(NamedTuple):
    """One walk with obstacles under one connection mode: the rollout and what it did on seeing each obstacle."""

    connection: str
    rollout: Rollout
    avoidances: tuple[Avoidance, ...]


def avoiding_rollout(
    config: PlannerConfig,
    strides: Sequence[Stride],
    dt: float,
    sole: SoleRect,
    obstacles: Sequence[Obstacle],
    changes: Sequence[ScheduledChange] = (),
    progress: Callable[[float], None] | None = None,
) -> tuple[Rollout, tuple[Avoidance, ...]]:
    """Roll out the walk of ``config`` and ``strides`` every ``dt`` (s), with the soles ``sole`` (m), reacting to
    ``obstacles``; returns the rollout and what the walk did on seeing each obstacle, in the order they were seen."""
    planner = OnlinePlanner(config, strides)
    reactions = [ObstacleReaction(obstacle, sole, dt) for obstacle in obstacles]
    result = rollout(planner, dt, sole, changes, progress=progress,
                     reactions=[(r.obstacle.seen_at, r) for r in reactions])  # fmt: skip
    seen = sorted((r.result for r in reactions if r.result is not None), key=lambda a: a.time)
    return result, tuple(seen)


__all__ = ["ObstacleRun", "avoiding_rollout"]
