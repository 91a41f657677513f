"""A walk in MuJoCo driven live from the keyboard (``rtgait play``): the keys and the velocity command they set,
pushes and controller-level switches between ticks, and the pacing of the closed loop to the wall clock. No window
here: :mod:`rtgait.viz.live_view` shows it in MuJoCo's viewer and feeds it the keys.

**Keys** (:data:`KEYS`; GLFW key codes, which is what ``mujoco.viewer``'s ``key_callback`` receives). MuJoCo's viewer
binds every letter, the digits 0-5, Tab, Escape, Backspace, F1-F7, ``[ ] - = , ; ' / \\ ```` and Page Up to its own
functions (visual toggles, the UI, a reset), and calls the user's callback *as well*; so the letters (WASD) are not
used here. The keys below are free in its passive mode (its Space, arrows, ``-`` and ``=`` act only when it runs
the physics itself). Each press steps the command by an increment (:class:`Increments`), clamped to what the
planner's step limits allow (:class:`CommandLimits`); holding a key down repeats nothing.

**Pacing** (:class:`Pacer`). The loop runs the control ticks that are due by the wall clock since the walk was
shown; when it falls more than :attr:`Pacer.max_lag` behind (the machine cannot keep up), the backlog is given up,
so the simulated time runs slower than real time rather than catching up in bursts, and :attr:`Pacer.lagging` says
so. The real-time factor is the simulated time per wall-clock time over the last second.
"""

from __future__ import annotations

import math
import queue
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rtgait.core.planner.levels import CONTROLLER_LEVELS
from rtgait.core.walk.walk import VelocityCommand

if TYPE_CHECKING:
    from rtgait.core.planner.config import PlannerConfig
    from rtgait.sim.loop import ClosedLoop

__all__ = [
    "KEYS",
    "PATH_LENGTH",
    "PATH_PERIOD",
    "CommandLimits",
    "Increments",
    "Key",
    "LiveWalk",
    "Pacer",
    "command_after",
    "key_action",
]


MESSAGE_TIME = 3.0
"""How long what a key did stays on screen (s of walk time)."""
PATH_PERIOD = 0.25
"""Walk time between two points of :attr:`LiveWalk.path` (s)."""
PATH_LENGTH = 14400
"""Points of :attr:`LiveWalk.path` kept: the last hour."""


@dataclass(frozen=True)
class Key:
    """A key of ``rtgait play``: its GLFW code, its name, the action (:func:`command_after`) and what it does."""

    code: int
    name: str
    action: str
    help: str


KEYS: tuple[Key, ...] = (
    Key(265, "Up", "forward", "faster forward"),
    Key(264, "Down", "backward", "faster backward"),
    Key(263, "Left", "turn-left", "turn left (yaw rate +)"),
    Key(262, "Right", "turn-right", "turn right (yaw rate -)"),
    Key(261, "Delete", "left", "step left (sideways speed +)"),
    Key(267, "Page Down", "right", "step right (sideways speed -)"),
    Key(32, "Space", "stop", "stop (command zero; a planned walk ends)"),
    Key(257, "Enter", "push", "push the base for 0.1 s"),
    Key(260, "Insert", "level", "next controller level"),
)
"""The keys of ``rtgait play``, in the order of its help line."""

_BY_CODE = {key.code: key.action for key in KEYS}
_MOVES = {
    "forward": (1, 0, 0),
    "backward": (-1, 0, 0),
    "left": (0, 1, 0),
    "right": (0, -1, 0),
    "turn-left": (0, 0, 1),
    "turn-right": (0, 0, -1),
}


def key_action(code: int) -> str | None:
    """The action of GLFW key ``code`` (:data:`KEYS`), ``None`` for a key ``rtgait play`` does not use."""
    return _BY_CODE.get(code)


