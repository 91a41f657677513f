"""A ``[terrain]`` table of ``type = "heightfield"``: a grid of heights read from a file.

::

    [terrain]
    type = "heightfield"
    file = "ramp.npy"        # relative to the scenario file (or absolute)
    size = [3.0, 1.0]        # m: the grid's extent along x and y, first to last sample
    origin = [0.0, -0.5]     # m, optional (default [0, -size_y / 2]): the world x, y of the first sample

The file holds heights in metres, one row per y sample (row 0 at ``origin`` y, rows going +y), one column per x
sample (column 0 at ``origin`` x, columns going +x), at least 2 x 2:

* ``.npy``: a 2D numpy array (``numpy.save``), read without pickles;
* ``.csv``: rows of comma-separated numbers, ``#`` starting a comment.

Between samples the ground is the grid's triangles, outside it level at 0
(:class:`~rtgait.core.geometry.heightfield.Heightfield`); the standing feet at the origin must stand on level ground at
0. Every problem raises :class:`~rtgait.scenario.checks.ScenarioError` with one line naming the field or the file.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from rtgait.core.geometry.heightfield import Heightfield
from rtgait.scenario.checks import ScenarioError
from rtgait.scenario.tomlfile import TomlFiles

__all__ = ["HEIGHTFIELD_SUFFIXES", "parse_heightfield", "read_heights", "resolve_terrain_file"]

HEIGHTFIELD_SUFFIXES = (".npy", ".csv")
"""The height field file formats, by suffix."""
_FILES = TomlFiles(kind="scenario", folder="scenarios", error=ScenarioError)


def read_heights(path: Path) -> np.ndarray:
    """The grid of heights (m) in the file ``path`` (module docstring)."""
    suffix = path.suffix.lower()
    if suffix not in HEIGHTFIELD_SUFFIXES:
        raise ScenarioError(f"terrain.file must be a {' or '.join(HEIGHTFIELD_SUFFIXES)} file of heights, got {path}")
    try:
        if suffix == ".npy":
            grid = np.load(path, allow_pickle=False)
        else:
            grid = np.loadtxt(path, delimiter=",", comments="#", ndmin=2)
    except OSError as error:
        raise ScenarioError(f"cannot read terrain.file {path}: {error.strerror or error}") from None
    except ValueError as error:
        raise ScenarioError(f"terrain.file {path} is not a grid of numbers: {' '.join(str(error).split())}") from None
    return np.asarray(grid)


def resolve_terrain_file(data: dict[str, Any], folder: Path | None) -> dict[str, Any]:
    """``data`` (a scenario document) with a relative ``terrain.file`` made absolute against ``folder`` (the scenario
    file's; ``None``: the working folder), so that the document alone rebuilds the scenario anywhere on this machine
    (a sweep's workers). Other documents are returned as they are."""
    terrain = data.get("terrain")
    if not isinstance(terrain, dict) or not isinstance(terrain.get("file"), str):
        return data
    path = Path(terrain["file"])
    if not path.is_absolute():
        path = (folder or Path.cwd()) / path
    return {**data, "terrain": {**terrain, "file": str(path.resolve())}}


def _pair(table: dict[str, Any], key: str, rule: str) -> tuple[float, float]:
    value = table[key]
    if not (isinstance(value, list) and len(value) == 2):
        raise ScenarioError(f"terrain.{key} must be two numbers [x, y] (m), got {value!r}")
    return tuple(_FILES.number(v, f"terrain.{key}[{i}]", rule=rule, unit="m") for i, v in enumerate(value))  # type: ignore[arg-type, return-value]


def parse_heightfield(table: dict[str, Any], folder: Path | None) -> Heightfield:
    """The :class:`Heightfield` of a ``[terrain]`` table of ``type = "heightfield"`` (keys already checked); a
    relative ``file`` is read from ``folder`` (the scenario file's; ``None``: the working folder)."""
    name = table["file"]
    if not isinstance(name, str) or not name:
        raise ScenarioError(f"terrain.file must be the path of a height field file, got {name!r}")
    path = Path(name)
    if not path.is_absolute():
        path = (folder or Path.cwd()) / path
    size = _pair(table, "size", "> 0")
    origin = _pair(table, "origin", "any") if "origin" in table else (0.0, -0.5 * size[1])
    grid = read_heights(path)
    try:
        return Heightfield(grid, size, origin, source=str(path))
    except ValueError as error:  # the core's checks, worded "terrain <field> must ..."
        raise ScenarioError(f"{str(error).replace('terrain ', 'terrain.', 1)} ({path.name})") from None
