"""The controller's settings from files: the ``[control]`` table of a robot description, of a scenario and of a
``rtgait simulate --control FILE`` file, applied in that order over the defaults of
:class:`~rtgait.control.settings.ControllerOptions`, so that a later file's key wins: the robot gives the defaults for
that robot, a scenario overrides them for its walk, the command line has the last word.

A table's keys are the fields of :class:`~rtgait.control.settings.ControllerOptions`: the DCM law's gains
(:class:`~rtgait.core.laws.feedback.DcmFeedbackGains`) in its ``dcm`` subtable, the foot force control's
(:class:`~rtgait.control.foot_control.FootControlGains`) in its ``foot`` subtable, and ``foot = false`` turns foot force
control off. The stride box of step adjustment is no key here: it is the robot description's ``[stepping]`` table.
Each value is checked by the settings type that holds it; a key or value it refuses is one line naming the file, the
key and what is allowed (:class:`ControlSettingsError`).

The tables arrive as ``(key, value)`` pairs, a subtable's keys dotted (``("dcm.k_p", 2.0)``), in file order, as
:meth:`rtgait.scenario.tomlfile.TomlFiles.settings` reads them.

**Per gain set.** A robot description's ``[control.gains.stiff]`` and ``[control.gains.robot]`` subtables hold
settings that apply only when its drives run at that gain set (:data:`~rtgait.interface.command.GAIN_SETS`), over the
rest of its table (:func:`at_gains`): a setting a robot needs against one kind of drive and not the other (a stiff
position servo answers a step of its reference at its torque limit, a soft one with feed-forward torques does not).
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Iterable

from rtgait.control.foot_control import FootControlGains
from rtgait.control.settings import ControllerOptions
from rtgait.core.laws.feedback import DcmFeedbackGains
from rtgait.interface.command import GAIN_SETS

__all__ = [
    "DCM_KEYS", "FOOT_KEYS", "OPTION_KEYS", "ControlSettingsError", "apply_control", "at_gains", "control_options",
    "walk_defaults",
]  # fmt: skip

OPTION_KEYS = tuple(f.name for f in dataclasses.fields(ControllerOptions) if f.name != "step_adjustment")
"""The keys of a ``[control]`` table: ``dcm`` and ``foot`` are its subtables (``foot`` may also be true or false)."""
DCM_KEYS = tuple(f.name for f in dataclasses.fields(DcmFeedbackGains))
"""The keys of ``[control.dcm]``, the DCM law's gains."""
FOOT_KEYS = tuple(f.name for f in dataclasses.fields(FootControlGains))
"""The keys of ``[control.foot]``, the foot force control's gains."""

Pairs = Iterable[tuple[str, object]]

_DEFAULT_FOOT = ControllerOptions().foot  # foot force control's gains when a table turns it on


class ControlSettingsError(ValueError):
    """A ``[control]`` key or value that the controller's settings refuse (one line naming the file and the key)."""


def at_gains(pairs: Pairs, gains: str, source: str) -> list[tuple[str, list[tuple[str, object]]]]:
    """A robot description's ``[control]`` pairs, from ``source``, as they apply at the drives' ``gains`` (one of
    :data:`~rtgait.interface.command.GAIN_SETS`): two layers for :func:`control_options`, those outside
    ``[control.gains]`` as they are, then those of ``[control.gains.<gains>]`` without the prefix, so that they win
    (their source names the subtable, for messages); the other gain sets' are left out.

    Raises:
        ControlSettingsError: a ``[control.gains]`` subtable that names no gain set, or a value directly in it.
    """
    if gains not in GAIN_SETS:
        raise ValueError(f"gains must be one of {', '.join(GAIN_SETS)}, got {gains!r}")
    common: list[tuple[str, object]] = []
    chosen: list[tuple[str, object]] = []
    for key, value in pairs:
        head, _, rest = key.partition(".")
        if head != "gains":
            common.append((key, value))
            continue
        gain_set, _, name = rest.partition(".")
        if gain_set not in GAIN_SETS or not name:
            sets = ", ".join(f"[control.gains.{each}]" for each in GAIN_SETS)
            raise ControlSettingsError(f"{source}: control.{key} is not a setting of {sets}")
        if gain_set == gains:
            chosen.append((name, value))
    return [(source, common), (f"{source} [control.gains.{gains}]", chosen)]


