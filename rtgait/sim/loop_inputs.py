"""What reaches the planner of a closed-loop run from its options, at their times (:class:`WalkInputs`, called by
:class:`rtgait.sim.loop.ClosedLoop` every tick of the walk before the controller runs).

In this order, at tick time ``t`` (s, walk clock):

1. the ``LoopOptions.on_tick`` hook, with the MuJoCo state, then the ``LoopOptions.reactions`` whose time has come
   (each once, in time order);
2. the footstep changes (``LoopOptions.changes``) whose connection-mode deadline
   (:meth:`~rtgait.core.planner.online.OnlinePlanner.change_deadline`) has come, ``t >= deadline``, in deadline order,
   as :func:`rtgait.core.analysis.rollout.rollout` gives them;
3. the velocity commands (``LoopOptions.velocity_changes``: ``(t_i, vx, vy, wz)``, m/s and rad/s) whose time has
   come, ``t >= t_i - 1 ns``, until the walk is stopped;
4. a walk by command is stopped (:meth:`~rtgait.core.planner.online.OnlinePlanner.stop`) once its first open step is
   past ``stop_after_steps``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Callable

    import mujoco

    from rtgait.core.analysis.rollout import ScheduledChange
    from rtgait.core.planner.online import OnlinePlanner
    from rtgait.sim.loop_options import LoopOptions

__all__ = ["WalkInputs"]


class WalkInputs:
    """The walk's scheduled inputs of ``options`` for ``planner`` (module docstring).

    Args:
        planner: the run's online planner.
        options: the run's loop options (hook, footstep changes, velocity commands).
        stop_after: stop a walk by command after this many steps; ``None``: it is not stopped (a walk of footsteps
            ends by itself; one by command ends with the run).
        on_stop: called once the walk is stopped (its end is known from then on).
    """

    def __init__(
        self,
        planner: OnlinePlanner,
        options: LoopOptions,
        stop_after: int | None,
        on_stop: Callable[[], None] | None = None,
    ) -> None:
        self.planner, self.options, self._on_stop = planner, options, on_stop
        self._pending: list[ScheduledChange] = []
        self._reactions = sorted(options.reactions, key=lambda r: r[0])
        self._commands = list(options.velocity_changes)
        self._stop_after = stop_after
        self._stopped = stop_after is None

    def start(self) -> None:
        """The walk starts (its first tick, the planner just started): the footstep changes in deadline order."""
        planner = self.planner
        self._pending = sorted(self.options.changes, key=lambda c: planner.change_deadline(c.step))

    def update(self, t: float, data: mujoco.MjData) -> None:
        """What reaches the planner at ``t`` (s): the hook, the changes and commands due, ``stop()`` when due."""
        planner = self.planner
        if self.options.on_tick is not None:
            self.options.on_tick(t, data)
        reactions = self._reactions
        while reactions and t >= reactions[0][0]:
            reactions.pop(0)[1](planner, t)
        pending = self._pending
        while pending and t >= planner.change_deadline(pending[0].step):
            change = pending.pop(0)
            planner.change_step(
                change.step, length=change.length, width=change.width, turn=change.turn, through=change.through
            )
        commands = self._commands
        while commands and t >= commands[0][0] - 1e-9 and not self._stopped:
            _, vx, vy, wz = commands.pop(0)
            planner.set_velocity(vx, vy, wz)
        if not self._stopped and planner.first_open_step() > self._stop_after:  # type: ignore[operator]
            planner.stop()
            self._stopped = True
            if self._on_stop is not None:
                self._on_stop()
