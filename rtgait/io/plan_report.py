"""The lines the command line prints from a summary: ``rtgait plan``'s (:func:`plan_report`) and
``rtgait simulate --model lipm``'s (:func:`pendulum_report`); lengths shown in m or mm, times in s or µs."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from rtgait.io.obstacle_outputs import obstacle_report_lines
from rtgait.io.terrain_summary import terrain_line

__all__ = ["pendulum_report", "plan_report"]


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
