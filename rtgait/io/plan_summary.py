"""The summary of a rollout (``summary.json`` of ``rtgait plan``), JSON-ready: the scenario, the worst ZMP margin (m)
and where it was, the planning times (µs), the changes and the auto connection's decisions (s), the footprints (m,
rad) and free segments the figures are drawn again from (``rtgait plot``).
"""

from __future__ import annotations

import statistics
from typing import Any

import numpy as np

from rtgait.core.analysis.rollout import Rollout
from rtgait.core.geometry.footsteps import Footstep
from rtgait.io.terrain_summary import footprint_entry, terrain_summary
from rtgait.scenario.scenario import Scenario
from rtgait.viz.margin_marker import margin_marker
from rtgait.viz.run_data import plan_free_segments

__all__ = ["auto_decisions", "summarize"]


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


def auto_decisions(scenario: Scenario) -> list[dict[str, Any]]:
    """The auto connection's decision for each change of ``scenario`` (``connection = "auto"``), JSON-ready: when the
    change arrived (s), the connection taken (``real-time``, ``quasi-real-time`` or ``deferred``), the strides it
    sets, when it is applied to the walk (s), every option weighed with its predicted ZMP margin (m) and the reason.

    The decisions are a deterministic function of the scenario (:mod:`rtgait.core.planner.auto`), so they are replayed
    here with a planner of the scenario's own rather than carried by the rollout."""
    from rtgait.core.analysis.rollout import rollout as roll_out
    from rtgait.core.planner.online import OnlinePlanner

    planner = OnlinePlanner(scenario.planner_config(), scenario.strides())
    replayed = roll_out(planner, scenario.dt, scenario.sole, scenario.changes)
    # The planner logs the latest time it sampled; the rollout, the tick at which it handed the change over.
    handed = {step: when for when, step in replayed.changes}
    out = []
    for record in planner.change_log:
        arrived = float(handed.get(record.step, record.time))
        committed = arrived if record.commit_time == record.time else float(record.commit_time)
        out.append({
            "step": record.step,
            "arrived_at": arrived,
            "connection": record.connection,
            "committed_step": record.committed_step,
            "through": record.through,
            "committed_at": committed,
            "predicted": [
                {"connection": kind, "step": step, "zmp_margin": margin} for kind, step, margin in record.predicted
            ],
            "reason": record.reason,
        })  # fmt: skip
    return out


def _footprints(footprints: list[Footstep]) -> list[dict[str, Any]]:
    return [footprint_entry(f) for f in footprints]


def summarize(rollout: Rollout, scenario: Scenario) -> dict[str, Any]:
    """Key numbers of a rollout, JSON-serialisable (SI units; planning times in microseconds).

    ``zmp_margin_min`` is the smallest margin; ``zmp_margin_min_time``, ``_position`` and ``_support`` describe the
    tick the figures mark, one of the ticks at that minimum chosen by :func:`rtgait.viz.margin_marker.margin_marker`
    (when the minimum is tied, the first tied tick at or after the first change's decision, else the first tied
    tick). ``nominal_footprints`` and ``free_segments`` are there so that the figures can be drawn again from the
    files alone (``rtgait plot``).
    """
    worst = margin_marker(rollout.times, rollout.margin, [t for t, _ in rollout.changes]).index
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
        "footprints": _footprints(rollout.footprints),
        "nominal_footprints": _footprints(scenario.nominal_footprints()),
        "free_segments": [list(segment) for segment in plan_free_segments(rollout)],
        **terrain_summary(rollout, scenario),
        **({"auto_margin": scenario.auto_margin, "auto_decisions": auto_decisions(scenario)}
           if scenario.connection == "auto" else {}),
    }  # fmt: skip
