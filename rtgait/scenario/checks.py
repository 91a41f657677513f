"""Checks shared by the scenario file loader and the :class:`~rtgait.scenario.scenario.Scenario` dataclass, and the
error they raise: each message is one line naming the field."""

from __future__ import annotations

import math

from rtgait.core.geometry.footsteps import Timing, check_step_timings
from rtgait.core.limits import MAX_PHASE_W_T, MAX_ROLLOUT_TICKS, check_range
from rtgait.scenario.tomlfile import is_finite_number

__all__ = ["PHASES", "ScenarioError", "check_distinct_steps", "check_phase_lengths", "check_ticks", "within"]

PHASES = ("single_support", "double_support", "start", "end", "settle")
"""The :class:`Timing` fields, each a phase duration (s)."""


class ScenarioError(ValueError):
    """A scenario is unknown, unreadable or invalid. The message is one line naming the field."""


def within(name: str, value: float, bounds: tuple[float, float], unit: str) -> None:
    """``value`` is a finite number within ``bounds`` (inclusive), in the core's wording of the message."""
    if not is_finite_number(value):
        raise ScenarioError(f"{name} must be a finite number ({unit}), got {value!r}")
    try:
        check_range(name, value, *bounds, unit)
    except ValueError as error:
        raise ScenarioError(str(error)) from None


def check_phase_lengths(timing: Timing, cog_height: float, gravity: float) -> None:
    """Every phase satisfies ``w T <= MAX_PHASE_W_T``: beyond it the cosh/sinh terms of the closed form cancel
    with too much round-off (:mod:`rtgait.core.limits`)."""
    w = math.sqrt(gravity / cog_height)
    for name in PHASES:
        duration = getattr(timing, name)
        if w * duration > MAX_PHASE_W_T:
            raise ScenarioError(
                f"timing.{name} = {duration:g} s is too long for a COG {cog_height:g} m high: w*T = {w * duration:.3g}"
                f" must be at most {MAX_PHASE_W_T:g} (w = sqrt(gravity / cog_height) = {w:.3g} 1/s), i.e. phases of "
                f"at most {MAX_PHASE_W_T / w:.3g} s"
            )
    try:
        check_step_timings(timing, w)
    except ValueError as error:
        raise ScenarioError(str(error)) from None


def check_ticks(duration: float, dt: float) -> None:
    """A rollout of ``duration`` (s) sampled every ``dt`` (s) holds at most MAX_ROLLOUT_TICKS rows in memory."""
    ticks = math.floor(duration / dt + 1e-9) + 1  # as rtgait.core.analysis.rollout counts them
    if ticks > MAX_ROLLOUT_TICKS:
        raise ScenarioError(
            f"dt {dt:g} s is too short for a walk of {duration:g} s: duration / dt + 1 = {ticks} samples, at most "
            f"{MAX_ROLLOUT_TICKS}; use a longer dt or fewer walk.steps"
        )


def check_distinct_steps(steps: list[int], where: str) -> None:
    """No two changes of the same step: which one should win would be a guess (the last one silently did)."""
    first: dict[int, int] = {}
    for index, step in enumerate(steps):
        if step in first:
            raise ScenarioError(
                f"{where}[{first[step]}] and {where}[{index}] both change step {step}: give each step one entry "
                "(with all of its length, width and yaw)"
            )
        first[step] = index