@dataclass(frozen=True)
class CommandLimits:
    """The largest velocity command the planner walks without clamping it along each axis alone: ``|vx| <= vx``,
    ``|vy| <= vy`` (m/s), ``|wz| <= wz`` (rad/s); together, the squares of the three shares add up to at most 1
    (:mod:`rtgait.core.walk.velocity_command`: the planner scales a command beyond onto that, with a warning)."""

    vx: float
    vy: float
    wz: float

    @classmethod
    def from_config(cls, config: PlannerConfig) -> CommandLimits:
        """From the planner's step limits over a step period ``T``: ``vx = max_step_length / T``; a sideways or
        turning walk opens the stance (or the turn) on every other step only, so ``vy = max_step_lateral / 2T`` and
        ``wz = max_step_turn / 2T`` (:meth:`rtgait.core.walk.walk.Walk.set_velocity`)."""
        period = config.timing.step_period
        return cls(
            config.max_step_length / period,
            config.max_step_lateral / (2.0 * period),
            config.max_step_turn / (2.0 * period),
        )


@dataclass(frozen=True)
class Increments:
    """What one key press adds to the command: forward (m/s), sideways (m/s), yaw rate (rad/s)."""

    vx: float = 0.05
    vy: float = 0.02
    wz: float = 0.05


def _stepped(value: float, sign: int, increment: float, limit: float) -> float:
    """``value + sign * increment`` on the grid of increments, clamped to ``[-limit, limit]``."""
    count = round(value / increment) + sign
    stepped = count * increment
    if abs(stepped) > limit:
        stepped = math.copysign(limit, stepped)
    return 0.0 if abs(stepped) < 1e-12 else stepped


def command_after(
    command: VelocityCommand, action: str, limits: CommandLimits, increments: Increments | None = None
) -> VelocityCommand:
    """The velocity command after ``action`` (:data:`KEYS`): a move steps one component by its increment (on the grid
    of increments, within ``limits``); ``"stop"`` zeroes it; any other action leaves it unchanged."""
    steps = increments or Increments()
    if action == "stop":
        return VelocityCommand()
    move = _MOVES.get(action)
    if move is None:
        return command
    return VelocityCommand(
        _stepped(command.vx, move[0], steps.vx, limits.vx),
        _stepped(command.vy, move[1], steps.vy, limits.vy),
        _stepped(command.wz, move[2], steps.wz, limits.wz),
    )


class Pacer:
    """How many control ticks of period ``dt`` (s) are due by the wall clock (module docstring).

    Args:
        dt: the control period (s).
        max_lag: the most simulated time (s) the loop may be behind before the backlog is given up.
        clock: the wall clock (s), ``time.perf_counter`` by default.
    """

    def __init__(self, dt: float, max_lag: float = 0.1, clock: Callable[[], float] = time.perf_counter) -> None:
        self.dt, self.max_lag, self.clock = dt, max_lag, clock
        self._origin = math.nan  # wall time at which tick 0 was due
        self.ticks = 0
        """Ticks run."""
        self.dropped = 0.0
        """Wall time given up because the loop could not keep up (s)."""
        self._window: list[tuple[float, int]] = []  # (wall time, ticks) samples of the last second
        self._last_drop = -math.inf

    def start(self) -> None:
        """Tick 0 is due now."""
        now = self.clock()
        self._origin = now
        self._window = [(now, 0)]

    def due(self) -> int:
        """Ticks to run now to be on time (0 when ahead)."""
        now = self.clock()
        behind = (now - self._origin) / self.dt - self.ticks
        if behind * self.dt > self.max_lag:  # cannot keep up: give the backlog up
            give_up = behind * self.dt - self.max_lag
            self._origin += give_up
            self.dropped += give_up
            self._last_drop = now
            behind = self.max_lag / self.dt
        return max(0, math.floor(behind))

    def ran(self, ticks: int) -> None:
        """``ticks`` more ticks have run."""
        self.ticks += ticks
        now = self.clock()
        if now - self._window[-1][0] >= 0.1:  # a sample every 0.1 s, the last second's kept
            self._window.append((now, self.ticks))
            if now - self._window[0][0] > 1.05:
                self._window.pop(0)

    def wait(self, ticks: int = 1) -> float:
        """Wall time (s) until ``ticks`` more ticks are due (0 when they are)."""
        return max(0.0, self._origin + (self.ticks + ticks - 1) * self.dt - self.clock())

    @property
    def real_time_factor(self) -> float:
        """Simulated time per wall-clock time over the last second (NaN before any)."""
        (t0, k0), (t1, k1) = self._window[0], self._window[-1]
        return (k1 - k0) * self.dt / (t1 - t0) if t1 > t0 else math.nan

    @property
    def lagging(self) -> bool:
        """Whether the loop gave time up in the last second: it runs slower than real time."""
        return self.clock() - self._last_drop < 1.0


