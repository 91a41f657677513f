"""What a caller of the MuJoCo closed loop reads and does between ticks (:class:`~rtgait.sim.loop.ClosedLoop` takes
these methods from :class:`LoopReadout`, a mixin; the state is the loop's): the last tick's values (s, m), the base's
position (m), the touch-downs so far, the plan's footprints, a push (N, s) given live, and the
:class:`~rtgait.sim.result.SimResult` of the ticks recorded.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import TYPE_CHECKING

from rtgait.core.geometry.support import SUPPORT_NAMES
from rtgait.sim.loop_record import TickValues
from rtgait.sim.loop_result import loop_result

if TYPE_CHECKING:
    from rtgait.core.geometry.footsteps import Footstep
    from rtgait.core.push import Push
    from rtgait.sim.result import SimResult

__all__ = ["LoopReadout"]


class LoopReadout:
    """The read-out methods of :class:`~rtgait.sim.loop.ClosedLoop` (see the module docstring)."""

    # ----- pushes --------------------------------------------------------------------------------------------------
    def push(self, force: Sequence[float], duration: float = 0.1, body: str | None = None) -> Push:
        """Push ``body`` (default the floating base) with ``force`` (N, world frame) for ``duration`` (s) from the
        next tick on (:class:`~rtgait.sim.loop_push.LivePush`: one at a time, rewritten every tick so that a viewer
        clearing the applied forces does not cut it short); it is added to :attr:`pushes`.

        Raises:
            ValueError: a force or duration that is not finite, beyond physical sense (:meth:`Push.check`), or an
                unknown body.
        """
        push = self._live.start(self.time_of(self.k), force, duration, body)
        self.pushes.append(push)
        return push

    @property
    def push_acting(self) -> tuple[float, float, float] | None:
        """The force (N) of the :meth:`push` acting at the last tick, or ``None``."""
        return self._live.force

    # ----- the last tick's values ----------------------------------------------------------------------------------
    @property
    def last(self) -> TickValues:
        """The last tick's values (those of the first tick's start before any step)."""
        row = (max(self.k, 1) - 1) % self.record.capacity
        p = self.record.planned[row].tolist()
        return TickValues(
            self.t, self.phase, SUPPORT_NAMES[int(self.record.support[row])], (p[0], p[1]), (p[2], p[3]),
            self.zmp_measured, (p[4], p[5]), (p[6], p[7]), tuple(self.cog_target), self.left_foot, self.right_foot,
        )  # fmt: skip

    @property
    def base_position(self) -> tuple[float, float, float]:
        """The floating base's position now (m): after the last tick's physics."""
        x, y, z = self.data.qpos[0:3].tolist()
        return x, y, z

    @property
    def steps_completed(self) -> int:
        """Touch-downs completed so far (:class:`~rtgait.sim.contact.Landings`)."""
        return self.landings.count

    def footprints(self) -> list[Footstep]:
        """The planner's footprints as planned now (the two standing feet before the walk starts)."""
        if self.planner.started:
            return self.planner.footprints()
        return self.planner.footprints(1)[:2]

    # ----- the result ----------------------------------------------------------------------------------------------
    def result(self, wall_time: float | None = None) -> SimResult:
        """The :class:`SimResult` of the ticks recorded (all, or the ring's last ones; at least one tick run).

        ``wall_time`` (s): the loop's wall-clock time to report; default the time from the first tick to the last
        (to now while the run goes on). An open-ended walk's :attr:`SimResult.walk_end` is its last tick's time.
        """
        if self.k == 0:
            raise RuntimeError("no tick has run yet")
        if wall_time is None:
            assert self._began is not None
            wall_time = (self._ended if self._ended is not None else time.perf_counter()) - self._began
        return loop_result(self, wall_time, self._n_steps, self._walk_end)
