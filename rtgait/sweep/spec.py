"""What a sweep is: a base scenario, the axes varied over it, and the cases they make (``docs/sweeps.md``).

A sweep file is TOML::

    base = "fig4"                      # a built-in scenario, a scenario file or a footstep plan (relative to
                                       # this file; a footstep plan's axes: timing.* and connection)

    [axes]                             # the cases are every combination, in this order
    "change.length" = { start = -0.1, stop = 0.45, num = 56 }    # m, the first change's new length
    "timing.double_support" = { start = 0.05, stop = 1.5, num = 30 }
    "timing.single_support" = [0.8]
    connection = ["real-time", "quasi-real-time", "auto", "preview"]

An axis is a list of values or a range ``{start, stop, num}`` (``num`` evenly spaced values, both ends included)
or ``{start, stop, step}``. Every problem raises :class:`SweepError` (a ``ValueError``) with one line naming it,
before anything is run or written.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from rtgait.core.geometry.heightfield import Heightfield
from rtgait.core.limits import MAX_STRIDE
from rtgait.core.planner.config import ALL_CONNECTION_MODES
from rtgait.scenario.heightfield_file import resolve_terrain_file
from rtgait.scenario.loading import parse_document
from rtgait.scenario.scenario import Scenario, ScenarioError
from rtgait.scenario.tomlfile import TomlFiles, is_finite_number

MAX_CASES = 200_000
"""Most cases one sweep may have: each keeps one row in memory and, at the pendulum level, about 10 us of work."""
MAX_PHYSICS_CASES = 5_000
"""Most cases one sweep may walk in physics (``--physics``): each takes seconds of a core."""
METHODS = (*ALL_CONNECTION_MODES, "preview")
"""Values of the ``connection`` axis: the planner's connection modes, and ``"preview"``, the ZMP preview control
baseline (:mod:`rtgait.core.analysis.preview`)."""

AXES: dict[str, str] = {
    "change.length": "m",
    "change.width": "m",
    "change.step": "",
    "walk.step_length": "m",
    "timing.double_support": "s",
    "timing.single_support": "s",
    "connection": "",
}
"""The axes a sweep may vary, with their units. ``change.*`` set the base scenario's first ``[[walk.change]]``."""


class SweepError(ValueError):
    """A sweep file is unreadable or invalid, or a sweep cannot start. The message is one line."""


_FILES = TomlFiles(kind="sweep", folder="scenarios", error=SweepError)
# as rtgait.scenario.scenario finds them
_SCENARIOS = TomlFiles(kind="scenario", folder="scenarios", error=ScenarioError)


