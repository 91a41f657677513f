"""The phase timeline of a walk: phase durations (:class:`Timing`) and their boundaries (:class:`Timeline`).

Phases are numbered ``q = 0, 1, 2, ...``: ``q = 0`` is the starting double support (ZMP from between the feet
to the first stance foot), ``q = 2i - 1`` the single support of step ``i``, ``q = 2i`` the double support after
step ``i`` lands (feet ``F[i]`` and ``F[i + 1]``). In a walk of ``N`` steps, phase ``2N`` is the final double
support (ZMP back between the feet) and ``2N + 1`` the settling phase in which the COG comes to rest. The names are
also importable from :mod:`rtgait.core.geometry.footsteps`, their former home.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field
from typing import Literal

from rtgait.core.limits import MAX_PHASE_DURATION, MAX_PHASE_W_T, MIN_PHASE_DURATION, check_range

__all__ = ["PhaseKind", "Timeline", "Timing", "check_step_timings"]


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
