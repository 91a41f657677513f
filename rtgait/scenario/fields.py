"""The fields of a scenario file's tables: checked numbers and choices, ``[[walk.change]]`` and ``[guide]``.

Split from :mod:`rtgait.scenario.scenario` (which builds the :class:`~rtgait.scenario.scenario.Scenario` from them);
every message is one line naming the TOML field.
"""

from __future__ import annotations

from typing import Any

from rtgait.core.analysis.rollout import ScheduledChange
from rtgait.core.limits import MAX_STRIDE
from rtgait.scenario.checks import ScenarioError, within
from rtgait.scenario.guide_path import GuidePath
from rtgait.scenario.tomlfile import NumberRule, TomlFiles

__all__ = ["LENGTH_BOUNDS", "WIDTH_BOUNDS", "YAW_RULE", "choice", "number", "parse_changes", "parse_guide"]

_FILES = TomlFiles(kind="scenario", folder="scenarios", error=ScenarioError)
YAW_RULE: NumberRule = "|x| < pi/2"
"""Stride.turn must stay strictly inside +-pi/2; checking yaws with this rule gives the error a TOML field name."""
LENGTH_BOUNDS = (-MAX_STRIDE, MAX_STRIDE)
WIDTH_BOUNDS = (0.0, MAX_STRIDE)


def number(
    data: dict[str, Any],
    key: str,
    where: str,
    *,
    rule: NumberRule = "any",
    unit: str = "",
    bounds: tuple[float, float] | None = None,
) -> float:
    """A finite number from ``data[key]`` of the table ``where`` (empty: the document) satisfying ``rule`` and
    lying within ``bounds`` (inclusive)."""
    path = f"{where}.{key}" if where else key
    # Scenario messages word the unit of an unconstrained number "(in m)"; tests and users rely on that wording.
    shown_unit = f"(in {unit})" if rule == "any" and unit else unit
    value = _FILES.number(data[key], path, rule=rule, unit=shown_unit)
    if bounds is not None:
        within(path, value, bounds, unit)
    return value


def choice(data: dict[str, Any], key: str, where: str, choices: tuple[str, ...]) -> str:
    value = data[key]
    path = f"{where}.{key}" if where else key
    if value not in choices:
        raise ScenarioError(f"{path} must be one of {', '.join(repr(c) for c in choices)}, got {value!r}")
    return value


def parse_changes(raw: Any, steps: int) -> tuple[ScheduledChange, ...]:
    if not isinstance(raw, list):
        raise ScenarioError("walk.change must be an array of tables, written [[walk.change]]")
    changes = []
    for index, entry in enumerate(raw):
        where = f"walk.change[{index}]"
        entry = _FILES.table(entry, where)
        _FILES.check_keys(entry, where, ("step",), ("length", "width", "yaw", "only"))
        step = _FILES.count(entry["step"], f"{where}.step")
        if step > steps:
            raise ScenarioError(f"{where}.step must be a step of the walk (1..{steps}), got {step}")
        length = number(entry, "length", where, unit="m", bounds=LENGTH_BOUNDS) if "length" in entry else None
        width = number(entry, "width", where, rule="> 0", unit="m", bounds=WIDTH_BOUNDS) if "width" in entry else None
        yaw = number(entry, "yaw", where, rule=YAW_RULE, unit="rad") if "yaw" in entry else None
        if length is None and width is None and yaw is None:
            raise ScenarioError(f"{where} changes nothing: give at least one of length, width, yaw")
        only = entry.get("only", False)
        if not isinstance(only, bool):
            raise ScenarioError(f"{where}.only must be true or false, got {only!r}")
        # By default a change persists (the user now wants longer/wider/turning steps); the closing step
        # steps + 1 is never touched so the walk still ends with the feet side by side.
        through = None if only else steps
        changes.append(ScheduledChange(step, length=length, width=width, turn=yaw, through=through))
    return tuple(changes)  # Scenario refuses two changes of one step, naming both entries


def parse_guide(raw: Any) -> GuidePath:
    table = _FILES.table(raw, "guide")
    keys = ("forward", "turn", "radius", "after", "speed")
    _FILES.check_keys(table, "guide", (), keys)
    units = {"forward": "m", "turn": "rad", "radius": "m", "after": "m", "speed": "m/s"}
    values = {key: number(table, key, "guide", unit=units[key]) for key in keys if key in table}
    try:
        return GuidePath(**values)
    except ValueError as error:
        raise ScenarioError(str(error)) from None