class LiveWalk:
    """A :class:`~rtgait.sim.loop.ClosedLoop` walked live: keys from any thread, their effects between ticks, the
    outcome so far.

    Args:
        loop: the closed loop (its record a ring: ``keep``), not stepped yet.
        by_command: a walk by velocity command (the arrows set it), or a planned walk (arrows do nothing).
        push_force: size of the pushes of the push key (N).
        push_duration: their duration (s).
        increments: what a key press adds to the command.
    """

    def __init__(
        self,
        loop: ClosedLoop,
        by_command: bool,
        push_force: float,
        push_duration: float = 0.1,
        increments: Increments | None = None,
    ) -> None:
        self.loop, self.by_command = loop, by_command
        self.push_force, self.push_duration = push_force, push_duration
        self.increments = increments or Increments()
        self.limits = CommandLimits.from_config(loop.planner.config)
        self.command = VelocityCommand()
        self._keys: queue.SimpleQueue[int] = queue.SimpleQueue()
        self.log: list[tuple[float, str]] = []
        """``(walk time, action)`` of every key acted on."""
        self.levels = [loop.controller.level]
        """The controller levels walked, in order."""
        self._message = ("", -math.inf)  # what to say on screen, and when it was said (walk time, s)
        self._start: tuple[float, float, float] | None = None  # base x, y, yaw when the walk started
        self._yaw = 0.0  # the base's yaw turned since then, unwrapped (rad)
        self.path: list[tuple[float, float, float, float]] = []
        """The base's ``(walk time, x, y, yaw turned)`` from where the walk started (s, m, m, rad), every
        :data:`PATH_PERIOD`, the last :data:`PATH_LENGTH` of them."""
        self._last_yaw = 0.0
        if by_command:
            loop.planner.set_velocity(0.0, 0.0, 0.0)

    @property
    def message(self) -> str:
        """What the last key did, worth saying on screen for :data:`MESSAGE_TIME` (a push, a switch, no effect)."""
        text, said = self._message
        return text if self.loop.t - said < MESSAGE_TIME else ""

    def _say(self, text: str) -> None:
        self._message = (text, self.loop.t)

    # ----- keys ------------------------------------------------------------------------------------------------------
    def press(self, code: int) -> None:
        """A key was pressed (any thread, e.g. the viewer's): acted on at the next :meth:`handle_keys`."""
        self._keys.put(code)

    def handle_keys(self) -> None:
        """Act on the keys pressed since the last call, in order (between ticks)."""
        while True:
            try:
                code = self._keys.get_nowait()
            except queue.Empty:
                return
            action = key_action(code)
            if action is not None:
                self.act(action)

    def act(self, action: str) -> None:
        """Do ``action`` (:data:`KEYS`) now."""
        loop, t = self.loop, self.loop.t
        self.log.append((t, action))
        if action == "push":
            fx, fy = self.push_direction()
            loop.push((self.push_force * fx, self.push_force * fy, 0.0), self.push_duration)
            self._say(f"push {self.push_force:.0f} N for {self.push_duration:g} s")
        elif action == "level":
            levels = list(CONTROLLER_LEVELS)
            level = levels[(levels.index(loop.controller.level) + 1) % len(levels)]
            loop.controller.set_level(level)
            self.levels.append(level)
            self._say(f"switched to {level}")
        elif not self.by_command:
            if action == "stop":
                loop.planner.stop()
                self._say("stop: the walk ends at the next open step")
            else:
                self._say("a planned walk: only Space, Enter and Insert act")
        else:
            command = command_after(self.command, action, self.limits, self.increments)
            changed = command != self.command
            if changed:
                self.command = command
                loop.planner.set_velocity(command.vx, command.vy, command.wz)
            self._say("" if changed or action == "stop" else "at the command's limit")

    def push_direction(self) -> tuple[float, float]:
        """The push key's direction (unit, world frame): the velocity command's direction of travel in the base's
        frame, or the base's heading when the command is zero (or the walk is planned)."""
        yaw = self._base_yaw()
        vx, vy = (self.command.vx, self.command.vy) if self.by_command else (0.0, 0.0)
        angle = yaw + (math.atan2(vy, vx) if math.hypot(vx, vy) > 1e-9 else 0.0)
        return math.cos(angle), math.sin(angle)

    # ----- stepping --------------------------------------------------------------------------------------------------
    def step(self) -> bool:
        """One tick (:meth:`ClosedLoop.step`); notes where the walk started. False once the robot fell."""
        alive = self.loop.step()
        if self._start is None and self.loop.t >= 0.0:
            x, y, _ = self.loop.base_position
            self._last_yaw = self._base_yaw()
            self._start = (x, y, self._last_yaw)
        return alive

    def track(self) -> None:
        """Follow the base (call a few times a second at least: it unwraps the yaw): its heading, and its path
        every :data:`PATH_PERIOD` of walk time."""
        if self._start is None:
            return
        yaw = self._base_yaw()
        self._yaw += math.remainder(yaw - self._last_yaw, math.tau)
        self._last_yaw = yaw
        t = self.loop.t
        if not self.path or t - self.path[-1][0] >= PATH_PERIOD:
            x, y, _ = self.loop.base_position
            x0, y0, _ = self._start
            self.path.append((t, x - x0, y - y0, self._yaw))
            if len(self.path) > PATH_LENGTH:
                del self.path[: len(self.path) - PATH_LENGTH]

    def _base_yaw(self) -> float:
        w, x, y, z = self.loop.data.qpos[3:7].tolist()
        return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))

    # ----- what is shown and said ------------------------------------------------------------------------------------
    def status(self, real_time_factor: float, lagging: bool) -> str:
        """The on-screen line: command, phase, controller level, real-time factor."""
        values = self.loop.last
        if values.phase < 0:
            phase = "start transition"
        elif values.support == "double":
            phase = f"phase {values.phase}: double support"
        else:
            phase = f"phase {values.phase}: {values.support} foot stance"
        if self.by_command:
            c = self.command
            command = f"command vx {c.vx:+.2f} m/s, vy {c.vy:+.2f} m/s, wz {c.wz:+.2f} rad/s"
        else:
            command = "planned walk"
        rate = f"real-time factor {real_time_factor:.2f}" if math.isfinite(real_time_factor) else "real-time factor -"
        if lagging:
            rate += ": cannot keep up, slower than real time"
        level = f"controller {self.loop.controller.level}"
        text = f"{command} | {phase}, walk time {values.t:.1f} s | {level} | {rate}"
        safety = self.loop.stack.safety
        if self.loop.fell:
            text += f" | FELL ({self.loop.fall_cause})"
        elif safety.damping:
            text += f" | DAMPING ({safety.events[-1].kind})" if safety.events else " | DAMPING"
        elif self.loop.done:
            text += " | walk over"
        return text

    def summary(self, wall_time: float, pacer: Pacer) -> dict[str, Any]:
        """The outcome: where the base went from the walk's start (m, rad, world frame), steps, fall, timing."""
        self.track()
        loop = self.loop
        x, y, _ = loop.base_position
        x0, y0, _ = self._start if self._start is not None else (x, y, 0.0)
        return {
            "robot": loop.sim.robot.name,
            "controller": loop.controller.level,
            "levels": self.levels,
            "by_command": self.by_command,
            "walk_time": max(loop.t, 0.0),
            "simulated_time": loop.k * loop.dt,
            "wall_time": wall_time,
            "real_time_factor": loop.k * loop.dt / wall_time if wall_time > 0.0 else None,
            "time_given_up": pacer.dropped,
            "displacement": [x - x0, y - y0],
            "distance_walked": math.hypot(x - x0, y - y0),
            "yaw_turned": self._yaw,
            "steps_completed": loop.steps_completed,
            "fell": loop.fell,
            "fall_time": loop.fall_time,
            "fall_cause": loop.fall_cause,
            "command": [self.command.vx, self.command.vy, self.command.wz],
            "keys": [{"t": t, "action": action} for t, action in self.log],
            "path": [list(p) for p in self.path],
            "pushes": [p.summary() for p in loop.pushes],
        }
