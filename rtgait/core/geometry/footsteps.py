"""Footsteps, strides, sole rectangles and the phase timeline of a walk.

A footprint is a foothold in 3D: its foot frame position ``(x, y, z)`` (m), heading ``yaw`` and the support
surface's ``pitch`` and ``roll`` (rad, rotations about the foot's lateral and forward axes; 0 on level ground). A
stride carries the height change ``rise = z_landing - z_stance`` and the landing surface's pitch and roll, so that a
change of a stride's length keeps the step's height.

Footprints are numbered ``F[0], F[1], ...``: ``F[0]`` is the standing position of the foot that swings first,
``F[1]`` that of the other foot, and ``F[i + 1]`` is where step ``i`` (1-based) lands. Step ``i`` swings the
foot from ``F[i - 1]`` to ``F[i + 1]`` while the robot stands on ``F[i]``.

Phases are numbered ``q = 0, 1, 2, ...``: ``q = 0`` is the starting double support (ZMP from between the feet
to the first stance foot), ``q = 2i - 1`` the single support of step ``i``, ``q = 2i`` the double support after
step ``i`` lands (feet ``F[i]`` and ``F[i + 1]``). In a walk of ``N`` steps, phase ``2N`` is the final double
support (ZMP back between the feet) and ``2N + 1`` the settling phase in which the COG comes to rest.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from rtgait.core.input_bounds import InputOutOfBoundsError
from rtgait.core.limits import (
    MAX_PHASE_DURATION,
    MAX_PHASE_W_T,
    MAX_STRIDE,
    MAX_SURFACE_TILT,
    MIN_PHASE_DURATION,
    check_range,
)

Side = Literal["left", "right"]
SIDES: tuple[Side, Side] = ("left", "right")


def other_side(side: Side) -> Side:
    return "right" if side == "left" else "left"


def wrap_angle(angle: float) -> float:
    """Angle wrapped to ``[-pi, pi)`` (rad)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def _require_finite(name: str, value: float) -> None:
    if not math.isfinite(value):
        raise InputOutOfBoundsError(f"{name} must be a finite number, got {value}")


def _check_height_and_tilt(what: str, z: float, pitch: float, roll: float) -> None:
    """``z`` within +-:data:`MAX_STRIDE` m, ``pitch`` and ``roll`` within +-:data:`MAX_SURFACE_TILT` rad."""
    if not abs(z) <= MAX_STRIDE:  # also refuses NaN
        raise InputOutOfBoundsError(f"{what} z (height) must be finite and within +-{MAX_STRIDE:g} m, got {z}")
    for name, value in (("pitch", pitch), ("roll", roll)):
        if not abs(value) <= MAX_SURFACE_TILT:
            raise InputOutOfBoundsError(
                f"{what} {name} must be finite and within +-{MAX_SURFACE_TILT:g} rad, got {value}"
            )


@dataclass(frozen=True, slots=True)
class Footstep:
    """A footprint: foot frame position (m), yaw (rad), which foot, and its height ``z`` (m) and the support
    surface's ``pitch`` and ``roll`` (rad, each within :data:`~rtgait.core.limits.MAX_SURFACE_TILT`)."""

    x: float
    y: float
    yaw: float
    side: Side
    z: float = 0.0
    pitch: float = 0.0
    roll: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.x) and math.isfinite(self.y) and math.isfinite(self.yaw)):
            for name in ("x", "y", "yaw"):
                _require_finite(f"footstep {name}", getattr(self, name))
        if self.side not in SIDES:
            raise InputOutOfBoundsError(f"footstep side must be 'left' or 'right', got {self.side!r}")
        if self.z or self.pitch or self.roll:  # level footprints (the common case) skip the checks
            _check_height_and_tilt("footstep", self.z, self.pitch, self.roll)

    @property
    def level(self) -> bool:
        """True on level ground at height 0 (every footprint of a flat walk)."""
        return not (self.z or self.pitch or self.roll)

    @property
    def position(self) -> np.ndarray:
        return np.array([self.x, self.y])