def walk_defaults(terrain_kind: str | None) -> ControllerOptions:
    """The settings a walk on ``terrain_kind`` (a ``[terrain]`` table's ``type``; ``None``: the flat floor) starts
    from, under every ``[control]`` table: the defaults, with sole levelling off on any terrain but the flat floor.
    The levelling (:mod:`rtgait.control.sole_level`) takes the tilt of a sole standing flat and loaded for its leg's
    calibration error, which holds only with a level floor under the whole sole: G1's toes over a stone's edge
    (a fall at 8.3 s of ``stepping-stones`` with it, 8 of 8 steps without), a ramp, a stair's toe-off are not."""
    if terrain_kind in (None, "flat"):
        return ControllerOptions()
    return ControllerOptions(sole_level=0.0)


def control_options(*layers: tuple[str, Pairs], base: ControllerOptions | None = None) -> ControllerOptions:
    """``base`` (default :class:`ControllerOptions`) with each layer's ``[control]`` pairs applied in turn, the
    lowest precedence first; a layer is ``(source, pairs)``, ``source`` naming its file in messages (``"scenario
    fig8"``).

    Raises:
        ControlSettingsError: an unknown key or a value out of its range, naming the source and the key.
    """
    options = base if base is not None else ControllerOptions()
    for source, pairs in layers:
        options = apply_control(options, pairs, source)
    return options


def apply_control(options: ControllerOptions, pairs: Pairs, source: str) -> ControllerOptions:
    """``options`` with the ``[control]`` pairs of ``source`` applied (module docstring)."""
    for key, value in pairs:
        options = _apply(options, key, value, source)
    return options


def _apply(options: ControllerOptions, key: str, value: object, source: str) -> ControllerOptions:
    group, _, name = key.rpartition(".")
    path = f"control.{key}"
    if group == "" and name in ("dcm", "foot") and not (name == "foot" and isinstance(value, bool)):
        what = "a table ([control.dcm])" if name == "dcm" else "a table ([control.foot]) or true or false"
        raise ControlSettingsError(f"{source}: {path} must be {what}, got {value!r}")
    known = {"": OPTION_KEYS, "dcm": DCM_KEYS, "foot": FOOT_KEYS}.get(group)
    if known is None or name not in known:
        where = f"control.{group}" if group in ("dcm", "foot") else "control"
        allowed = ", ".join(known or OPTION_KEYS)
        raise ControlSettingsError(f"{source}: unknown key {path} (allowed in [{where}]: {allowed})")
    try:
        if group == "dcm":
            return dataclasses.replace(options, dcm=dataclasses.replace(options.dcm, **{name: value}))
        if group == "foot":
            foot = options.foot if options.foot is not None else _DEFAULT_FOOT
            return dataclasses.replace(options, foot=dataclasses.replace(foot, **{name: value}))
        if name == "foot":  # true: foot force control on (with the gains so far), false: off
            on = options.foot if options.foot is not None else _DEFAULT_FOOT
            return dataclasses.replace(options, foot=on if value else None)
        return dataclasses.replace(options, **{name: value})
    except ValueError as error:
        raise ControlSettingsError(f"{source}: {_reworded(str(error), name, path)}") from None


def _reworded(message: str, name: str, path: str) -> str:
    """A settings type's message about field ``name`` (``"DcmFeedbackGains.k_p must be ..."``) about the TOML key
    ``path`` instead (``"control.dcm.k_p must be ..."``)."""
    named = re.match(rf"(\w+\.)?{re.escape(name)}\b", message)
    return path + message[named.end() :] if named else f"{path}: {message}"
