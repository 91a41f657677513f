"""The ZMP error the COG's vertical motion adds to the horizontal dynamics, per built-in terrain scenario.

For each walk off the flat floor, the full point-mass ZMP equation ``p = c - (c_z - p_z) c'' / (c_z'' + g)`` is
evaluated on the planned COG (:mod:`rtgait.core.analysis.height_error`) and compared with the planned ZMP: for the
planner's 3D-DCM/VRP COG height, and for the alternative of a quintic COG height profile over each double support with
``w`` kept constant. Prints the Markdown table of ``docs/method.md`` (max and RMS over every tick, mm; the largest
vertical COG acceleration, m/s^2; the smallest ZMP margin, mm).

Usage: ``python benchmarks/height_error.py``
"""

from __future__ import annotations

import numpy as np

from rtgait.core.analysis.height_error import smooth_height_profile, zmp_error
from rtgait.core.analysis.rollout import rollout
from rtgait.core.planner.online import OnlinePlanner
from rtgait.scenario.loading import load_scenario

SCENARIOS = (
    "stairs-up", "stairs-down", "stairs-up-185", "stairs-down-185", "slope-up", "slope-down", "stepping-stones",
    "unseen-step",
)  # fmt: skip


def _rms_mm(values: np.ndarray) -> float:
    return float(np.sqrt(np.mean(values**2)) * 1e3)


def main() -> None:
    print(
        "| scenario | VRP max [mm] | RMS [mm] | max abs(c_z'') | profile max [mm] | RMS [mm] | max abs(c_z'') "
        "| margin [mm] |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for name in SCENARIOS:
        scenario = load_scenario(name)
        planner = OnlinePlanner(scenario.planner_config(), scenario.strides())
        result = rollout(planner, scenario.dt, scenario.sole, scenario.changes)
        terrain = scenario.terrain.terrain
        vrp = zmp_error(result, terrain, scenario.gravity)
        profile_z = smooth_height_profile(result, scenario.cog_height)
        profile = zmp_error(result, terrain, scenario.gravity, profile_z)
        vrp_acc = np.abs(result.column("cog_az")).max()
        profile_acc = np.abs(np.gradient(np.gradient(profile_z, result.times), result.times)).max()
        print(
            f"| `{name}` | {vrp.max() * 1e3:.2f} | {_rms_mm(vrp):.2f} | {vrp_acc:.2f} | {profile.max() * 1e3:.1f} | "
            f"{_rms_mm(profile):.1f} | {profile_acc:.2f} | {result.margin.min() * 1e3:.0f} |"
        )


if __name__ == "__main__":
    main()
