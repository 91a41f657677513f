"""Plain-file outputs of a rollout: the per-tick trajectory as CSV, a JSON-ready summary, and the few lines the
command line prints from a summary.

Kept apart from the command-line tool so that scripts driving the planner can write the same files. Every file
is written through a temporary name (:func:`rtgait.outputs.write_atomic`), so none is ever seen half written.
"""

from __future__ import annotations

import os
import statistics
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rtgait.core.analysis.rollout import Rollout
from rtgait.core.geometry.footsteps import Footstep
from rtgait.core.planner.online import SAMPLE_FIELDS
from rtgait.io.obstacle_outputs import obstacle_report_lines, obstacle_summary
from rtgait.io.summary_json import summary_text
from rtgait.io.terrain_summary import footprint_entry, terrain_line, terrain_summary
from rtgait.outputs import Staging, staged_outputs, write_atomic
from rtgait.scenario.scenario import Scenario
from rtgait.viz.run_data import OBSTACLE_FIGURE, figure_file, margin_marker, plan_figure_files, plan_free_segments

if TYPE_CHECKING:  # the robot layer is optional (the [robot] extra)
    from rtgait.core.obstacle.walk import ObstacleRun
    from rtgait.robot.pipeline import RobotRun

__all__ = [
    "CSV_COLUMNS",
    "CSV_HEAD_COLUMNS",
    "auto_decisions",
    "plan_files",
    "plan_report",
    "summarize",
    "write_joints_csv",
    "write_plan_outputs",
    "write_trajectory_csv",
]

CSV_HEAD_COLUMNS = (
    "t", "cog_x", "cog_y", "cog_z", "cog_vx", "cog_vy", "cog_ax", "cog_ay", "zmp_x", "zmp_y",
    "lfoot_x", "lfoot_y", "lfoot_z", "lfoot_yaw", "rfoot_x", "rfoot_y", "rfoot_z", "rfoot_yaw", "support",
)  # fmt: skip
"""The first columns of ``trajectory.csv``, a stable interface for downstream tools (SI units, yaw in rad)."""

CSV_EXTRA_COLUMNS = ("zmp_ref_x", "zmp_ref_y", "zmp_margin", "phase", "cog_vz", "cog_az", "dcm_x", "dcm_y")
"""Columns after :data:`CSV_HEAD_COLUMNS`: reference ZMP (m), signed ZMP margin (m, > 0 inside), phase
index, the vertical COG velocity and acceleration (zero for the constant-height model), and the divergent
component of motion (capture point) ``xi = c + c'/w`` (m)."""

CSV_COLUMNS = CSV_HEAD_COLUMNS + CSV_EXTRA_COLUMNS

# 10 significant digits: sub-micrometre for positions within 100 m, exact for the tick times of usual periods.
_FLOAT_FORMAT = "%.10g"


def write_joints_csv(header: tuple[str, ...], rows: np.ndarray, path: Path) -> int:
    """Write a joint table (``t``, ``base_x`` .. ``base_qw``, one column per joint) to ``path``; returns the rows."""

    def write(temporary: Path) -> None:
        with open(temporary, "w", encoding="utf-8", newline="") as stream:
            stream.write(",".join(header) + "\n")
            np.savetxt(stream, rows, fmt=_FLOAT_FORMAT, delimiter=",")

    write_atomic(path, write)
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

    def write(temporary: Path) -> None:
        with open(temporary, "w", encoding="utf-8", newline="") as stream:
            stream.write(",".join(CSV_COLUMNS) + "\n")
            stream.writelines(",".join(row) + "\n" for row in table.tolist())

    write_atomic(path, write)
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
    tick the figures mark, one of the ticks at that minimum chosen by :func:`rtgait.viz.run_data.margin_marker`
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


# ----- the whole set of a plan's outputs ------------------------------------------------------------------------


def plan_files(figures: bool, robot: bool, html: bool, fmt: str = "png", obstacles: bool = False) -> list[str]:
    """The files :func:`write_plan_outputs` writes with these options (figures in the format ``fmt``: png, pdf or
    svg; ``obstacles``: the scenario has some, and its figure like the paper's Fig. 1 is added), in the order the
    summary lists them."""
    names = ["trajectory.csv", "summary.json"] + (["joints.csv"] if robot else [])
    if figures:
        names += [*plan_figure_files(fmt), *([figure_file("multibody_zmp", fmt)] if robot else [])]
        names += [figure_file(OBSTACLE_FIGURE, fmt)] if obstacles else []
    return names + (["replay.html"] if robot and html else [])


