"""Wall time of one whole-body IK tick on a planned walk (run on demand, not in the test suite).

The fig8 scenario (quasi-real-time connection, step length 0.05 -> 0.15 m) is planned for the robot (its COG
height, step width and sole) and sampled at the control period; each tick then calls
:meth:`rtgait.robot.ik.WholeBodyIK.solve` once, warm-started from the previous tick's solution, as a control loop
would. The first tick (from half-sitting to the walk's first pose) is excluded. Reported: median and p99 wall
time per tick (us), iterations per tick, and the largest task errors the solver measured.

Wall times on a shared virtual machine vary from run to run: run it a few times.

Usage: ``python benchmarks/ik.py [--json] [--robot NAME] [--dt S] [--iterations N] [--tolerance M]``
"""

from __future__ import annotations

import argparse
import dataclasses
import gc
import json
import time

import numpy as np

from rtgait.core.analysis.rollout import rollout
from rtgait.core.planner.online import OnlinePlanner
from rtgait.core.planner.sample import SampleColumns
from rtgait.interface.task_targets import IKTargets
from rtgait.robot.ik import WholeBodyIK
from rtgait.robot.model import RobotModel
from rtgait.robot.motion import robot_scenario
from rtgait.scenario.loading import load_scenario


def run(robot_name: str, dt: float, iterations: int, tolerance: float) -> dict:
    robot = RobotModel.load(robot_name)
    scenario = dataclasses.replace(robot_scenario(load_scenario("fig8"), robot), dt=dt)
    walk = rollout(OnlinePlanner(scenario.planner_config(), scenario.strides()), dt, scenario.sole, scenario.changes)
    cogs = walk.values[:, SampleColumns.cog].tolist()
    lefts = walk.values[:, SampleColumns.left_foot].tolist()
    rights = walk.values[:, SampleColumns.right_foot].tolist()
    rows = [IKTargets(cog, left, right) for cog, left, right in zip(cogs, lefts, rights, strict=True)]
    ik = WholeBodyIK(robot, max_iterations=iterations, tolerance=tolerance)
    q, _ = ik.solve(rows[0], robot.q_half_sitting, 200)
    ticks = np.empty(len(rows) - 1)
    used = np.empty(len(rows) - 1, dtype=int)
    worst = np.zeros(6)
    clock = time.perf_counter
    gc.collect()
    for k, targets in enumerate(rows[1:]):
        start = clock()
        q, errors = ik.solve(targets, q)
        ticks[k] = clock() - start
        used[k] = errors.iterations
        np.maximum(worst, errors[:6], out=worst)
    micro = ticks * 1e6
    return {
        "robot": robot.name,
        "dt": dt,
        "ticks": len(ticks),
        "tick_us": {"median": float(np.median(micro)), "p99": float(np.percentile(micro, 99))},
        "iterations_per_tick": {str(n): int(c) for n, c in enumerate(np.bincount(used)) if c},
        "max_error": {
            "cog_m": float(worst[0]),
            "feet_position_m": float(max(worst[1], worst[3])),
            "feet_orientation_rad": float(max(worst[2], worst[4])),
            "torso_orientation_rad": float(worst[5]),
        },
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--robot", default="talos", help="built-in robot name or description file (default talos)")
    parser.add_argument("--dt", type=float, default=0.001, help="control period (s), default 0.001")
    parser.add_argument("--iterations", type=int, default=3, help="most Gauss-Newton iterations per tick")
    parser.add_argument("--tolerance", type=float, default=1e-6, help="iterate while an error exceeds this (m)")
    args = parser.parse_args()
    result = run(args.robot, args.dt, args.iterations, args.tolerance)
    if args.json:
        print(json.dumps(result))
        return
    t = result["tick_us"]
    e = result["max_error"]
    print(f"{result['robot']}: {result['ticks']} IK ticks at dt = {result['dt']} s")
    print(f"  per tick: median {t['median']:.1f} us, p99 {t['p99']:.1f} us")
    print(f"  iterations per tick: {result['iterations_per_tick']}")
    print(
        f"  largest errors: COG {e['cog_m'] * 1e3:.4f} mm, feet {e['feet_position_m'] * 1e3:.4f} mm / "
        f"{e['feet_orientation_rad'] * 1e3:.4f} mrad, torso {e['torso_orientation_rad'] * 1e3:.4f} mrad"
    )


if __name__ == "__main__":
    main()
