"""A scenario's ``[terrain]`` table: the ground the walk's footsteps are placed on.

::

    [terrain]
    type = "stairs"          # "flat" | "stairs" | "slope" | "stones" | "step" | "heightfield"
    place_footsteps = true   # optional (default true): give the footholds the terrain's height, pitch and roll;
                             # false: the walk keeps its own (a plan that does not know the terrain)
    # stairs: riser (m), tread (m), count, direction ("up" | "down", default "up"), start (m, default 0.5)
    # slope:  angle (rad, positive up), length (m, horizontal), start (m, default 0.5)
    # stones: length, width (m: each stone), gap (m, along x), count (stones per row), start (m, default 0.3);
    #         one row under each foot, the walk's step_width apart
    # step:   height (m, negative: down), x (m)
    # heightfield: file (.npy or .csv of heights in m, relative to the scenario file), size = [x, y] (m),
    #         origin = [x, y] (m, default [0, -size_y / 2]): anything else (:mod:`rtgait.scenario.heightfield_file`)

Every terrain runs along x from the standing feet at the origin (:mod:`rtgait.core.geometry.terrain`). Placing the
walk checks each step (:mod:`rtgait.core.geometry.terrain_walk`): a sole across an edge, a foothold off the surface,
a step longer or higher than the robot's reach, on a height field a sole across a discontinuity or on ground too
rough for it (the least-squares plane under it missing the terrain by more than
:data:`~rtgait.core.geometry.terrain.EDGE_TOLERANCE`), and a swing that cuts into the terrain or passes closer than
:data:`~rtgait.core.geometry.swing_terrain.MIN_SWING_CLEARANCE` mid-swing
(:mod:`rtgait.core.geometry.swing_terrain`) are refused with one line naming the step.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from rtgait.core.geometry.footsteps import Footstep, SoleRect
from rtgait.core.geometry.swing_terrain import check_swing
from rtgait.core.geometry.terrain import Flat, Slope, Stairs, Step, SteppingStones, TerrainKind
from rtgait.core.geometry.terrain_walk import DEFAULT_MAX_RISE, place_walk
from rtgait.scenario.checks import ScenarioError
from rtgait.scenario.heightfield_file import parse_heightfield
from rtgait.scenario.tomlfile import TomlFiles

__all__ = ["TERRAIN_TYPES", "TerrainSpec", "parse_terrain"]

_FILES = TomlFiles(kind="scenario", folder="scenarios", error=ScenarioError)
# Per type: required keys, optional keys.
_KEYS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "flat": ((), ()),
    "stairs": (("riser", "tread", "count"), ("direction", "start")),
    "slope": (("angle", "length"), ("start",)),
    "stones": (("length", "width", "gap", "count"), ("start",)),
    "step": (("height", "x"), ()),
    "heightfield": (("file", "size"), ("origin",)),
}
TERRAIN_TYPES = tuple(_KEYS)
"""The ``[terrain]`` table's ``type`` values."""


@dataclass(frozen=True)
class TerrainSpec:
    """The terrain of a scenario and whether the walk's footholds are placed on it.

    Attributes:
        terrain: the height field (:mod:`rtgait.core.geometry.terrain`).
        place_footsteps: give the footholds the terrain's height, pitch and roll (``False``: the plan keeps its own;
            the terrain is then the truth the plan does not know).
        max_step_rise: the largest height change of one step (m), the robot's reach.
    """

    terrain: TerrainKind
    place_footsteps: bool = True
    max_step_rise: float = DEFAULT_MAX_RISE

    def place(
        self, prints: Sequence[Footstep], sole: SoleRect, max_length: float, step_height: float
    ) -> list[Footstep]:
        """``prints`` on the terrain when :attr:`place_footsteps`, each step and its swing (``step_height`` m above
        the higher foothold) checked; else as they are."""
        if not self.place_footsteps:
            return list(prints)
        try:
            placed = place_walk(self.terrain, prints, sole, max_length, self.max_step_rise)
            for step in range(1, len(placed) - 1):
                check_swing(self.terrain, placed[step - 1], placed[step + 1], step_height, sole, step)
        except ValueError as error:
            raise ScenarioError(f"terrain: {error}") from None
        return placed


def _number(table: dict[str, Any], key: str, rule: str = "any", unit: str = "m") -> float:
    return _FILES.number(table[key], f"terrain.{key}", rule=rule, unit=unit)  # type: ignore[arg-type]


def parse_terrain(raw: Any, step_width: float) -> TerrainSpec:
    """The :class:`TerrainSpec` of a ``[terrain]`` table (module docstring); ``step_width`` (m) spaces the rows of
    stepping stones."""
    table = _FILES.table(raw, "terrain")
    kind = table.get("type")
    if kind not in _KEYS:
        raise ScenarioError(f"terrain.type must be one of {', '.join(repr(k) for k in TERRAIN_TYPES)}, got {kind!r}")
    required, optional = _KEYS[kind]
    _FILES.check_keys(table, "terrain", ("type", *required), (*optional, "place_footsteps"))
    place = table.get("place_footsteps", True)
    if not isinstance(place, bool):
        raise ScenarioError(f"terrain.place_footsteps must be true or false, got {place!r}")
    if kind == "heightfield":  # its file is read relative to the working folder unless the loader made it absolute
        return TerrainSpec(parse_heightfield(table, None), place)
    start = {"start": _number(table, "start")} if "start" in table else {}
    try:
        terrain: TerrainKind
        if kind == "flat":
            terrain = Flat()
        elif kind == "stairs":
            direction = table.get("direction", "up")
            if direction not in ("up", "down"):
                raise ScenarioError(f"terrain.direction must be 'up' or 'down', got {direction!r}")
            count = _FILES.count(table["count"], "terrain.count", high=1000)
            riser, tread = _number(table, "riser", "> 0"), _number(table, "tread", "> 0")
            terrain = Stairs(riser, tread, count, direction, **start)
        elif kind == "slope":
            terrain = Slope(_number(table, "angle", unit="rad"), _number(table, "length", "> 0"), **start)
        elif kind == "stones":
            count = _FILES.count(table["count"], "terrain.count", high=1000)
            size = _number(table, "length", "> 0"), _number(table, "width", "> 0")
            terrain = SteppingStones(*size, _number(table, "gap", ">= 0"), count, step_width, **start)
        else:
            terrain = Step(_number(table, "height"), _number(table, "x"))
    except ScenarioError:
        raise
    except ValueError as error:  # the core's range checks, worded "terrain <field> must be within ..."
        raise ScenarioError(str(error).replace("terrain ", "terrain.", 1)) from None
    return TerrainSpec(terrain, place)
