"""The feet's targets ``(x, y, z, yaw)`` (m, rad) as their landings leave them: the height offsets over the plan's, the
hold of an early landing, the way of a foot that met ground short of its foothold, and the blends of the IK's targets.
:class:`~rtgait.control.landings.FootLandings` takes these methods from :class:`FootTargets` (a mixin); the
equations are in :mod:`rtgait.control.landings`' docstring ("Heights", "Blends").
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from rtgait.control.late_descent import descent_depth

if TYPE_CHECKING:
    from collections.abc import Sequence

    from rtgait.control.target_blend import Pose
    from rtgait.core.planner.sample import SampleValues

__all__ = ["SHORT_LANDING", "SKIM_CLEARANCE", "FootTargets"]

SHORT_LANDING = 0.03
"""Distance (m) from the swing's planned foothold beyond which an early touch-down is ground met short of it (module
docstring): a sag or a servo lag lands within millimetres of it, the horizontal swing being over before the last
descent; an unseen 3 cm step met by the sole's toe is several centimetres short."""

SKIM_CLEARANCE = 0.015
"""Height (m) a foot that met ground short of its foothold keeps above it on the way there: from
:data:`SHORT_LANDING` away on, lowered in proportion to the distance left to the height it touched."""


class FootTargets:
    """The target methods of :class:`~rtgait.control.landings.FootLandings` (see the module docstring); the state
    they read and write is the landings'."""

    def _update_heights(self, t: float) -> None:
        """This tick's height offsets of the feet's targets (m): a landing height blended out over the swing that
        follows it, or the descent of a late foot."""
        for i in (0, 1):
            blend = self._blend[i]
            if blend is not None:
                height, start, duration = blend
                s = (t - start) / duration
                if s >= 1.0:
                    self._blend[i] = None
                    self._z[i] = 0.0
                else:
                    self._z[i] = height * (1.0 - (0.0 if s < 0.0 else s))  # max(s, 0.0), without the call
            elif self._late[i] and t >= self._late_from[i]:
                options = self.options
                if options.late_descent_acceleration > 0.0:
                    # From where the target stood when it became late, at rest, down to the limit along a profile
                    # continuous in position and velocity (rtgait.control.late_descent).
                    descent = self._descent[i]
                    if descent is None:
                        descent = self._descent[i] = (self._z[i], t - self.dt)
                    z0, since = descent
                    room = z0 + options.late_descent_limit
                    speed, acceleration = options.late_descent_speed, options.late_descent_acceleration
                    self._z[i] = z0 - descent_depth(t - since, speed, room, acceleration)
                else:  # at full speed from the first tick
                    limit = options.late_descent_limit
                    z = self._z[i] - options.late_descent_speed * self.dt
                    self._z[i] = -limit if -limit > z else z  # max(z, -limit), without the call
            elif (ground := self._ground[i]) is not None:  # landed late: back to the ground's height
                landed, level, start, until = ground
                s = (t - start) / (until - start)
                if s >= 1.0:
                    self._z[i], self._ground[i] = level, None
                else:
                    self._z[i] = landed + (level - landed) * (0.0 if s < 0.0 else s)  # max(s, 0.0)

    def _foot_target(self, i: int, planned: Pose) -> Pose:
        """Foot ``i``'s target ``(x, y, z, yaw)`` before foot force control."""
        hold = self._hold[i]
        if hold is not None:  # early touch-down: where it landed, down with the plan to a floor
            z = planned[2] + self._z[i]
            return (hold[0], hold[1], hold[3] if hold[3] > z else z, hold[2])  # max(z, floor), without the call
        skim = self._skim[i]
        if skim is not None:  # ground met short of the foothold: on with the plan, no lower than it touched
            z = planned[2] + self._z[i]
            # Clear of the ground it met while short of the foothold (a sole dragged on it would be loaded there).
            away = math.hypot(planned[0] - skim[2], planned[1] - skim[3]) / SHORT_LANDING
            floor = skim[0] + SKIM_CLEARANCE * (away if away < 1.0 else 1.0)
            return (planned[0], planned[1], floor if floor > z else z, planned[3])
        return (planned[0], planned[1], planned[2] + self._z[i], planned[3])

    def targets(self, values: SampleValues) -> tuple[Pose, Pose]:
        """Both feet's targets ``(x, y, z, yaw)`` before foot force control, for the sample ``values``."""
        return self._foot_target(0, values.left_foot), self._foot_target(1, values.right_foot)

    def _start_blends(
        self,
        t: float,
        before: tuple[Pose, Pose],
        after: tuple[Pose, Pose],
        goals: Sequence[tuple[float, float, float] | None],
    ) -> None:
        """Blend the IK's targets of the feet re-anchored or held at ``t`` (s) over ``anchor_blend`` to the poses
        ``goals`` (x, y, yaw; ``None``: not this foot) they are to stand at (:mod:`rtgait.control.target_blend`), from
        where the IK had them: ``before`` and ``after`` are the tick's targets without and with the change."""
        duration = self.options.anchor_blend
        if duration <= 0.0:
            return
        last, rate = self._last_ik, 1.0 / self.dt
        for i in (0, 1):
            goal = goals[i]
            if goal is None:
                continue
            old = self._blends[i].apply(t, before[i])  # a blend under way goes on from where it has the target
            previous = old if last is None else last[i]
            vx, vy = (old[0] - previous[0]) * rate, (old[1] - previous[1]) * rate
            vyaw = math.remainder(old[3] - previous[3], math.tau) * rate
            self._blends[i].start(t, old, (vx, vy, vyaw), goal, old[2] - after[i][2], duration)
