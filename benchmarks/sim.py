"""Speed of the closed loop in physics: planner + whole-body IK + MuJoCo at 1 kHz (run on demand, not in tests).

Walks a built-in scenario (fig8 by default) with the robot in MuJoCo via :func:`rtgait.sim.run.simulate` a few
times and reports the real-time factor (simulated seconds per wall-clock second) and the wall time per tick; then
times the parts of one tick separately on the same walk: the planner's sample, the IK solve, ``mj_step`` alone
(with the IK's joint targets replayed), and the contact measurement.

Wall times on a shared virtual machine vary from run to run: run it a few times.

Usage: ``python benchmarks/sim.py [--json] [--robot NAME] [--scenario NAME] [--repeat N]``
"""

from __future__ import annotations

import argparse
import gc
import json
import statistics
import time

import mujoco
import numpy as np

from rtgait.core.online import OnlinePlanner
from rtgait.robot.ik import IKTargets, WholeBodyIK
from rtgait.robot.model import RobotModel
from rtgait.robot.motion import robot_scenario
from rtgait.scenario import load_scenario
from rtgait.sim.loop import measure_contacts
from rtgait.sim.model import SimConfig, build_sim_model
from rtgait.sim.run import simulate


def parts(robot: RobotModel, scenario_name: str) -> dict[str, float]:
    """Median wall time (us) of each part of a tick, each timed in a loop of its own over the same walk."""
    sim = build_sim_model(robot, SimConfig(meshes=False))
    walk = robot_scenario(load_scenario(scenario_name), robot)
    planner = OnlinePlanner(walk.planner_config(), walk.strides())
    planner.start(0.0)
    n = round(planner.end_time / sim.timestep)
    clock = time.perf_counter
    samples, rows = np.empty(n), []
    for k in range(n):
        began = clock()
        values, _, _ = planner.sample_values(k * sim.timestep)
        samples[k] = clock() - began
        rows.append(values)
    ik = WholeBodyIK(robot)
    q, _ = ik.solve(IKTargets(rows[0][0:3], rows[0][13:17], rows[0][17:21]), robot.q_half_sitting, 200, 1e-9)
    solves, targets = np.empty(n), np.empty((n, len(sim.joint_names)))
    for k, row in enumerate(rows):
        began = clock()
        q, _ = ik.solve(IKTargets(row[0:3], row[13:17], row[17:21]), q, max_iterations=1, tolerance=0.0)
        solves[k] = clock() - began
        targets[k] = q[7:]
    data = sim.new_data()
    steps, contacts = np.empty(n), np.empty(n)
    for k in range(n):
        data.ctrl[:] = targets[k]
        began = clock()
        mujoco.mj_step(sim.model, data)
        steps[k] = clock() - began
        began = clock()
        measure_contacts(data, sim.left_sole_geom, sim.right_sole_geom)
        contacts[k] = clock() - began
    return {
        "planner_sample_us": float(np.median(samples) * 1e6),
        "ik_solve_us": float(np.median(solves) * 1e6),
        "mj_step_us": float(np.median(steps) * 1e6),
        "measure_contacts_us": float(np.median(contacts) * 1e6),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--robot", default="talos")
    parser.add_argument("--scenario", default="fig8")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    robot = RobotModel.load(args.robot)
    sim = build_sim_model(robot)
    scenario = load_scenario(args.scenario)
    factors, per_tick = [], []
    for _ in range(args.repeat):
        gc.collect()
        result = simulate(scenario, robot, sim=sim)
        factors.append(result.real_time_factor)
        per_tick.append(result.wall_time / len(result.times) * 1e6)
    report = {
        "robot": robot.name,
        "scenario": args.scenario,
        "simulated_time_s": result.duration,
        "real_time_factor": factors,
        "tick_us_median_of_runs": statistics.median(per_tick),
        "fell": result.fell,
        **parts(robot, args.scenario),
    }
    if args.json:
        print(json.dumps(report))
        return
    print(f"{robot.name}, {args.scenario}: {report['simulated_time_s']:.1f} s simulated per run")
    print("real-time factor per run: " + ", ".join(f"{f:.1f}" for f in factors))
    print(f"wall time per 1 ms tick (median of runs): {report['tick_us_median_of_runs']:.0f} us")
    for key in ("planner_sample_us", "ik_solve_us", "mj_step_us", "measure_contacts_us"):
        print(f"  {key[:-3].replace('_', ' ')}: {report[key]:.1f} us (median)")


if __name__ == "__main__":
    main()