def write_plan_outputs(
    result: Rollout,
    scenario: Scenario,
    out: Path,
    *,
    figures: bool = True,
    robot_run: RobotRun | None = None,
    html: bool = False,
    fmt: str = "png",
    background: str = "sky",
    obstacle_runs: list[ObstacleRun] | None = None,
) -> dict[str, Any]:
    """Write what ``rtgait plan`` writes into the folder ``out``, replacing the previous outputs of the same names
    together or not at all (:func:`rtgait.outputs.staged_outputs`); returns the summary.

    Args:
        result: the rollout.
        scenario: the scenario rolled out (as the robot walks it, with a robot).
        out: the output folder, created if missing.
        figures: the four figures and, with a robot, the multibody ZMP figure (needs matplotlib).
        robot_run: the walk on a robot: adds ``joints.csv`` and the robot's numbers to the summary.
        html: with a robot, also the 3D replay ``replay.html`` (needs meshcat).
        fmt: the figures' file format, ``"png"``, ``"pdf"`` or ``"svg"``.
        background: the replay's background, ``"sky"`` or ``"white"``.
        obstacle_runs: with obstacles, the walk under each connection mode (:func:`rtgait.io.obstacle_outputs
            .obstacle_runs`): adds ``obstacle_walks`` to the summary and, with figures, the obstacle figure.

    Raises:
        rtgait.outputs.OutputError: the outputs could not be written; ``out`` is unchanged.
    """
    with staged_outputs(out) as staging:
        rows = write_trajectory_csv(result, staging.add("trajectory.csv"))
        summary_path = staging.add("summary.json")
        summary = summarize(result, scenario)
        if robot_run is not None:
            write_joints_csv(*robot_run.motion.table(), staging.add("joints.csv"))
            summary.update(robot_run.summary())
        if obstacle_runs:
            summary["obstacle_walks"] = obstacle_summary(obstacle_runs)
        if figures:
            _write_figures(result, scenario, robot_run, staging, fmt)
            if obstacle_runs:
                from rtgait.viz.obstacle_figure import plot_obstacle_walks

                path = staging.add(figure_file(OBSTACLE_FIGURE, fmt))
                plot_obstacle_walks(obstacle_runs, scenario.sole, scenario.name, path)
        if html and robot_run is not None:
            _write_replay(result, scenario, robot_run, staging.add("replay.html"), background)
        summary["rows"] = rows
        summary["files"] = list(staging.files)
        summary_path.write_text(summary_text(summary), encoding="utf-8")
    return summary


def _write_figures(result: Rollout, scenario: Scenario, robot_run: RobotRun | None, staging: Staging, fmt: str) -> None:
    from rtgait.viz.figures import FigureInfo, plot_multibody_zmp, render_all

    info = FigureInfo(
        title=f"{scenario.name} ({scenario.connection})",
        sole=scenario.sole,
        nominal_footprints=scenario.nominal_footprints(),
    )
    for path in render_all(result, info, staging.folder, fmt):
        staging.add(path.name)
    if robot_run is not None:
        before = robot_run.uncompensated[1] if robot_run.uncompensated else robot_run.check
        after = robot_run.check if robot_run.uncompensated else None
        plot_multibody_zmp(
            result, info, staging.add(figure_file("multibody_zmp", fmt)), before.zmp,
            None if after is None else after.zmp, robot=robot_run.robot.name,
        )  # fmt: skip


def _write_replay(
    result: Rollout, scenario: Scenario, robot_run: RobotRun, path: Path, background: str = "sky"
) -> None:
    from rtgait.robot.pipeline import visual_model
    from rtgait.viz.replay import write_replay_html

    robot = robot_run.robot
    motion = robot_run.motion
    write_replay_html(
        path,
        robot.full_model,
        visual_model(robot),
        motion.times,
        motion.q_full,
        footprints=result.footprints,
        sole=scenario.sole,
        cog=robot_run.check.cog,
        zmp=np.column_stack([result.column("zmp_x"), result.column("zmp_y")]),
        title=f"rtgait: {scenario.name} on {robot.name}",
        background=background,
    )


# ----- what the command line prints -----------------------------------------------------------------------------


def _describe_change(change: dict[str, Any]) -> str:
    parts = []
    if change["length"] is not None:
        parts.append(f"length {change['length']:g} m")
    if change["width"] is not None:
        parts.append(f"width {change['width']:g} m")
    if change["yaw"] is not None:
        parts.append(f"yaw {change['yaw']:g} rad")
    span = "that step only" if change["through"] == change["step"] else f"steps {change['step']}..{change['through']}"
    return f"step {change['step']} decided at {change['decided_at']:.3f} s: {', '.join(parts)} ({span})"


def _describe_decision(decision: dict[str, Any]) -> str:
    def option(p: dict[str, Any]) -> str:
        where = f" {p['step']}" if p["connection"] == "deferred" else ""
        return f"{p['connection']}{where} {p['zmp_margin'] * 1e3:+.1f} mm"

    others = ", ".join(option(p) for p in decision["predicted"])
    return (
        f"step {decision['step']} at {decision['arrived_at']:.3f} s -> {decision['reason']}; applied at "
        f"{decision['committed_at']:.3f} s (weighed: {others})"
    )