@dataclass(frozen=True)
class SweepSpec:
    """A parsed sweep: the base scenario (and its TOML document, which workers rebuild it from), the axes in
    order with their values, and where the file came from."""

    base: Scenario
    base_document: dict[str, Any]
    axes: tuple[tuple[str, tuple[Any, ...]], ...]
    source: str = ""

    @property
    def n_cases(self) -> int:
        return math.prod(len(values) for _, values in self.axes)

    @property
    def axis_names(self) -> tuple[str, ...]:
        return tuple(name for name, _ in self.axes)

    def cases(self) -> list[dict[str, Any]]:
        """Every combination of the axes' values, in order (the first axis varies slowest)."""
        names = self.axis_names
        return [dict(zip(names, values, strict=True)) for values in itertools.product(*(v for _, v in self.axes))]

    def fingerprint(self) -> str:
        """A hash of the base scenario's document (and of a height field's grid, which the document names by its
        file only): cases of different bases never share an identity."""
        text = json.dumps(self.base_document, sort_keys=True)
        terrain = None if self.base.terrain is None else self.base.terrain.terrain
        if isinstance(terrain, Heightfield):
            text += terrain.digest
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def case_id(fingerprint: str, values: dict[str, Any]) -> str:
    """A case's identity (16 hex digits): the same base and axis values give the same id, in any sweep."""
    text = json.dumps({"base": fingerprint, **{k: values[k] for k in sorted(values)}}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def load_spec(path: str | Path) -> SweepSpec:
    """Read and check a sweep file (module docstring)."""
    document = _FILES.load(Path(path))
    return parse_spec(document.data, document.folder, str(path))


def parse_spec(data: dict[str, Any], folder: Path | None = None, source: str = "") -> SweepSpec:
    """Check a parsed sweep document; ``folder`` resolves a relative ``base`` path."""
    _FILES.check_keys(data, "", ("base", "axes"), ())
    base_name = _FILES.string(data, "base", non_empty=True)
    target: str | Path = base_name
    if base_name.endswith(".toml") or "/" in base_name:
        target = Path(base_name) if folder is None or Path(base_name).is_absolute() else folder / base_name
    try:
        document = _SCENARIOS.load(target)
        # A height field's file made absolute: the document alone rebuilds the base (workers, other folders).
        base_document = resolve_terrain_file(document.data, document.folder)
        base = parse_document(base_document, document.source)
    except ScenarioError as error:
        raise SweepError(f"base: {error}") from None
    table = _FILES.table(data["axes"], "axes")
    if not table:
        raise SweepError("axes must name at least one axis")
    axes = []
    for name, raw in table.items():
        if name not in AXES:
            raise SweepError(f"axes.{name} is not an axis one can sweep; the axes are {', '.join(AXES)}")
        if base.footholds is not None:
            _check_footstep_axis(name, base)
        axes.append((name, _values(name, raw)))
    spec = SweepSpec(base, base_document, tuple(axes), source)
    if any(name.startswith("change.") for name in spec.axis_names) and not base.changes:
        raise SweepError("axes change.* set the base scenario's first [[walk.change]], and it has none")
    if spec.n_cases > MAX_CASES:
        raise SweepError(f"the sweep has {spec.n_cases} cases, more than the {MAX_CASES} one sweep may have")
    # Every value alone (its own range), then the corners of the numeric axes (a walk's length, the period
    # against the shortest phase): together they bound every combination.
    for name, values in spec.axes:
        for value in values:
            case_scenario(spec.base, {name: value})
    for pick in (min, max):
        case_scenario(spec.base, {name: pick(v) if name != "connection" else v[0] for name, v in spec.axes})
    return spec


FOOTSTEP_PLAN_AXES = ("timing.double_support", "timing.single_support", "connection")
"""The axes of a sweep whose base is a footstep plan: its footholds are given one by one, so it has no step length
and no ``[[walk.change]]`` to vary."""


def _check_footstep_axis(name: str, base: Scenario) -> None:
    """Refuse an axis that has no meaning for the footstep plan ``base``, in one line."""
    where = f"axes.{name}: the base {base.name} is a footstep plan"
    if name not in FOOTSTEP_PLAN_AXES:
        what = "step length" if name == "walk.step_length" else "[[walk.change]]"
        raise SweepError(
            f"{where}, whose footholds are given one by one: it has no {what} to vary (a footstep plan's axes: "
            f"{', '.join(FOOTSTEP_PLAN_AXES)})"
        )
    if name.startswith("timing.") and not base.timing.uniform:
        raise SweepError(f"{where} whose steps have their own timing: {name} would not reach them")


def _values(name: str, raw: Any) -> tuple[Any, ...]:
    where = f"axes.{name}"
    if isinstance(raw, dict):
        _FILES.check_keys(raw, where, ("start", "stop"), ("num", "step"))
        if ("num" in raw) == ("step" in raw):
            raise SweepError(f"{where} needs exactly one of num and step")
        start, stop = (_FILES.number(raw[k], f"{where}.{k}", unit=AXES[name]) for k in ("start", "stop"))
        if "num" in raw:
            num = _FILES.count(raw["num"], f"{where}.num", high=MAX_CASES)
            values = [start] if num == 1 else [start + (stop - start) * i / (num - 1) for i in range(num)]
        else:
            step = _FILES.number(raw["step"], f"{where}.step", rule="> 0", unit=AXES[name])
            count = math.floor((stop - start) / step + 1e-9) + 1
            if count < 1:
                raise SweepError(f"{where} is empty: start {start:g} is beyond stop {stop:g}")
            if count > MAX_CASES:
                raise SweepError(f"{where} has {count} values, more than {MAX_CASES}")
            values = [start + i * step for i in range(count)]
        values = [round(v, 12) for v in values]  # 0.1 + 2 * 0.05 is 0.2, not 0.20000000000000004
    elif isinstance(raw, list):
        values = list(raw)
    else:
        raise SweepError(f"{where} must be a list of values or a table {{start, stop, num}}")
    if not values:
        raise SweepError(f"{where} is empty: give at least one value")
    for value in values:
        _check_value(name, value)
    if len(set(map(repr, values))) != len(values):
        raise SweepError(f"{where} repeats a value: {values}")
    return tuple(values)


def _check_value(name: str, value: Any) -> None:
    where = f"axes.{name}"
    if name == "connection":
        if value not in METHODS:
            raise SweepError(f"{where} values must be among {', '.join(METHODS)}, got {value!r}")
    elif name == "change.step":
        if not isinstance(value, int) or isinstance(value, bool) or value < 1:
            raise SweepError(f"{where} values must be step numbers >= 1, got {value!r}")
    elif not is_finite_number(value):
        raise SweepError(f"{where} values must be finite numbers ({AXES[name]}), got {value!r}")
    elif name in ("change.length", "walk.step_length") and abs(value) > MAX_STRIDE:
        raise SweepError(f"{where} values must be within [-{MAX_STRIDE:g}, {MAX_STRIDE:g}] m, got {value!r}")
    elif name == "change.width" and not 0.0 < value <= MAX_STRIDE:
        raise SweepError(f"{where} values must be within (0, {MAX_STRIDE:g}] m, got {value!r}")


def case_scenario(base: Scenario, values: dict[str, Any]) -> Scenario:
    """``base`` with one case's axis values; a value the scenario refuses raises :class:`SweepError`."""
    timing, changes, fields = base.timing, list(base.changes), {}
    for name, value in values.items():
        if name == "connection":
            fields["connection"] = "real-time" if value == "preview" else value  # preview: changes as real-time
        elif name == "walk.step_length":
            fields["step_length"] = float(value)
        elif name.startswith("timing."):
            try:
                timing = replace(timing, **{name.split(".", 1)[1]: float(value)})
            except ValueError as error:
                raise SweepError(f"case {name} = {value}: {error}") from None
        else:
            key = {"change.length": "length", "change.width": "width", "change.step": "step"}[name]
            changes[0] = replace(changes[0], **{key: value if key == "step" else float(value)})
    if changes and "change.step" in values:
        first = base.changes[0]
        # A one-step change (`only = true`) moves with its step; a lasting one still lasts to the walk's end.
        through = changes[0].step if first.through in (None, first.step) else first.through
        changes[0] = replace(changes[0], through=max(through, changes[0].step))
    try:
        return replace(base, timing=timing, changes=tuple(changes), **fields)
    except ValueError as error:
        shown = ", ".join(f"{k} = {v}" for k, v in values.items())
        raise SweepError(f"case {shown}: {' '.join(str(error).split())}") from None


def scenario_from_document(document: dict[str, Any]) -> Scenario:
    """The base scenario (or footstep plan) from its TOML document (how workers on other machines rebuild it)."""
    return parse_document(document, "sweep")


__all__ = [
    "AXES",
    "FOOTSTEP_PLAN_AXES",
    "MAX_CASES",
    "MAX_PHYSICS_CASES",
    "METHODS",
    "SweepError",
    "SweepSpec",
    "case_id",
    "case_scenario",
    "load_spec",
    "parse_spec",
    "scenario_from_document",
]
