"""What a run walked, in words, for its titles: the scenario, or the velocity commands of a walk by command.

A walk by velocity command (``rtgait simulate --velocity``) takes its timing and number of steps from the scenario
named, not its footsteps: its figures, replay and printed summary say so, with the commands
(:func:`walk_title`). The commands are kept in the run's summary as ``velocity``, a list of ``{t, vx, vy, wz}`` (s,
m/s, m/s, rad/s; :func:`velocity_facts`), so a figure drawn again from the files says the same.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

__all__ = ["velocity_commands", "velocity_facts", "velocity_text", "walk_title"]

Command = tuple[float, float, float, float]
"""A velocity command from a time on: ``(t, vx, vy, wz)`` (s, m/s, m/s, rad/s; ``vy`` positive to the left, ``wz``
positive turning left)."""

_FIELDS = ("t", "vx", "vy", "wz")


def velocity_facts(commands: Sequence[Command]) -> list[dict[str, float]]:
    """``commands`` as the summary's ``velocity`` entry."""
    return [dict(zip(_FIELDS, map(float, command), strict=True)) for command in commands]


def velocity_commands(facts: Mapping[str, Any]) -> list[Command]:
    """The velocity commands of a run's summary (or a log's metadata); none for a walk of footsteps."""
    return [(entry["t"], entry["vx"], entry["vy"], entry["wz"]) for entry in facts.get("velocity") or []]


def _command_text(vx: float, vy: float, wz: float) -> str:
    """One command in words: ``0.2 m/s forward, turning left 0.1 rad/s``; ``on the spot`` when it turns without
    moving, ``standing`` when it does neither."""
    moves = [f"{abs(vx):g} m/s {'forward' if vx > 0 else 'backward'}"] if vx else []
    moves += [f"{abs(vy):g} m/s to the {'left' if vy > 0 else 'right'}"] if vy else []
    turn = [f"turning {'left' if wz > 0 else 'right'} {abs(wz):g} rad/s"] if wz else []
    if not moves:
        return f"{turn[0]} on the spot" if turn else "standing"
    return ", ".join(moves + turn)


def velocity_text(commands: Sequence[Command]) -> str:
    """A walk's velocity commands, in time order, in words: ``0.2 m/s forward, from 5 s turning left 0.2 rad/s on
    the spot``."""
    return ", ".join(
        (f"from {t:g} s " if i else "") + _command_text(vx, vy, wz) for i, (t, vx, vy, wz) in enumerate(commands)
    )


def walk_title(scenario: str, connection: str, commands: Sequence[Command] = ()) -> str:
    """The title of a run: the scenario and its connection mode, ``fig8 (quasi-real-time)``, or for a walk by
    velocity ``commands`` what it was asked, ``velocity walk 0.2 m/s forward (fig8's timing, quasi-real-time)``."""
    if not commands:
        return f"{scenario} ({connection})"
    return f"velocity walk {velocity_text(commands)} ({scenario}'s timing, {connection})"
