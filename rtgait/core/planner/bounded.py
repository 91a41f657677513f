"""The online planner's guard on its closed-loop calls: each argument checked against its bound before anything
changes, and what a refused call began undone.

:class:`~rtgait.core.planner.online.OnlinePlanner` takes these methods from :class:`BoundedCalls` (a mixin, like
:class:`~rtgait.core.planner.measured.MeasuredPlanning`). The bounds are those of :mod:`rtgait.core.input_bounds`,
made concrete for the planner's configuration here (:func:`landing_bounds`, the COM's reach and speed): a refused
call raises :class:`~rtgait.core.input_bounds.InputOutOfBoundsError`.

Checking first is the rule, and on the per-tick path the only guard (``observe`` costs a few float comparisons).
A call that must change the planner before it knows whether its input is acceptable (``touchdown`` samples the
landing instant to learn which footprint landed), or that goes through the whole replanning machinery
(``replan_now``, the walk's changes), runs inside :meth:`BoundedCalls._atomic`: a copy of the planner's state
(:meth:`BoundedCalls._save`) is put back if the call raises, whatever it raised.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator, Sequence

from rtgait.core.geometry.footsteps import Footstep
from rtgait.core.input_bounds import (
    COM_REACH_HEIGHTS,
    COM_SPEED_FROUDE,
    LANDING_TOLERANCE,
    MAX_TIME,
    InputOutOfBoundsError,
    LandingBounds,
    check_position,
)
from rtgait.core.laws.stepping import SteppingLimits
from rtgait.core.limits import MAX_REPLANS_PER_SAMPLE, MAX_STRIDE
from rtgait.core.planner.config import PlannerConfig

DEFAULT_STEPPING_HEIGHT = 0.8
"""COM height (m) the :class:`~rtgait.core.laws.stepping.SteppingLimits` defaults are set for: a planner without
step adjustment bounds landings by those defaults scaled by ``cog_height / 0.8``, as the controllers scale them by
leg length (:func:`rtgait.control.settings.step_limits`)."""

_SCALARS = (
    "_plan", "_next_replan_time", "_next_replan_phase", "_t0", "_latest", "_phase", "_start_state", "_observed",
    "_observed_on_plan", "_commit_time", "replan_count", "step_adjustment_count", "_swing_retarget",
    "_last_auto_replan", "_prepared", "_reach",
)  # fmt: skip
"""The planner's fields a call may reassign (never mutate in place), saved by reference."""


def landing_bounds(config: PlannerConfig) -> LandingBounds:
    """The stride box of a measured landing for ``config``: the widest of the walk's velocity limits
    (``max_step_length``; widths from ``min_step_width`` or ``step_width`` to ``step_width + max_step_lateral``),
    step adjustment's :class:`~rtgait.core.laws.stepping.SteppingLimits` (``config.step_adjustment``'s, and the
    defaults scaled to the COM height: a controller may pass its own per replan), to be widened by
    :data:`~rtgait.core.input_bounds.LANDING_TOLERANCE` and capped at :data:`~rtgait.core.limits.MAX_STRIDE` (m)."""
    scale = config.cog_height / DEFAULT_STEPPING_HEIGHT
    default = SteppingLimits()
    limits = [(default.max_length * scale, default.min_width * scale, default.max_width * scale)]
    if config.step_adjustment is not None:
        own = config.step_adjustment.limits
        limits.append((own.max_length, own.min_width, own.max_width))
    narrowest = config.min_step_width if config.min_step_width is not None else config.step_width
    limits.append((config.max_step_length, narrowest, config.step_width + config.max_step_lateral))
    return LandingBounds(
        max_length=max(length for length, _, _ in limits),
        min_width=min(low for _, low, _ in limits),
        max_width=max(high for _, _, high in limits),
        tolerance=LANDING_TOLERANCE,
        max_stride=MAX_STRIDE,
    )


