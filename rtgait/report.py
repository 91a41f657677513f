"""Plain-file outputs of a rollout: the per-tick trajectory as CSV and a JSON-ready summary.

Kept apart from the command-line tool so that scripts driving the planner can write the same files.
"""

from __future__ import annotations

import statistics
from pathlib import Path
from typing import Any

import numpy as np

from rtgait.core.online import SAMPLE_FIELDS
from rtgait.core.rollout import Rollout
from rtgait.scenario import Scenario

__all__ = ["CSV_COLUMNS", "CSV_HEAD_COLUMNS", "summarize", "write_joints_csv", "write_trajectory_csv"]

CSV_HEAD_COLUMNS = (
    "t", "cog_x", "cog_y", "cog_z", "cog_vx", "cog_vy", "cog_ax", "cog_ay", "zmp_x", "zmp_y",
    "lfoot_x", "lfoot_y", "lfoot_z", "lfoot_yaw", "rfoot_x", "rfoot_y", "rfoot_z", "rfoot_yaw", "support",
)  # fmt: skip
"""The first columns of ``trajectory.csv``, a stable interface for downstream tools (SI units, yaw in rad)."""

CSV_EXTRA_COLUMNS = ("zmp_ref_x", "zmp_ref_y", "zmp_margin", "phase", "cog_vz", "cog_az")
"""Columns after :data:`CSV_HEAD_COLUMNS`: reference ZMP (m), signed ZMP margin (m, > 0 inside), phase
index, and the vertical COG velocity and acceleration (zero for the constant-height model)."""

CSV_COLUMNS = CSV_HEAD_COLUMNS + CSV_EXTRA_COLUMNS

# 10 significant digits: sub-micrometre for positions within 100 m, exact for the tick times of usual periods.
_FLOAT_FORMAT = "%.10g"


def write_joints_csv(header: tuple[str, ...], rows: np.ndarray, path: Path) -> int:
    """Write a joint table (``t``, ``base_x`` .. ``base_qw``, one column per joint) to ``path``; returns the rows."""
    with open(path, "w", encoding="utf-8", newline="") as stream:
        stream.write(",".join(header) + "\n")
        np.savetxt(stream, rows, fmt=_FLOAT_FORMAT, delimiter=",")
    return len(rows)


def write_trajectory_csv(rollout: Rollout, path: Path) -> int:
    """Write one row per control tick to ``path`` with the header :data:`CSV_COLUMNS`; returns the row count."""
    numeric: dict[str, np.ndarray] = {"t": rollout.times, "zmp_margin": rollout.margin}
    for name in SAMPLE_FIELDS:
        numeric[name] = rollout.column(name)
    columns: list[np.ndarray] = []
    for name in CSV_COLUMNS:
        if name == "support":
            columns.append(rollout.support.astype(str))
        elif name == "phase":
            columns.append(rollout.phase.astype(int).astype(str))
        else:
            # Vectorised formatting: a Python-level loop over every value would dominate long runs.
            columns.append(np.char.mod(_FLOAT_FORMAT, numeric[name]))
    table = np.stack(columns, axis=1)
    with open(path, "w", encoding="utf-8", newline="") as stream:
        stream.write(",".join(CSV_COLUMNS) + "\n")
        stream.writelines(",".join(row) + "\n" for row in table.tolist())
    return len(table)


def _changes(rollout: Rollout, scenario: Scenario) -> list[dict[str, Any]]:
    # The rollout hands changes over in deadline order, which is step order (stable for equal steps).
    ordered = sorted(scenario.changes, key=lambda change: change.step)
    decided = sorted(rollout.changes, key=lambda item: item[1])
    out = []
    for change, (when, _) in zip(ordered, decided, strict=False):
        out.append(
            {
                "step": change.step,
                "decided_at": float(when),
                "length": change.length,
                "width": change.width,
                "yaw": change.turn,
                "through": change.through if change.through is not None else change.step,
            }
        )
    return out


def summarize(rollout: Rollout, scenario: Scenario) -> dict[str, Any]:
    """Key numbers of a rollout, JSON-serialisable (SI units; planning times in microseconds)."""
    worst = rollout.worst_index
    zmp = np.stack([rollout.column("zmp_x"), rollout.column("zmp_y")], axis=1)
    deviation = zmp - np.stack([rollout.column("zmp_ref_x"), rollout.column("zmp_ref_y")], axis=1)
    free = rollout.free_segment_mask()
    max_deviation = np.abs(deviation[free]).max(axis=0) if free.any() else np.zeros(2)
    replan_us = [plan.compute_time * 1e6 for plan in rollout.connections]
    timing = scenario.timing
    return {
        "scenario": scenario.name,
        "description": scenario.description,
        "source": scenario.source,
        "connection": scenario.connection,
        "cog_height": scenario.cog_height,
        "gravity": scenario.gravity,
        "dt": scenario.dt,
        "timing": {
            "single_support": timing.single_support,
            "double_support": timing.double_support,
            "start": timing.start,
            "end": timing.end,
            "settle": timing.settle,
        },
        "horizon_steps": scenario.horizon_steps,
        "sole": {
            "front": scenario.sole.front,
            "back": scenario.sole.back,
            "inner": scenario.sole.inner,
            "outer": scenario.sole.outer,
        },
        "steps": scenario.steps,
        "step_length": scenario.step_length,
        "step_width": scenario.step_width,
        "step_height": scenario.step_height,
        "duration": float(rollout.times[-1]),
        "ticks": len(rollout.times),
        "plans": len(rollout.plans),
        "replans": len(rollout.connections),
        "planning_time_us": {
            "first_plan": rollout.plans[0].compute_time * 1e6 if rollout.plans else None,
            "replan_median": statistics.median(replan_us) if replan_us else None,
            "replan_max": max(replan_us) if replan_us else None,
        },
        "zmp_margin_min": rollout.zmp_margin_min,
        "zmp_outside": rollout.zmp_outside,
        "zmp_margin_min_time": float(rollout.times[worst]),
        "zmp_margin_min_position": [float(zmp[worst, 0]), float(zmp[worst, 1])],
        "zmp_margin_min_support": str(rollout.support[worst]),
        "zmp_outside_duration": float(np.count_nonzero(rollout.margin < 0.0) * scenario.dt),
        "zmp_deviation_max": [float(max_deviation[0]), float(max_deviation[1])],
        "changes": _changes(rollout, scenario),
        "footprints": [{"x": f.x, "y": f.y, "yaw": f.yaw, "side": f.side} for f in rollout.footprints],
    }