@dataclass(frozen=True)
class Stride:
    """Where a step lands relative to the previous footprint (the stance foot).

    Attributes:
        length: forward displacement along the mean heading of the two footprints (m).
        width: lateral distance between the two footprints, positive = feet apart (m).
        turn: yaw change from the stance foot to the landing foot (rad), positive = to the left.
        rise: height of the landing above the stance foot (m), negative = down.
        pitch: pitch of the landing's support surface (rad, absolute, not relative to the stance foot's).
        roll: roll of the landing's support surface (rad, absolute).
    """

    length: float
    width: float
    turn: float = 0.0
    rise: float = 0.0
    pitch: float = 0.0
    roll: float = 0.0

    def __post_init__(self) -> None:
        if self.rise or self.pitch or self.roll:
            _check_height_and_tilt("stride", self.rise, self.pitch, self.roll)
        for name in ("length", "width", "turn"):
            _require_finite(f"stride {name}", getattr(self, name))
        if self.width <= 0.0:
            raise InputOutOfBoundsError(f"stride width must be > 0 m (feet apart), got {self.width}")
        if abs(self.length) > MAX_STRIDE or self.width > MAX_STRIDE:
            raise InputOutOfBoundsError(
                f"stride length and width must be at most {MAX_STRIDE:g} m, got {self.length}, {self.width}"
            )
        if abs(self.turn) >= math.pi / 2:
            raise InputOutOfBoundsError(f"stride turn must be within +-pi/2 rad, got {self.turn}")


def place_step(stance: Footstep, stride: Stride) -> Footstep:
    """Landing footprint of the other foot for ``stride`` taken from ``stance``."""
    side = other_side(stance.side)
    lateral = stride.width if side == "left" else -stride.width
    heading = stance.yaw + 0.5 * stride.turn
    c, s = math.cos(heading), math.sin(heading)
    return Footstep(
        x=stance.x + c * stride.length - s * lateral,
        y=stance.y + s * stride.length + c * lateral,
        yaw=wrap_angle(stance.yaw + stride.turn),
        side=side,
        z=stance.z + stride.rise,
        pitch=stride.pitch,
        roll=stride.roll,
    )


def stride_between(stance: Footstep, landing: Footstep) -> Stride:
    """Inverse of :func:`place_step`: the stride that takes ``stance`` to ``landing``."""
    if landing.side == stance.side:
        raise InputOutOfBoundsError("consecutive footprints must alternate between left and right")
    turn = wrap_angle(landing.yaw - stance.yaw)
    heading = stance.yaw + 0.5 * turn
    c, s = math.cos(heading), math.sin(heading)
    dx, dy = landing.x - stance.x, landing.y - stance.y
    lateral = -s * dx + c * dy
    width = lateral if landing.side == "left" else -lateral
    return Stride(c * dx + s * dy, width, turn, landing.z - stance.z, landing.pitch, landing.roll)


def standing_feet(step_width: float, first_side: Side = "right") -> tuple[Footstep, Footstep]:
    """``(F[0], F[1])``: feet side by side at the origin, ``step_width`` (m) apart, heading +x."""
    if not (math.isfinite(step_width) and step_width > 0.0):
        raise ValueError(f"step_width must be > 0 m, got {step_width}")
    if first_side not in SIDES:
        raise ValueError(f"first_side must be 'left' or 'right', got {first_side!r}")
    half = 0.5 * step_width
    first = Footstep(0.0, half if first_side == "left" else -half, 0.0, first_side)
    second = Footstep(0.0, -first.y, 0.0, other_side(first_side))
    return first, second


def place_footsteps(start: tuple[Footstep, Footstep], strides: list[Stride]) -> list[Footstep]:
    """Footprints ``F[0..N+1]`` of a walk of ``N = len(strides)`` steps from standing feet ``start``."""
    prints = list(start)
    for stride in strides:
        prints.append(place_step(prints[-1], stride))
    return prints


def midpoint(a: Footstep, b: Footstep) -> tuple[float, float]:
    """Point halfway between two footprints (m)."""
    return 0.5 * (a.x + b.x), 0.5 * (a.y + b.y)


def mean_heading(yaw_a: float, yaw_b: float) -> float:
    """The heading halfway between two (rad), the short way round: safe across the +-pi wrap."""
    return yaw_a + 0.5 * math.remainder(yaw_b - yaw_a, 2.0 * math.pi)


@dataclass(frozen=True)
class SoleRect:
    """Sole rectangle around the foot frame (m): ``front``/``back`` along the foot, ``inner`` toward the other
    foot, ``outer`` away from it. All distances are from the foot frame origin and non-negative."""

    front: float
    back: float
    inner: float
    outer: float

    def __post_init__(self) -> None:
        for name in ("front", "back", "inner", "outer"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"sole {name} must be a finite distance >= 0 m, got {value}")
        if self.front + self.back <= 0.0 or self.inner + self.outer <= 0.0:
            raise ValueError("sole rectangle must have a positive length and width")

    def corners(self, foot: Footstep) -> np.ndarray:
        """World corners of the sole of ``foot``, counter-clockwise, shape ``(4, 2)`` (m)."""
        left = foot.side == "left"
        y_max = self.outer if left else self.inner
        y_min = -self.inner if left else -self.outer
        local = np.array([[self.front, y_min], [self.front, y_max], [-self.back, y_max], [-self.back, y_min]])
        c, s = math.cos(foot.yaw), math.sin(foot.yaw)
        rotation = np.array([[c, -s], [s, c]])
        return local @ rotation.T + foot.position


