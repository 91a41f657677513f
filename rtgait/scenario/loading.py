"""Scenarios by name or path: the built-in ones, and any scenario or footstep-plan TOML file."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from rtgait.scenario.footholds import parse_footstep_plan
from rtgait.scenario.heightfield_file import resolve_terrain_file
from rtgait.scenario.scenario import SCENARIO_FILES, Scenario
from rtgait.scenario.scenario_file import parse_scenario

__all__ = ["builtin_scenarios", "load_scenario", "parse_document"]


def builtin_scenarios() -> dict[str, str]:
    """Built-in scenario names mapped to their one-line descriptions."""
    return {name: load_scenario(name).description for name in SCENARIO_FILES.builtin_names()}


def load_scenario(name_or_path: str | Path) -> Scenario:
    """Load a built-in scenario by name, or any scenario TOML file by path; a file with ``[[footstep]]``
    entries is a footstep plan (:mod:`rtgait.scenario.footholds`). A height field's file is read relative to the
    scenario file.

    A string that is a built-in name wins over a file of the same name in the current folder; anything that
    looks like a path (a ``.toml`` suffix, a folder separator, or an existing file) is read as a file.
    """
    document = SCENARIO_FILES.load(name_or_path)
    return parse_document(resolve_terrain_file(document.data, document.folder), document.source)


def parse_document(data: dict[str, Any], source: str = "") -> Scenario:
    """The :class:`Scenario` of a parsed scenario or footstep-plan TOML document ``data`` (a footstep plan has
    ``[[footstep]]`` entries)."""
    if "footstep" in data:
        return parse_footstep_plan(data, source)
    return parse_scenario(data, source)
