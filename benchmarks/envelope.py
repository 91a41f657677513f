"""The walked envelope of velocity commands: which commands each robot walks in physics, at each paper timing.

A command is swept along a direction of the step limits' ellipsoid (:mod:`rtgait.core.walk.velocity_command`):
a direction ``d = (a, b, c)`` (a unit vector of shares of the limits) at a share ``s`` of them asks, over the step
period ``T`` of the timing, the command

    vx = s a L / T,    vy = s b Dmax / 2T,    wz = s c Tmax / 2T,

with the robot's step limits ``L``, ``Dmax``, ``Tmax`` (its ``[velocity]`` table's, those of the timing's COG sway:
:func:`rtgait.core.lipm.sway.cog_sway`), so ``s = 1`` is on the clamp and
``s < 1`` inside it: the sweep covers everything the planner accepts without clamping. Each case is planned and
checked for reach by the whole-body IK first (as ``rtgait simulate`` does: a command out of reach is refused), then
walked in MuJoCo for a few steps of that one command (``--steps``, then a closing step) with the adaptive
controller, on ``state`` ``"truth"`` or ``"estimated"``. It walked when it was reachable and the robot did not fall,
landed every step and ended at rest.

Per robot and timing, the summary gives per direction the largest share walked with every smaller share of the
grid walked too, and the stride it asks (forward step length m, lateral displacement per pair of steps m, turn per
pair of steps rad). ``benchmarks/sim.py --envelope`` runs it (its module docstring has the options).
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
import time
import warnings
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Any

TIMINGS = ("fig6", "fig7", "fig8")
"""The scenarios whose timing the envelope is walked at (their footsteps are not used)."""

_HALF = math.sqrt(0.5)
DIRECTIONS: dict[str, tuple[float, float, float]] = {
    "forward": (1.0, 0.0, 0.0),
    "backward": (-1.0, 0.0, 0.0),
    "left": (0.0, 1.0, 0.0),
    "right": (0.0, -1.0, 0.0),
    "turn left": (0.0, 0.0, 1.0),
    "turn right": (0.0, 0.0, -1.0),
    "forward-left": (_HALF, _HALF, 0.0),
    "forward-right": (_HALF, -_HALF, 0.0),
    "backward-left": (-_HALF, _HALF, 0.0),
    "forward turning": (_HALF, 0.0, _HALF),
    "left turning": (0.0, _HALF, _HALF),
}
"""Directions of the sweep: shares of (forward step, lateral displacement, turn) limits, unit length."""
QUICK_DIRECTIONS = ("forward", "backward", "left", "right", "turn left", "forward-left", "forward turning")
SHARES = (0.25, 0.5, 0.75, 1.0)
QUICK_SHARES = (0.5, 1.0)
_MODELS: dict[str, Any] = {}


def command_at(limits: tuple[float, float, float], period: float, direction: str, share: float) -> tuple[float, ...]:
    """The command ``(vx, vy, wz)`` (m/s, m/s, rad/s) at ``share`` of the step ``limits`` (forward step m, lateral
    per pair m, turn per pair rad) along ``direction``, over a step period ``period`` (s)."""
    a, b, c = DIRECTIONS[direction]
    length, lateral, turn = limits
    return (share * a * length / period, share * b * lateral / (2.0 * period), share * c * turn / (2.0 * period))


def _model(name: str, physics_dt: float | None) -> tuple[Any, Any]:
    """The robot (loaded once per worker process) and a new MuJoCo model of it (no meshes, 0.2-0.3 s to build).

    A new model per case keeps the cases independent: a run that ends in the safety layer's damping leaves the
    model's actuators damping, and the next run on the same model would settle onto the floor with them before its
    loop restores the servos."""
    from rtgait.robot.model import RobotModel
    from rtgait.sim.model import SimConfig, build_sim_model

    if name not in _MODELS:
        _MODELS[name] = RobotModel.load(name)
    robot = _MODELS[name]
    return robot, build_sim_model(robot, SimConfig(meshes=False, physics_dt=physics_dt))


def envelope_case(job: dict[str, Any]) -> dict[str, Any]:
    """One case of the envelope (a worker's task): reach, then the walk in physics, and its outcome."""
    from rtgait.core.planner.online import CommandClampedWarning
    from rtgait.io.sim_run import mujoco_messages, planned_walk, simulate
    from rtgait.robot.motion import UnreachableError, robot_scenario, whole_body_motion
    from rtgait.scenario.loading import load_scenario
    from rtgait.sim.loop_options import LoopOptions

    began = time.perf_counter()
    robot, sim = _model(job["robot"], job["physics_dt"])
    scenario = dataclasses.replace(load_scenario(job["timing"]), steps=job["steps"])
    config = robot_scenario(scenario, robot).planner_config()
    period = config.timing.step_period
    limits = (config.max_step_length, config.max_step_lateral, config.max_step_turn)
    command = command_at(limits, period, job["direction"], job["share"])
    row: dict[str, Any] = {
        "robot": robot.name,
        "timing": job["timing"],
        "state": job["state"],
        "direction": job["direction"],
        "share": job["share"],
        "command": list(command),
        "step_period": period,
        # The stride asked: forward step (m), lateral displacement per pair of steps (m), turn per pair (rad).
        "stride": [command[0] * period, 2.0 * command[1] * period, 2.0 * command[2] * period],
        "limits": list(limits),
    }
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", CommandClampedWarning)
        try:
            whole_body_motion(robot, planned_walk(scenario, robot, command))
            row["reach_error"] = None
        except UnreachableError as error:
            row["reach_error"] = str(error)
        row["reachable"] = row["reach_error"] is None
        if row["reachable"]:
            with mujoco_messages():
                result = simulate(
                    scenario, robot, sim=sim, controller="adaptive", velocity=command,
                    options=LoopOptions(state=job["state"]),
                )  # fmt: skip
    row["clamped"] = any(issubclass(w.category, CommandClampedWarning) for w in caught)
    if row["reachable"]:
        row.update(
            walked=bool(result.all_steps_completed and result.ended_at_rest and not result.fell),
            fell=result.fell,
            fall_time=result.fall_time,
            tipped=result.tipped,
            steps_completed=result.steps_completed,
            steps_planned=result.steps_planned,
            step_adjustments=result.step_adjustment_count,
            foot_slip_max=result.foot_slip_max,
            simulated_time=result.duration,
        )
    else:
        row.update(walked=False, fell=None, fall_time=None, tipped=None, steps_completed=0, steps_planned=None,
                   step_adjustments=None, foot_slip_max=None, simulated_time=0.0)  # fmt: skip
    row["wall_time"] = time.perf_counter() - began
    return row


def outcome(row: dict[str, Any]) -> str:
    """One word or two for a case: walked, unreachable, fell at T s, or what else kept it from walking."""
    if row["walked"]:
        return "walked"
    if not row["reachable"]:
        return "unreachable"
    if row["fell"]:
        return f"fell {row['fall_time']:.1f}s"
    return f"stood {row['steps_completed']}/{row['steps_planned']}"


def jobs_of(args: Any) -> list[dict[str, Any]]:
    """Every case of the sweep (``args``: robots, timings, directions, shares, quick, state, steps, physics_dt), in
    the order of the report."""
    robots = args.robots or ["talos", "g1"]
    timings = args.timings or TIMINGS
    directions = args.directions or (QUICK_DIRECTIONS if args.quick else tuple(DIRECTIONS))
    shares = args.shares or (QUICK_SHARES if args.quick else SHARES)
    state, steps, physics_dt = args.state, args.steps, args.physics_dt
    return [
        {"robot": robot, "timing": timing, "direction": direction, "share": share, "state": state, "steps": steps,
         "physics_dt": physics_dt}
        for robot in robots
        for timing in timings
        for direction in directions
        for share in shares
    ]  # fmt: skip


def run(jobs: list[dict[str, Any]], workers: int, progress: bool = True) -> list[dict[str, Any]]:
    """The cases of ``jobs`` over ``workers`` processes, in the jobs' order; a line on stderr per finished case."""
    rows: list[dict[str, Any] | None] = [None] * len(jobs)
    began = time.perf_counter()
    with ProcessPoolExecutor(workers) as pool:
        futures = {pool.submit(envelope_case, job): i for i, job in enumerate(jobs)}
        for done, future in enumerate(as_completed(futures), start=1):
            row = future.result()
            rows[futures[future]] = row
            if progress:
                elapsed = time.perf_counter() - began
                sys.stderr.write(
                    f"[{done}/{len(jobs)} {elapsed:.0f} s] {row['robot']} {row['timing']} {row['direction']} "
                    f"{row['share']:g}: {outcome(row)} ({row['wall_time']:.1f} s)\n"
                )
                sys.stderr.flush()
    return [row for row in rows if row is not None]


def summary(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per robot, timing and direction: the direction's unit vector of shares and the limits it was swept to, the
    largest share walked with every smaller share walked too (0 when the smallest failed), its stride and command,
    and the cases that did not walk."""
    groups: dict[tuple[str, str, str], list[dict[str, Any]]] = {}
    for row in rows:
        groups.setdefault((row["robot"], row["timing"], row["direction"]), []).append(row)
    out = []
    for (robot, timing, direction), cases in groups.items():
        cases.sort(key=lambda r: r["share"])
        best = None
        for case in cases:
            if not case["walked"]:
                break
            best = case
        out.append({
            "robot": robot,
            "timing": timing,
            "direction": direction,
            "unit": list(DIRECTIONS[direction]),
            "limits": cases[0]["limits"],
            "largest_walked_share": best["share"] if best else 0.0,
            "stride": best["stride"] if best else [0.0, 0.0, 0.0],
            "command": best["command"] if best else [0.0, 0.0, 0.0],
            "failed": [f"{c['share']:g}: {outcome(c)}" for c in cases if not c["walked"]],
        })  # fmt: skip
    return out


def print_summary(table: list[dict[str, Any]], state: str) -> None:
    """The summary, one block per robot and timing."""
    print(f"walked envelope ({state} state; share: of the step limits along the direction, every smaller share "
          "of the grid walked too)")  # fmt: skip
    print(f"{'robot':<6} {'timing':<6} {'direction':<16} {'share':>5} {'vx,vy,wz m/s,m/s,rad/s':<24} "
          f"{'step m, lateral m, turn rad':<28} not walked")  # fmt: skip
    for entry in table:
        command = "{:.3f},{:.3f},{:.3f}".format(*entry["command"])
        stride = "{:.3f}, {:.3f}, {:.3f}".format(*entry["stride"])
        failed = "; ".join(entry["failed"])
        print(f"{entry['robot']:<6} {entry['timing']:<6} {entry['direction']:<16} "
              f"{entry['largest_walked_share']:>5.2f} {command:<24} {stride:<28} {failed}")  # fmt: skip


def record_text(report: dict[str, Any]) -> str:
    """The record of a sweep (``--record``): its state, grid and summary, one summary entry a line."""
    head = {key: report[key] for key in ("state", "quick", "steps")}
    lines = [json.dumps(entry) for entry in report["summary"]]
    return json.dumps(head)[:-1] + ', "summary": [\n' + ",\n".join(lines) + "\n]}\n"


def envelope(args: Any) -> dict[str, Any]:
    """The sweep of ``benchmarks/sim.py --envelope`` (``args``: as :func:`jobs_of`, and workers)."""
    jobs = jobs_of(args)
    began = time.perf_counter()
    rows = run(jobs, args.workers)
    return {
        "state": args.state,
        "quick": args.quick,
        "steps": args.steps,
        "cases": rows,
        "summary": summary(rows),
        "seconds": time.perf_counter() - began,
        "workers": args.workers,
    }
