"""What ``rtgait plan``'s summary and report say of a walk off the flat floor.

``summary.json`` of a scenario with a ``[terrain]`` table has a ``terrain`` entry: the terrain's ``type`` and
``fields`` (:func:`~rtgait.core.geometry.terrain.terrain_fields`, what ``rtgait plot`` draws it from), whether
the footholds were placed on it, the COG height's range (m) and the error the vertical motion adds to the
horizontal dynamics, ``zmp_error_max`` and ``zmp_error_rms`` (m): the full point-mass ZMP equation on the planned
COG against the planned ZMP (:mod:`rtgait.core.analysis.height_error`, ``docs/method.md``). Footprints off level
ground also carry their ``z``, ``pitch`` and ``roll`` (level ones are written as before).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rtgait.core.analysis.height_error import zmp_error
from rtgait.core.analysis.rollout import Rollout
from rtgait.core.geometry.footsteps import Footstep
from rtgait.core.geometry.terrain import terrain_fields
from rtgait.scenario.scenario import Scenario

__all__ = ["footprint_entry", "terrain_line", "terrain_summary"]


def footprint_entry(foot: Footstep) -> dict[str, Any]:
    """A footprint as ``summary.json`` lists it: ``x, y, yaw, side``, and ``z, pitch, roll`` off level ground."""
    entry: dict[str, Any] = {"x": foot.x, "y": foot.y, "yaw": foot.yaw, "side": foot.side}
    if not foot.level:
        entry.update(z=foot.z, pitch=foot.pitch, roll=foot.roll)
    return entry


def terrain_summary(rollout: Rollout, scenario: Scenario) -> dict[str, Any]:
    """``{"terrain": {...}}`` for a scenario with a terrain (module docstring), ``{}`` without one."""
    spec = scenario.terrain
    if spec is None:
        return {}
    error = zmp_error(rollout, spec.terrain, scenario.gravity)
    cog_z = rollout.column("cog_z")
    return {
        "terrain": {
            "type": spec.terrain.kind,
            "fields": terrain_fields(spec.terrain),
            "place_footsteps": spec.place_footsteps,
            "cog_height_range": [float(cog_z.min()), float(cog_z.max())],
            "zmp_error_max": float(error.max()),
            "zmp_error_rms": float(np.sqrt(np.mean(error**2))),
        }
    }


def terrain_line(summary: dict[str, Any]) -> list[str]:
    """The report's line on the terrain, if the summary has one."""
    terrain = summary.get("terrain")
    if terrain is None:
        return []
    low, high = terrain["cog_height_range"]
    placed = "footholds on it" if terrain["place_footsteps"] else "the plan does not know it"
    return [
        f"terrain     {terrain['type']} ({placed}): COG z {low:.3f} .. {high:.3f} m; vertical motion's ZMP error "
        f"max {terrain['zmp_error_max'] * 1e3:.2f} mm, RMS {terrain['zmp_error_rms'] * 1e3:.2f} mm (full ZMP equation)"
    ]