def _robot_lines(summary: dict[str, Any]) -> list[str]:
    error = summary["multibody_zmp_error_max"]
    lines = [
        f"robot       {summary['robot']} ({summary['robot_mass']:.1f} kg): IK error max COG "
        f"{summary['ik_cog_error_max'] * 1e6:.2f} µm, feet {summary['ik_foot_error_max'] * 1e6:.2f} µm, "
        f"{summary['ik_time_per_tick_us']:.0f} µs per tick; multibody ZMP error max x {error['x'] * 1e3:.1f} mm, "
        f"y {error['y'] * 1e3:.1f} mm"
    ]
    compensation = summary.get("angular_momentum_compensation")
    if compensation is not None:
        before, after = compensation["before"], compensation["after"]
        changes = [
            ", ".join(f"{axis} {before[key][axis] * 1e3:.1f} -> {after[key][axis] * 1e3:.1f} mm" for axis in "xy")
            for key in ("multibody_zmp_error_max", "multibody_zmp_error_rms")
        ]
        lines.append(
            f"compensate  angular momentum, Fourier order {compensation['order']}: multibody ZMP error max "
            f"{changes[0]}; rms {changes[1]}"
        )
    return lines


def plan_report(summary: dict[str, Any], out: Path, wall_time: float) -> str:
    """The lines ``rtgait plan`` prints for the summary of a run written to ``out`` whose rollout took
    ``wall_time`` (s): scenario, mode, changes, worst ZMP margin and verdict, replanning times, robot, outputs."""
    timing = summary["timing"]
    outside = summary["zmp_outside"]
    x, y = summary["zmp_margin_min_position"]
    times = summary["planning_time_us"]
    lines = [
        f"scenario    {summary['scenario']}: {summary['description']}",
        f"mode        {summary['connection']} connection, T_s {timing['single_support']:g} s, "
        f"T_dbl {timing['double_support']:g} s, {summary['steps']} steps + 1 closing, dt {summary['dt']:g} s, "
        f"{summary['duration']:.2f} s walked",
    ]
    lines += [f"change      {_describe_change(change)}" for change in summary["changes"]] or ["change      none"]
    lines += [f"auto        {_describe_decision(decision)}" for decision in summary.get("auto_decisions", [])]
    lines += [
        f"ZMP margin  min {summary['zmp_margin_min']:+.4f} m at t = {summary['zmp_margin_min_time']:.3f} s, "
        f"ZMP at ({x:.3f}, {y:.3f}) m, {summary['zmp_margin_min_support']} support",
        f"verdict     {'OUTSIDE the support polygon' if outside else 'inside the support polygon'}"
        + (f" for {summary['zmp_outside_duration']:.3f} s" if outside else ""),
        *terrain_line(summary),
    ]
    if times["replan_median"] is not None:
        lines.append(
            f"replans     {summary['replans']} connected replans, planning time per replan "
            f"median {times['replan_median']:.0f} µs, max {times['replan_max']:.0f} µs "
            f"(first plan {times['first_plan']:.0f} µs; whole rollout {wall_time:.2f} s)"
        )
    else:
        lines.append(f"replans     none (first plan {times['first_plan']:.0f} µs)")
    lines += obstacle_report_lines(summary.get("obstacle_walks", []))
    if "robot" in summary:
        lines += _robot_lines(summary)
    lines.append(f"outputs     {out}{os.sep}: {', '.join(summary['files'])} ({summary['rows']} rows)")
    return "\n".join(lines) + "\n"


def pendulum_report(summary: dict[str, Any], out: Path) -> str:
    """The lines ``rtgait simulate --model lipm`` prints: outcome, step adjustments, pushes, tracking, speed,
    outputs."""
    if summary["fell"]:
        outcome = f"FELL at {summary['fall_time']:.2f} s"
    else:
        rest = "ended at rest" if summary["ended_at_rest"] else "did NOT end at rest"
        outcome = f"walked {summary['steps_completed']} of {summary['steps_planned']} steps, {rest}"
    pushes = summary["pushes"]
    lines = [
        f"scenario    {summary['scenario']} ({summary['connection']}) on a {summary['mass']:g} kg point mass (LIPM), "
        f"{summary['controller']}, control period {summary['dt'] * 1e3:g} ms",
        f"outcome     {outcome}",
        "pushes      "
        + (", ".join(f"{p['impulse_norm']:.1f} N s at {p['start']:.2f} s" for p in pushes) if pushes else "none"),
        f"stepping    {summary['step_adjustments']} step adjustment(s)"
        + "".join(f"; first at {entry['t']:.2f} s: {entry['reason']}" for entry in summary["step_adjustment_log"][:1]),
        f"tracking    commanded vs planned ZMP RMS {summary['zmp_tracking_error_rms'] * 1e3:.1f} mm, "
        f"{summary['replans']} replans",
        f"speed       real-time factor {summary['real_time_factor']:.0f} ({summary['simulated_time']:.1f} s simulated "
        f"in {summary['wall_time']:.2f} s)",
        f"outputs     {out}{os.sep}: {', '.join(summary['files'])} ({summary['rows']} rows)",
    ]
    return "\n".join(lines) + "\n"
