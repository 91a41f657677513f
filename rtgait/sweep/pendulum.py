"""The pendulum level of a sweep: every case planned (or preview-controlled) and its ZMP margin measured, batched.

Cases that differ only in the numbers a walk is affine in (``change.length``, ``change.width``,
``walk.step_length``) form one group: one :class:`~rtgait.core.analysis.walk_family.WalkFamily` (or one preview loop),
one vectorised pass (:mod:`rtgait.core.analysis.batch`, :func:`rtgait.core.analysis.preview.evaluate_preview`). The
numbers are those ``rtgait plan`` reports for the same scenario. A base scenario the batch cannot take (a turning walk,
a footstep plan) is rolled out case by case instead, with the same results, slowly.

A base with a ``[terrain]`` table is batched as well: each case's footholds placed on the terrain as ``rtgait plan``
places them (a ``walk.step_length`` moves them onto other heights), their heights, the support heights their stances
hold (lowered before a step down) and the terrain handed to the batch with the parameters, and the results gain
:data:`~rtgait.sweep.store.TERRAIN_COLUMNS`: the range of the planned COG height and the error the vertical motion
adds to the horizontal ZMP, as ``summary.json``'s ``terrain`` entry (the preview baseline plans flat and has none).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import replace
from typing import Any

import numpy as np

from rtgait.core.analysis.batch import StraightWalk, evaluate_parameters
from rtgait.core.analysis.preview import PREVIEW_PERIOD, PreviewPlanner, evaluate_preview
from rtgait.core.geometry.footsteps import place_footsteps, standing_feet
from rtgait.core.geometry.support_height import support_heights
from rtgait.scenario.scenario import Scenario
from rtgait.sweep.spec import SweepSpec, case_scenario
from rtgait.sweep.store import TERRAIN_COLUMNS

PARAMETER_AXES = ("walk.step_length", "change.length", "change.width")
"""Axes a group's cases may differ in: the walk is affine in them."""


def groups(spec: SweepSpec, cases: list[tuple[str, dict[str, Any]]]) -> Iterator[list[tuple[str, dict[str, Any]]]]:
    """``cases`` (id, values) split into groups of one family each, in order of first appearance."""
    by_key: dict[tuple, list[tuple[str, dict[str, Any]]]] = {}
    for key, values in cases:
        group = tuple((k, v) for k, v in values.items() if k not in PARAMETER_AXES)
        by_key.setdefault(group, []).append((key, values))
    yield from by_key.values()


def evaluate_group(spec: SweepSpec, group: list[tuple[str, dict[str, Any]]]) -> dict[str, dict[str, Any]]:
    """Results (case id -> fields of :data:`~rtgait.sweep.store.PENDULUM_COLUMNS`) of one group of cases."""
    first = case_scenario(spec.base, group[0][1])
    method = group[0][1].get("connection", first.connection)
    heights = support = None
    try:
        walk = _walk(first, method)
        theta = np.stack([_parameters(walk, spec.base, values) for _, values in group])
        if method == "preview":
            margin, time, deviation = evaluate_preview(walk, theta)
            decisions = [""] * len(group)
        else:
            terrain = None if first.terrain is None else first.terrain.terrain
            if terrain is not None:
                heights, support = _case_heights(spec.base, [values for _, values in group])
            result = evaluate_parameters(walk, theta, heights, terrain, support)
            margin, time, deviation = result.zmp_margin_min, result.zmp_margin_min_time, result.zmp_deviation_max
            decisions = list(result.decisions)
    except ValueError as error:
        if "straight walks" not in str(error):
            raise
        return {key: rolled_out(case_scenario(spec.base, values), method) for key, values in group}
    out = {}
    for i, (key, _) in enumerate(group):
        out[key] = _fields(float(margin[i]), float(time[i]), deviation[i], decisions[i])
        if heights is not None:
            out[key].update({name: float(getattr(result, name)[i]) for name in TERRAIN_COLUMNS})
    return out


def _case_heights(base: Scenario, cases: list[dict[str, Any]]) -> tuple[np.ndarray, np.ndarray]:
    """The footholds' heights and the support heights their stances hold, each ``(cases, steps + 3)`` (m), of the
    footprints each case walks on: placed on the terrain (checked), as the planner takes them, from its strides.
    Cases of the same step length share them."""
    known: dict[Any, np.ndarray] = {}
    rows = []
    for values in cases:
        length = values.get("walk.step_length", base.step_length)
        if length not in known:
            scenario = case_scenario(base, {"walk.step_length": length}) if "walk.step_length" in values else base
            known[length] = _planned_heights(scenario)
        rows.append(known[length])
    both = np.stack(rows)
    return both[:, 0], both[:, 1]