class BoundedCalls:
    """The bounds and the undo of :class:`~rtgait.core.planner.online.OnlinePlanner` (see the module docstring)."""

    def _init_bounds(self) -> None:
        config = self.config
        self._landing_bounds = landing_bounds(config)
        self._com_reach = COM_REACH_HEIGHTS * config.cog_height  # m, beyond half the feet's distance
        self._max_com_speed = COM_SPEED_FROUDE * math.sqrt(config.gravity * config.cog_height)  # m/s
        self._max_com_speed2 = self._max_com_speed**2
        self._reach: tuple | None = None  # (phase it was made for, centre x, y, squared radius) for observe
        self._atomic_depth = 0

    # ----- times --------------------------------------------------------------------------------------------
    def _check_time(self, name: str, t: float) -> None:
        """``t`` (s) must be within :data:`~rtgait.core.input_bounds.MAX_TIME` of zero (so finite) and less than
        :data:`~rtgait.core.limits.MAX_REPLANS_PER_SAMPLE` double supports past the next replan (one call makes at
        most that many)."""
        if not abs(t) <= MAX_TIME:  # also refuses NaN
            raise InputOutOfBoundsError(f"{name} must be finite and within +-{MAX_TIME:g} s, got {t}")
        q = self._next_replan_phase
        if q is None or t < self._next_replan_time:
            return
        far = q + 2 * MAX_REPLANS_PER_SAMPLE
        last = self.timeline.last_phase
        if last is not None and far > last:
            return  # the walk ends within the bound: every replan left fits in one call
        limit = self.phase_start(far)
        if t >= limit:
            raise InputOutOfBoundsError(
                f"{name}={t} s must be before {limit} s: at most {MAX_REPLANS_PER_SAMPLE} double supports past the "
                f"plan under way (sample the planner at least once per step)"
            )

    def _check_not_before_latest(self, name: str, t: float) -> None:
        if t < self._latest:
            raise InputOutOfBoundsError(f"{name}={t} s must not be before the latest sample ({self._latest} s)")

    # ----- the measured COM --------------------------------------------------------------------------------
    def _reach_now(self) -> tuple:
        """``(phase, cx, cy, r^2)``: the centre (m) and squared radius (m^2) a measured COM must lie within, from
        the feet on the ground in the phase last sampled (or, before the first sample, the first phase)."""
        phase = self._phase
        if phase is not None:
            feet = phase.feet
            if len(feet) == 4:  # single support: (x, y, z, yaw) of the stance foot
                cx, cy, half = feet[0], feet[1], 0.0
            else:  # double support: left then right
                cx, cy = 0.5 * (feet[0] + feet[4]), 0.5 * (feet[1] + feet[5])
                half = 0.5 * math.hypot(feet[4] - feet[0], feet[5] - feet[1])
        else:
            contact = self._walk.contact_feet(self._walk.latest_phase or 0)
            a, b = contact[0], contact[-1]
            cx, cy = 0.5 * (a.x + b.x), 0.5 * (a.y + b.y)
            half = 0.5 * math.hypot(b.x - a.x, b.y - a.y)
        reach = self._reach = (phase, cx, cy, (self._com_reach + half) ** 2)
        return reach

    def _refuse_observation(self, values: tuple[float, float, float, float, float]) -> None:
        """Raise the error that says which of ``(t, cx, cy, vx, vy)`` is beyond which bound (off the per-tick path)."""
        t, cx, cy, vx, vy = values
        if not all(math.isfinite(v) for v in values):
            raise InputOutOfBoundsError(f"observe needs a finite t, cog and cog_vel, got {values}")
        _, mx, my, r2 = self._reach_now()
        if math.hypot(cx - mx, cy - my) > math.sqrt(r2):
            raise InputOutOfBoundsError(
                f"observe: cog ({cx}, {cy}) must be within {math.sqrt(r2):.3f} m of the feet's midpoint ({mx:.3f}, "
                f"{my:.3f}) (COM_REACH_HEIGHTS = {COM_REACH_HEIGHTS:g} COM heights plus half the feet's distance)"
            )
        if math.hypot(vx, vy) > self._max_com_speed:
            raise InputOutOfBoundsError(
                f"observe: cog_vel ({vx}, {vy}) must be at most {self._max_com_speed:.3f} m/s (COM_SPEED_FROUDE = "
                f"{COM_SPEED_FROUDE:g} times sqrt(g cog_height))"
            )
        raise InputOutOfBoundsError(f"observe: t must be a time a float sum does not overflow, got {t}")

    def _check_com(self, cog: tuple[float, float], cog_vel: tuple[float, float], feet: tuple[Footstep, ...]) -> None:
        """A COM state given to ``start`` within reach of the standing ``feet`` and below the speed bound."""
        a, b = feet
        mx, my = 0.5 * (a.x + b.x), 0.5 * (a.y + b.y)
        radius = self._com_reach + 0.5 * math.hypot(b.x - a.x, b.y - a.y)
        check_position("cog", *cog)
        if math.hypot(cog[0] - mx, cog[1] - my) > radius:
            raise InputOutOfBoundsError(
                f"cog {cog} must be within {radius:.3f} m of the feet's midpoint ({mx:.3f}, {my:.3f})"
            )
        if math.hypot(*cog_vel) > self._max_com_speed:
            raise InputOutOfBoundsError(f"cog_vel {cog_vel} must be at most {self._max_com_speed:.3f} m/s")

    # ----- landings -----------------------------------------------------------------------------------------
    def _check_landing(self, index: int, footprint: Footstep) -> None:
        """``footprint`` may replace ``F[index]``: within the landing box of the foot it stepped from (``F[index -
        1]``; for ``F[0]``, the box of ``F[1]`` from it), the box widened to the stride planned there."""
        walk = self._walk
        if index >= 1:
            stance, old, new = walk.footprint(index - 1), walk.footprint(index), footprint
            planned = (stance, old)
        else:
            stance, new = footprint, walk.footprint(1)
            planned = (walk.footprint(0), new)
        self._landing_bounds.check(f"touchdown of footprint {index}", stance, new, planned)

    # ----- undo ---------------------------------------------------------------------------------------------
    def _save(self) -> tuple:
        """What a call may change, to put back with :meth:`_restore`."""
        return (
            tuple(getattr(self, name) for name in _SCALARS),
            dict(self._layout_at),
            tuple(self.plans),
            tuple(self.change_log),
            tuple(self.step_adjustments),
            dict(self._auto.held),
            self._walk.snapshot(),
        )

    def _restore(self, saved: tuple) -> None:
        scalars, layout_at, plans, changes, adjustments, held, walk = saved
        for name, value in zip(_SCALARS, scalars, strict=True):
            setattr(self, name, value)
        self._layout_at = layout_at
        for records, old in ((self.plans, plans), (self.change_log, changes), (self.step_adjustments, adjustments)):
            records.clear()
            records.extend(old)
        self._auto.held.clear()
        self._auto.held.update(held)
        self._walk.restore(walk)

    @contextlib.contextmanager
    def _atomic(self) -> Iterator[None]:
        """Whatever the block raises, the planner is put back as it was before it (nested blocks: the outermost)."""
        if self._atomic_depth:
            yield
            return
        saved = self._save()
        self._atomic_depth = 1
        try:
            yield
        except BaseException:
            self._restore(saved)
            raise
        finally:
            self._atomic_depth = 0


def measured_pair(
    name: str, value: Sequence[float] | None, default: tuple[float, float] | None
) -> tuple[float, float] | None:
    """``value`` as two floats (``default`` when ``None``), refused unless finite (``name`` in the message)."""
    if value is None:
        return default
    pair = (float(value[0]), float(value[1]))
    if not all(math.isfinite(v) for v in pair):
        raise InputOutOfBoundsError(f"{name} must be finite, got {pair}")
    return pair


__all__ = ["DEFAULT_STEPPING_HEIGHT", "BoundedCalls", "landing_bounds", "measured_pair"]
