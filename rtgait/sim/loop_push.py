"""A push given while the MuJoCo closed loop runs (:meth:`rtgait.sim.loop.ClosedLoop.push`): a hand on the robot
from a live session, as opposed to the pushes scheduled before the run (:class:`rtgait.sim.contact.Pushes`).

One acts at a time (a new one replaces it). Its force is written into ``data.xfrc_applied`` at every tick it lasts,
not once: MuJoCo's passive viewer clears the applied forces at each ``sync`` (it puts the mouse perturbation there),
which would cut a push written once short at the next frame. While it acts it replaces a scheduled push on the same
body.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import mujoco

from rtgait.core.push import Push

if TYPE_CHECKING:
    from rtgait.sim.model import SimModel

__all__ = ["LivePush"]

_TIME_TOLERANCE = 1e-9  # s: a window edge within a nanosecond of a tick counts as on it (as Pushes does)


class LivePush:
    """The live push of a run on ``sim`` stepping ``data``; ``cog_height`` (m) and ``gravity`` (m/s^2) size the
    largest push accepted (:meth:`Push.check`)."""

    def __init__(self, sim: SimModel, data: mujoco.MjData, cog_height: float, gravity: float) -> None:
        self._sim, self._xfrc = sim, data.xfrc_applied
        self._cog_height, self._gravity = cog_height, gravity
        self._acting: tuple[float, tuple[float, float, float], int] | None = None  # (end time, force, body id)

    def start(self, start: float, force: Sequence[float], duration: float, body: str | None = None) -> Push:
        """Push ``body`` (default the floating base) with ``force`` (N, world frame) for ``duration`` (s) from
        ``start`` (s, walk clock: the next tick's time).

        Raises:
            ValueError: a force or duration that is not finite, beyond physical sense, or an unknown body.
        """
        fx, fy, fz = (float(v) for v in force)
        push = Push(start=start, duration=duration, force=(fx, fy, fz), body=body)
        push.check(self._sim.robot.mass, self._cog_height, self._gravity)
        index = self._sim.base_body
        if body is not None:
            index = mujoco.mj_name2id(self._sim.model, mujoco.mjtObj.mjOBJ_BODY, body)
            if index < 0:
                raise ValueError(f"push body {body!r}: the MuJoCo model of {self._sim.robot.name} has no such body")
        self.clear()
        self._acting = (start + duration, push.force, int(index))
        return push

    @property
    def force(self) -> tuple[float, float, float] | None:
        """The force acting (N), or ``None``."""
        return None if self._acting is None else self._acting[1]

    def update(self, t: float) -> None:
        """The tick at ``t`` (s): write the force, or end the push when its time is over."""
        if self._acting is None:
            return
        end, force, body = self._acting
        if t + _TIME_TOLERANCE >= end:
            self.clear()
        else:
            self._xfrc[body, 0:3] = force

    def clear(self) -> None:
        """End the push acting now, if any."""
        if self._acting is not None:
            self._xfrc[self._acting[2], 0:3] = 0.0
            self._acting = None
