"""Step adjustment: push recovery by stepping, decided in one vectorised batch through the plan's operator.

When the plan made from the measured state asks for a ZMP outside the support polygon (its free first segment is
the only part of a plan that may leave the footprints), the ankle alone cannot recover: the robot must step
elsewhere. The landing point of the next step that can still change is chosen among a grid of candidates:

* within limits a robot description can set: a stride box in the stance foot's frame (forward/backward reach,
  least and largest distance between the feet, so the feet never cross), the largest average swing speed over the
  time left, and no change in the last ``min_time_to_touchdown`` seconds before touch-down (the foot is landing);
* with the ZMP margin at least ``required_margin``, and among those the least departure from the commanded walk;
  if no candidate reaches it, the one with the largest margin (a capture step), after which the walk goes on or
  stops (``on_failure``), with the reason logged.

Why it is cheap: moving the landing ``F[k+1]`` by ``delta`` moves every later footprint by ``delta`` too (strides
are relative), so every anchor of the plan moves by ``w_a delta`` with ``w_a`` in {0, 1/2, 1}, and the ZMP of the
free segment at time ``t_i`` moves by ``g_i delta`` with ``g_i = sum_a M[i, a] w_a``. For ``C`` candidates and
``T`` sample times the margins are one ``(C, T, 2)`` array against the polygon's half-planes: a thousand
candidates in a few hundred microseconds.

Step timing (Morisawa et al. 2006), with ``adapt_timing``: the single support of the step being adjusted may also
end sooner, a landing sooner moving the ZMP's anchors sooner, or (with ``max_single_support``) later, which gives
the stance sole longer to catch a push toward its outside. A new duration changes the plan's operator, not its
inputs, so each candidate duration ``d`` has its own rows ``M_d`` (built in one batch, ahead where the durations
are known ahead, and kept with the plan's layout); the landings are then weighed against every duration at once,
``(D, C)`` margins, and the choice minimises ``|delta|^2 + (time_cost * (d - d_nominal))^2`` among the candidates
that reach the margin (``docs/closed_loop.md``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from rtgait.core.geometry.footsteps import Footstep, SoleRect, mean_heading

if TYPE_CHECKING:
    from rtgait.core.walk.walk import Walk


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
        ranges = {"max_length": (0.0, 2.0, "m", False), "min_width": (0.0, 2.0, "m", False),
                  "max_width": (0.0, 2.0, "m", False), "max_swing_speed": (0.0, 20.0, "m/s", False),
                  "min_time_to_touchdown": (0.0, 1.0, "s", True), "min_single_support": (0.05, 5.0, "s", True)}
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

    def __post_init__(self) -> None:
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


def candidate_landings(adjust: StepAdjustment, stance: Footstep, nominal: Footstep) -> np.ndarray:
    """Grid of landing points ``(grid**2, 2)`` (m) in the stride box around ``stance``, oriented along the mean
    heading of the stance and the nominal landing (as :func:`~rtgait.core.geometry.footsteps.place_step` measures a
    stride)."""
    limits = adjust.limits
    local = _stride_box_grid(limits.max_length, limits.min_width, limits.max_width, adjust.grid, nominal.side)
    heading = mean_heading(stance.yaw, nominal.yaw)
    c, s = math.cos(heading), math.sin(heading)
    return local @ np.array([[c, s], [-s, c]]) + np.array([stance.x, stance.y])


@lru_cache(maxsize=64)
def _stride_box_grid(max_length: float, min_width: float, max_width: float, grid: int, side: str) -> np.ndarray:
    """The candidate grid in the stance foot's frame, ``(grid**2, 2)`` (m, read-only): along, then lateral
    (toward the landing's side)."""
    along = np.linspace(-max_length, max_length, grid)
    lateral = np.linspace(min_width, max_width, grid)
    if side == "right":
        lateral = -lateral
    a, b = np.meshgrid(along, lateral, indexing="ij")
    local = np.stack([a.ravel(), b.ravel()], axis=1)
    local.setflags(write=False)
    return local


def choose_step(
    adjust: StepAdjustment,
    candidates: np.ndarray,
    nominal: tuple[float, float],
    zmp: np.ndarray,
    gain: np.ndarray,
    halfplanes: tuple[np.ndarray, np.ndarray],
    swing_from: tuple[float, float],
    time_left: np.ndarray,
    time_change: np.ndarray,
) -> tuple[int, np.ndarray, float, bool] | None:
    """The timing and landing to take among ``D`` timings and ``candidates`` ``(C, 2)``: the timing's index, the
    landing, its margin (m) and whether that reaches ``required_margin``.

    Args:
        zmp: the free segment's ZMP with the nominal landing under each timing, ``(D, T, 2)`` (m).
        gain: how much that ZMP moves per metre the landing moves, under each timing, ``(D, T)``.
        time_left: until the touch-down under each timing (s), ``(D,)``: a landing is reachable if the swing foot
            covers the distance from ``swing_from`` (m) at ``max_swing_speed`` in that time.
        time_change: each timing's change of the single support (s, negative: sooner), ``(D,)``; 0 for the
            nominal one, which comes first (of equal departures the first candidate wins, so the nominal timing does).

    The margin of candidate ``(d, c)`` is ``min_t min_k b_k - n_k . (zmp[d, t] + gain[d, t] delta_c)``; among the
    candidates reaching ``required_margin`` the least departure ``|delta_c|^2 + (time_cost time_change_d)^2``
    wins; when none does, the largest margin among the timings no longer than the nominal one, and of candidates
    within a millimetre of it the least departure.
    Returns ``None`` when no candidate can be reached in time.
    """
    distance = np.hypot(candidates[:, 0] - swing_from[0], candidates[:, 1] - swing_from[1])
    reachable = distance[None, :] <= adjust.limits.max_swing_speed * np.asarray(time_left)[:, None]  # (D, C)
    if not reachable.any():
        return None
    delta = candidates - np.asarray(nominal)
    # margin(d, c, t, k) = b_k - n_k . (zmp_dt + g_dt delta_c) = A[d, t, k] - g_dt D[c, k]: two small products and
    # one broadcast per edge, instead of moving every (timing, candidate, time) point through the polygon.
    normals, offsets = halfplanes
    # Laid out (K, T, D, C) so that the minimum over the sample times is a reduction over the leading axis (fast
    # elementwise minima of contiguous rows, not a short reduction per candidate), one edge at a time (an edge's
    # (T, D, C) block stays in cache).
    base = np.ascontiguousarray((offsets - zmp @ normals.T).transpose(2, 1, 0))[..., None]  # (K, T, D, 1)
    along = np.ascontiguousarray((delta @ normals.T).T)  # (K, C)
    spread = np.ascontiguousarray(np.asarray(gain).T)[:, :, None]  # (T, D, 1)
    margin = np.full(reachable.shape, np.inf)
    block = np.empty((spread.shape[0], *reachable.shape))
    for k in range(base.shape[0]):
        np.multiply(spread, along[k], out=block)
        np.subtract(base[k], block, out=block)
        np.minimum(margin, np.minimum.reduce(block, axis=0), out=margin)
    margin[~reachable] = -np.inf
    timing_departure = (adjust.time_cost * np.asarray(time_change))[:, None] ** 2
    departure = np.einsum("cd,cd->c", delta, delta)[None, :] + timing_departure
    enough = margin >= adjust.required_margin
    if enough.any():
        best = int(np.argmin(np.where(enough, departure, np.inf)))
    else:
        # Nothing is enough: the largest margin, and of candidates within a millimetre of it the nearest one (the
        # margin is often flat along one axis of the box). Not a longer single support: held longer with its ZMP
        # still outside the sole, a stance only lets the fall grow (the sole tips about its edge); the step is the
        # answer then, and it comes no later than planned.
        later = np.asarray(time_change) > 0.0
        if later.any() and not later.all():
            margin[later] = -np.inf
        near_best = margin >= margin.max() - 1e-3
        best = int(np.argmin(np.where(near_best, departure, np.inf)))
    d, c = divmod(best, margin.shape[1])
    return d, candidates[c], float(margin[d, c]), bool(enough[d, c])


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


class LandingProposal(NamedTuple):
    """Where step adjustment would land ``step``: the landing ``(x, y)`` (m), the margin it predicts (m), whether
    that reaches the required margin, how many candidates were weighed, whether the step is swinging now, its
    single-support duration (s) and nominal one, and which of the planner's :class:`TimingOptions` it takes
    (``-1``: the nominal timing)."""

    step: int
    nominal: Footstep
    landing: tuple[float, float]
    margin: float
    enough: bool
    candidates: int
    swinging: bool
    single_support: float = math.nan
    nominal_single_support: float = math.nan
    timing: int = -1


def propose_landing(
    adjust: StepAdjustment,
    walk: Walk,
    q: int,
    t: float,
    phase_start: Callable[[int], float],
    rows: np.ndarray,
    zmp: np.ndarray,
    halfplanes: tuple[np.ndarray, np.ndarray],
    anchor_phases: Sequence[int],
    swing_position: Callable[[], tuple[float, float]],
    timings: Callable[[int, bool], TimingOptions | None] | None = None,
) -> LandingProposal | None:
    """The landing (and, with ``timings``, the single-support duration) of the next step that can still change,
    for a plan starting at phase ``q`` whose free segment's ZMP at the sample times is ``zmp = rows @ y`` (m);
    ``None`` if no step can move (the last one has landed, or no candidate can be reached in time).

    The step is the one swinging in a single support, unless it lands within ``min_time_to_touchdown`` of ``t``
    (s), else the next one to lift off. ``phase_start(p)`` is the absolute start of phase ``p`` (s);
    ``swing_position()`` where the swinging foot is now (m); ``timings(step, swinging)`` the other durations the
    planner offers for that step (:class:`TimingOptions`), or ``None``.
    """
    kind = walk.timeline.kind(q)
    k = (q + 1) // 2 if kind == "single" else q // 2 + 1
    touchdown = phase_start(2 * k)
    if kind == "single" and touchdown - t < adjust.limits.min_time_to_touchdown:
        k += 1
        touchdown = phase_start(2 * k)
    n = walk.n_steps
    if n is not None and k > n:
        return None
    swinging = kind == "single" and k == (q + 1) // 2
    if swinging:
        swing_from = swing_position()
    else:
        origin = walk.footprint(k - 1)
        swing_from = (origin.x, origin.y)
    nominal = walk.footprint(k + 1)
    # Every anchor resting on F[k + 1] or later moves with the landing; one between the final feet, half as much.
    weights = np.array([(a >= k + 1) + (b >= k + 1) for a, b in walk.anchor_sources(q, anchor_phases)]) * 0.5
    candidates = candidate_landings(adjust, walk.footprint(k), nominal)
    single = walk.timeline.duration(2 * k - 1)
    options = timings(k, swinging) if timings is not None else None
    if options is None:
        zmps, gains, singles = zmp[None], (rows[:, 4:] @ weights)[None], np.array([single])
    else:
        zmps = np.concatenate((zmp[None], options.zmp))
        gains = np.concatenate(((rows[:, 4:] @ weights)[None], options.rows[:, :, 4:] @ weights))
        singles = np.concatenate(([single], options.single_support))
    change = singles - single  # a shorter single support lands that much sooner
    choice = choose_step(
        adjust, candidates, (nominal.x, nominal.y), zmps, gains, halfplanes, swing_from, touchdown - t + change, change
    )
    if choice is None:
        return None
    d, landing, margin, enough = choice
    return LandingProposal(
        k, nominal, (float(landing[0]), float(landing[1])), margin, enough, len(candidates) * len(singles), swinging,
        float(singles[d]), single, d - 1,
    )  # fmt: skip


__all__ = [
    "ON_FAILURE",
    "STEPPING_KEYS",
    "LandingProposal",
    "StepAdjustment",
    "StepDecision",
    "SteppingLimits",
    "TimingOptions",
    "candidate_landings",
    "choose_step",
    "propose_landing",
    "remainder_options",
    "single_support_options",
]
