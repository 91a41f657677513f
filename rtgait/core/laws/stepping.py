"""Step adjustment: push recovery by stepping, its settings and its decisions.

When the plan made from the measured state asks for a ZMP outside the support polygon, the ankle alone cannot
recover: the robot must step elsewhere. This module holds what a robot's legs allow (:class:`SteppingLimits`, SI
units), how the adjustment is made (:class:`StepAdjustment`: the grid of candidates, the required ZMP margin in m,
step timing) and the record of one decision (:class:`StepDecision`). The landing is chosen by
:mod:`rtgait.core.laws.landing_choice`; the other single-support durations a step may take (Morisawa et al. 2006) are
listed by :mod:`rtgait.core.laws.step_timing`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, NamedTuple

from rtgait.core.geometry.footsteps import SoleRect
from rtgait.core.geometry.terrain import Terrain

if TYPE_CHECKING:
    pass


ON_FAILURE = ("continue", "stop", "keep")
"""What step adjustment does when no candidate reaches the required margin (:class:`StepAdjustment`)."""


STEPPING_KEYS = (
    "max_length", "min_width", "max_width", "max_swing_speed", "min_time_to_touchdown", "min_single_support",
    "max_single_support",
)  # fmt: skip
"""The limits of a robot's stepping (:class:`SteppingLimits`), as a robot description's ``[stepping]`` table names
them."""


@dataclass(frozen=True)
class SteppingLimits:
    """What a robot's legs allow step adjustment (a robot description's ``[stepping]`` table; SI units).

    Attributes:
        max_length: forward and backward reach of a landing from the stance foot, along its heading (m).
        min_width: least lateral distance between the two foot frames (m): the feet never cross, and with soles
            ``inner`` wide toward each other their inner edges stay ``min_width - 2 inner`` apart.
        max_width: largest lateral distance between the foot frames (m).
        max_swing_speed: largest average horizontal speed of the swing foot over the time left (m/s).
        min_time_to_touchdown: no landing or timing changes closer than this to touch-down (s).
        min_single_support: shortest single support step timing adaptation may give a step (s). A swinging foot
            also never lands sooner than ``min_time_to_touchdown`` from the decision.
        max_single_support: longest single support step timing adaptation may give a step (s), or ``None`` (the
            default): steps are only shortened. A longer single support is how the ankle catches a push toward the
            stance foot's outside, which no landing can (the swing foot lands on the other side): the centre of
            pressure at the sole's outer edge has longer to bring the DCM back before the weight moves to the other
            foot.

    The defaults suit an HRP-2-like robot, COM 0.8 m high.
    """

    max_length: float = 0.35
    min_width: float = 0.12
    max_width: float = 0.45
    max_swing_speed: float = 1.5
    min_time_to_touchdown: float = 0.2
    min_single_support: float = 0.4
    max_single_support: float | None = None

    def __post_init__(self) -> None:
        # (lowest, highest, unit, lowest allowed itself): lengths and the speed must be positive.
        ranges = {
            "max_length": (0.0, 2.0, "m", False),
            "min_width": (0.0, 2.0, "m", False),
            "max_width": (0.0, 2.0, "m", False),
            "max_swing_speed": (0.0, 20.0, "m/s", False),
            "min_time_to_touchdown": (0.0, 1.0, "s", True),
            "min_single_support": (0.05, 5.0, "s", True),
        }
        for name, (low, high, unit, closed) in ranges.items():
            value = getattr(self, name)
            number = not isinstance(value, bool) and isinstance(value, (int, float)) and math.isfinite(value)
            if not (number and (low <= value if closed else low < value) and value <= high):
                interval = f"{'[' if closed else '('}{low:g}, {high:g}]"
                raise ValueError(f"stepping.{name} must be a number within {interval} {unit}, got {value!r}")
        if self.min_width >= self.max_width:
            raise ValueError(f"stepping.min_width ({self.min_width}) must be < max_width ({self.max_width})")
        _check_longest(self.max_single_support, self.min_single_support, "stepping")

    @classmethod
    def from_table(cls, table: dict) -> SteppingLimits:
        """From a ``[stepping]`` table (keys :data:`STEPPING_KEYS`, all optional: the defaults fill in)."""
        unknown = sorted(set(table) - set(STEPPING_KEYS))
        if unknown:
            raise ValueError(f"stepping: unknown key {unknown[0]!r} (known: {', '.join(STEPPING_KEYS)})")
        return cls(**table)

    def adjustment(self, sole: SoleRect, **options) -> StepAdjustment:
        """The :class:`StepAdjustment` with these limits for ``sole`` (its other settings from ``options``)."""
        return StepAdjustment(sole, self, **options)


@dataclass(frozen=True)
class StepAdjustment:
    """Limits and preferences of step adjustment (``PlannerConfig(step_adjustment=...)``).

    Attributes:
        sole: the sole rectangle, for the support polygons (m).
        limits: what the legs allow: the stride box, the swing speed, the last moment a landing may change and the
            single-support durations timing adaptation may give (:class:`SteppingLimits`).
        required_margin: ZMP margin a plan must keep to need no adjustment, and that a candidate must reach (m).
        grid: candidates per axis of the stride box (``grid**2`` in all).
        samples: sample times of the free segment at which the margin is checked.
        on_failure: when no candidate reaches ``required_margin``: ``"continue"`` takes the best one and walks on
            (the default: at the pendulum level it recovers more, see ``docs/closed_loop.md``), ``"stop"`` takes it
            and stops the walk after that step (an emergency sequence: capture step, then stop), ``"keep"`` keeps
            the walk as planned (no landing or timing moves; the plan goes on from the planned state).
        adapt_timing: also choose the single-support duration of the step being adjusted (Morisawa et al. 2006):
            ``durations`` candidates evenly from the shortest allowed to the nominal one (nominal included), and
            with ``limits.max_single_support`` as many again up to the longest, so ``grid**2 * durations`` (or
            ``grid**2 * (2 durations - 1)``) candidates in all. Off by default (the decisions are then those of
            landings alone). Not with ``connection="auto"`` (it needs one timing for every step): ignored there.
        durations: candidate single-support durations per decision on each side of the nominal one, nominal
            included (2..16).
        time_cost: how many metres of landing departure one second of timing change weighs (m/s): the departure
            is ``|delta|^2 + (time_cost * dT)^2``. 0.5 m/s, about a walking speed: shortening a step by ``dT``
            moves the body about as much as landing ``0.5 dT`` elsewhere.
        terrain: the terrain the walk's footholds were placed on (:mod:`rtgait.core.geometry.terrain`), or
            ``None`` (the flat floor, or footholds that do not know the ground): a moved landing is then kept on its
            foothold's own tread or stone and takes the terrain's height and tilt at its new place
            (:func:`~rtgait.core.geometry.terrain_landing.land_on_terrain`).
    """

    sole: SoleRect
    limits: SteppingLimits = field(default_factory=SteppingLimits)
    required_margin: float = 0.005
    grid: int = 32
    samples: int = 16
    on_failure: str = "continue"
    adapt_timing: bool = False
    durations: int = 4
    time_cost: float = 0.5
    terrain: Terrain | None = None

    def __post_init__(self) -> None:
        if self.terrain is not None and not callable(getattr(self.terrain, "height", None)):
            raise ValueError(f"step_adjustment.terrain must be a terrain or None, got {type(self.terrain).__name__}")
        if not isinstance(self.sole, SoleRect):
            raise ValueError("step_adjustment.sole must be a SoleRect")
        if not isinstance(self.limits, SteppingLimits):
            raise ValueError(f"step_adjustment.limits must be a SteppingLimits, got {type(self.limits).__name__}")
        if not (math.isfinite(self.required_margin) and 0.0 <= self.required_margin <= 1.0):
            raise ValueError(f"step_adjustment.required_margin must be within [0, 1], got {self.required_margin}")
        if self.on_failure not in ON_FAILURE:
            raise ValueError(f"step_adjustment.on_failure must be one of {ON_FAILURE}, got {self.on_failure!r}")
        if not isinstance(self.adapt_timing, bool):
            raise ValueError(f"step_adjustment.adapt_timing must be true or false, got {self.adapt_timing!r}")
        value = self.time_cost
        if not (isinstance(value, (int, float)) and math.isfinite(value) and 0.0 <= value <= 100.0):
            raise ValueError(f"step_adjustment.time_cost must be within [0, 100], got {value!r}")
        for name, low, high in (("grid", 2, 200), ("samples", 2, 200), ("durations", 2, 16)):
            value = getattr(self, name)
            if not (isinstance(value, int) and not isinstance(value, bool) and low <= value <= high):
                raise ValueError(f"step_adjustment.{name} must be an integer in {low}..{high}, got {value!r}")


def _check_longest(longest: float | None, shortest: float, prefix: str) -> None:
    """``max_single_support`` is ``None`` or a number of seconds above ``min_single_support`` and at most 10 s."""
    if longest is None:
        return
    number = not isinstance(longest, bool) and isinstance(longest, (int, float)) and math.isfinite(longest)
    if not (number and shortest < longest <= 10.0):
        raise ValueError(
            f"{prefix}.max_single_support must be a number of seconds above min_single_support ({shortest:g} s) "
            f"and at most 10 s, got {longest!r}"
        )


class StepDecision(NamedTuple):
    """One step adjustment.

    Attributes:
        t: when it was decided (s).
        step: the step whose landing moved (1-based).
        nominal: where it was to land ``(x, y)`` (m).
        landing: where it lands now ``(x, y)`` (m).
        margin_before, margin_after: the free segment's ZMP margin before and after (m, half-plane measure).
        candidates: candidates evaluated.
        emergency: no candidate kept the ZMP inside; the walk stops after this step.
        reason: one line for the log.
        single_support: the step's single-support duration now (s).
        nominal_single_support: the step's single-support duration before the decision (s); differs from
            ``single_support`` only with ``adapt_timing``.
        kept: nothing moved: no candidate was enough and ``on_failure="keep"`` kept the step as planned.
    """

    t: float
    step: int
    nominal: tuple[float, float]
    landing: tuple[float, float]
    margin_before: float
    margin_after: float
    candidates: int
    emergency: bool
    reason: str
    single_support: float = math.nan
    nominal_single_support: float = math.nan
    kept: bool = False


__all__ = [
    "ON_FAILURE",
    "STEPPING_KEYS",
    "StepAdjustment",
    "StepDecision",
    "SteppingLimits",
]