def _check_duration(name: str, value: float) -> None:
    if not (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} must be a finite duration > 0 s, got {value}")
    check_range(name, value, MIN_PHASE_DURATION, MAX_PHASE_DURATION, "s")


@dataclass(frozen=True)
class Timing:
    """Phase durations of a walk (s).

    Attributes:
        single_support: one foot on the ground, the other swinging (``T_s``).
        double_support: both feet on the ground between steps (``T_dbl``).
        start: initial double support, ZMP from between the feet to the first stance foot.
        end: final double support, ZMP from the last stance foot back between the feet.
        settle: ZMP held between the feet while the COG comes to rest.
        per_step: optional per-step timing, ``per_step[k - 1] = (single support of step k, double support after
            it)`` (s); steps beyond the tuple take ``single_support`` and ``double_support``. The double support
            after the walk's last step is the final one (``end``), so the last entry's second value is unused.
            Carried to the planner with the rest of the timing (:class:`Timeline`); a walk by velocity command
            ignores it (its steps are uniform).
    """

    single_support: float
    double_support: float
    start: float = 1.0
    end: float = 1.0
    settle: float = 2.0
    per_step: tuple[tuple[float, float], ...] = ()

    def __post_init__(self) -> None:
        for name in ("single_support", "double_support", "start", "end", "settle"):
            _check_duration(f"timing {name}", getattr(self, name))
        if not isinstance(self.per_step, tuple):
            raise ValueError(f"timing per_step must be a tuple of (single, double) pairs, got {type(self.per_step)}")
        for k, pair in enumerate(self.per_step, start=1):
            if not (isinstance(pair, tuple) and len(pair) == 2):
                raise ValueError(f"timing per_step[{k - 1}] (step {k}) must be a (single, double) pair, got {pair!r}")
            _check_duration(f"step {k} single_support", pair[0])
            _check_duration(f"step {k} double_support", pair[1])

    @property
    def uniform(self) -> bool:
        """True when every step has the same timing (no :attr:`per_step`)."""
        return not self.per_step

    @property
    def shortest_phase(self) -> float:
        """Shortest duration of any phase (s), ``settle`` excepted, per-step ones included."""
        values = [self.single_support, self.double_support, self.start, self.end]
        values += [d for pair in self.per_step for d in pair]
        return min(values)

    @property
    def step_period(self) -> float:
        """Time from one lift-off to the next (s)."""
        return self.single_support + self.double_support


def check_step_timings(timing: Timing, w: float) -> None:
    """Every per-step phase of ``timing`` satisfies ``w T <= MAX_PHASE_W_T`` (``w`` in 1/s; the global phases are
    checked by :class:`~rtgait.core.planner.config.PlannerConfig`)."""
    for k, pair in enumerate(timing.per_step, start=1):
        for name, value in zip(("single_support", "double_support"), pair, strict=True):
            if w * value > MAX_PHASE_W_T:
                raise ValueError(
                    f"step {k} {name} must be at most {MAX_PHASE_W_T / w:.3g} s at this COG height and gravity "
                    f"(w T <= {MAX_PHASE_W_T:g}), got {value}"
                )


PhaseKind = Literal["start", "single", "double", "end", "settle"]