def _planned_heights(scenario: Scenario) -> np.ndarray:
    """The heights and the stances' support heights ``(2, n + 2)`` (m) of the footprints ``F[0..n+1]`` the planner
    walks, from ``scenario``'s strides."""
    prints = place_footsteps(standing_feet(scenario.step_width, scenario.first_foot), scenario.strides())
    return np.array([[foot.z for foot in prints], support_heights(prints)])


def evaluate_cases(
    spec: SweepSpec, cases: list[tuple[str, dict[str, Any]]], done: Callable[[dict[str, dict[str, Any]]], None]
) -> None:
    """Evaluate ``cases`` group by group, handing each group's results to ``done`` as soon as they are known."""
    for group in groups(spec, cases):
        done(evaluate_group(spec, group))


def rolled_out(scenario: Scenario, method: str) -> dict[str, Any]:
    """One case by a rollout (what ``rtgait plan`` does), for what the batch does not take."""
    from rtgait.core.analysis.height_error import zmp_error
    from rtgait.core.analysis.rollout import rollout
    from rtgait.core.planner.online import OnlinePlanner
    from rtgait.viz.margin_marker import margin_marker

    config = scenario.planner_config()
    if method == "preview":
        run = rollout(PreviewPlanner(config, scenario.strides()), PREVIEW_PERIOD, scenario.sole, scenario.changes)
        mask = np.ones(len(run.times), dtype=bool)
    else:
        run = rollout(OnlinePlanner(config, scenario.strides()), scenario.dt, scenario.sole, scenario.changes)
        mask = run.free_segment_mask()
    zmp = np.stack([run.column("zmp_x"), run.column("zmp_y")], axis=1)
    ref = np.stack([run.column("zmp_ref_x"), run.column("zmp_ref_y")], axis=1)
    deviation = np.abs(zmp - ref)[mask].max(axis=0) if mask.any() else np.zeros(2)
    worst = margin_marker(run.times, run.margin, [t for t, _ in run.changes]).index
    fields = _fields(run.zmp_margin_min, float(run.times[worst]), deviation, "")
    if scenario.terrain is not None and method != "preview":
        cog_z = run.column("cog_z")
        error = zmp_error(run, scenario.terrain.terrain, scenario.gravity)
        fields.update(cog_z_min=float(cog_z.min()), cog_z_max=float(cog_z.max()), zmp_error_max=float(error.max()),
                      zmp_error_rms=float(np.sqrt(np.mean(error**2))))  # fmt: skip
    return fields


def _walk(scenario: Scenario, method: str) -> StraightWalk:
    config = scenario.planner_config()
    if method == "preview":
        config = replace(config, connection="real-time")  # its changes are decided at the real-time deadline
    if scenario.yaw != 0.0 or scenario.footholds is not None:  # a footstep plan's strides are its own
        raise ValueError("batched evaluation needs straight walks")
    return StraightWalk(config, scenario.sole, scenario.dt, scenario.steps, scenario.step_length, scenario.changes)


def _parameters(walk: StraightWalk, base: Scenario, values: dict[str, Any]) -> np.ndarray:
    """The family parameters of one case: the group's own, with its swept lengths and widths."""
    theta = walk.parameters()
    if "walk.step_length" in values:
        theta[1] = float(values["walk.step_length"])
    if walk.changes:
        first = walk.changes[0]
        column = 3
        if "change.length" in values and first.length is not None:
            theta[column] = float(values["change.length"])
        column += first.length is not None
        if "change.width" in values and first.width is not None:
            theta[column] = float(values["change.width"])
    return theta


def _fields(margin: float, time: float, deviation: np.ndarray, decision: str) -> dict[str, Any]:
    dx, dy = float(deviation[0]), float(deviation[1])
    return {
        "zmp_margin_min": margin,
        "zmp_margin_min_time": time,
        "zmp_outside": bool(margin < 0.0),
        "zmp_deviation_max": max(dx, dy),
        "zmp_deviation_max_x": dx,
        "zmp_deviation_max_y": dy,
        "decision": decision,
    }


__all__ = ["PARAMETER_AXES", "evaluate_cases", "evaluate_group", "groups", "rolled_out"]