@dataclass(frozen=True)
class Timeline:
    """Phase boundaries of a walk of ``n_steps`` steps (``None``: no end planned yet), times from its start.

    ``step_timings[k - 1] = (single support of step k, double support after it)`` (s) gives steps their own
    timing (:attr:`Timing.per_step`); later steps take ``timing``'s. A uniform timeline computes boundaries in
    closed form; a per-step one precomputes the start times of its phases up to the first uniform single support
    (a bisection finds a phase there) and continues in closed form after it. Its start times are the uniform
    closed form plus the accumulated differences of the given durations from the uniform ones, so per-step timings
    equal to the global timing give exactly the uniform boundaries.
    """

    timing: Timing
    n_steps: int | None = None
    step_timings: tuple[tuple[float, float], ...] = ()
    _starts: tuple[float, ...] = field(default=(), init=False, repr=False, compare=False)
    _cut: int = field(default=-1, init=False, repr=False, compare=False)
    _shift: float = field(default=0.0, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not self.step_timings:
            return
        if not isinstance(self.step_timings, tuple):
            object.__setattr__(self, "step_timings", tuple(self.step_timings))
        # Phases from `cut` on all have uniform durations (steps past the given ones, the end and settling).
        cut = 2 * len(self.step_timings) + 1
        if self.n_steps is not None:
            cut = min(cut, 2 * self.n_steps + 1)
        uniform = Timeline(self.timing, self.n_steps)
        shift, starts = 0.0, [0.0]
        for q in range(cut):
            shift += self.duration(q) - uniform.duration(q)
            starts.append(self._uniform_start(q + 1) + shift)
        object.__setattr__(self, "_starts", tuple(starts))
        object.__setattr__(self, "_cut", cut)
        object.__setattr__(self, "_shift", shift)

    @property
    def uniform(self) -> bool:
        """True when every step has the global timing (the closed-form boundaries apply)."""
        return not self.step_timings

    def step_timing(self, step: int) -> tuple[float, float]:
        """``(single support, double support after it)`` of ``step`` (1-based, s)."""
        if 1 <= step <= len(self.step_timings):
            return self.step_timings[step - 1]
        return self.timing.single_support, self.timing.double_support

    def kind(self, q: int) -> PhaseKind:
        if q == 0:
            return "start"
        if q % 2 == 1:
            return "single" if self.n_steps is None or q < 2 * self.n_steps else "settle"
        if self.n_steps is not None and q == 2 * self.n_steps:
            return "end"
        return "double"

    def duration(self, q: int) -> float:
        kind = self.kind(q)
        t = self.timing
        if kind == "single":
            return self.step_timing((q + 1) >> 1)[0] if self.step_timings else t.single_support
        if kind == "double":
            return self.step_timing(q >> 1)[1] if self.step_timings else t.double_support
        return t.start if kind == "start" else t.end if kind == "end" else t.settle

    def durations(self, first: int, last: int) -> tuple[float, ...]:
        """Durations of phases ``first..last`` (s)."""
        return tuple(self.duration(q) for q in range(first, last + 1))

    def start_time(self, q: int) -> float:
        """Start of phase ``q`` relative to the walk's start (s)."""
        if self.step_timings:
            cut = self._cut
            if q <= cut:
                return self._starts[q]
            return self._uniform_start(q) + self._shift
        return self._uniform_start(q)

    def _uniform_start(self, q: int) -> float:
        """:meth:`start_time` with every step at the global timing."""
        if q == 0:
            return 0.0
        t = self.timing
        # Step (q + 1) // 2 has its single support in phase 2 step - 1; the settling phase follows the end phase.
        if q & 1 and self.n_steps is not None and q == 2 * self.n_steps + 1:
            return t.start + (self.n_steps - 1) * (t.single_support + t.double_support) + t.single_support + t.end
        time = t.start + ((q + 1) // 2 - 1) * (t.single_support + t.double_support)
        return time if q & 1 else time + t.single_support

    @property
    def last_phase(self) -> int | None:
        return None if self.n_steps is None else 2 * self.n_steps + 1

    @property
    def end_time(self) -> float:
        """End of the settling phase (s); ``inf`` while no end is planned."""
        if self.n_steps is None:
            return math.inf
        q = 2 * self.n_steps + 1
        return self.start_time(q) + self.timing.settle

    def phase_at(self, t: float) -> int:
        """Phase index containing time ``t`` (s from the start); clamped to the first and last phase.

        A time equal to a phase's :meth:`start_time` belongs to that phase, exactly: the first guess (a floor
        division, or a bisection of the precomputed start times of a per-step timeline) can be one phase off by
        rounding, and comparing with the start times settles it.
        """
        timing = self.timing
        if t < timing.start:
            return 0
        if self.step_timings and t < self._starts[self._cut]:
            return max(bisect.bisect_right(self._starts, t) - 1, 0)
        u = t
        if self.step_timings:  # past the per-step phases: the uniform guess, shifted to where they end
            u = t - self._shift
        k = int((u - timing.start) // timing.step_period)
        q = 2 * k + 1 if (u - timing.start) - k * timing.step_period < timing.single_support else 2 * k + 2
        last = self.last_phase
        if last is not None and q > last:
            q = last
        while q > 0 and t < self.start_time(q):
            q -= 1
        while (last is None or q < last) and self.start_time(q + 1) <= t:
            q += 1
        return q
