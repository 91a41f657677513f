"""Speed of the closed loop in physics: planner + whole-body IK + MuJoCo (run on demand, not in tests).

Walks a built-in scenario (fig8 by default) with the robot in MuJoCo via :func:`rtgait.sim.run.simulate` a few
times and reports the real-time factor (simulated seconds per wall-clock second) and the wall time per control
tick; then times the parts of one tick separately on the same walk: the planner's sample, the IK solve, one
``mj_step`` (with the IK's joint references replayed; a tick takes ``control_dt / physics_dt`` of them), the
contact measurement, and ``mj_step`` again without the no-slip solver and without the leg collision boxes, to
show what each costs.

Wall times on a shared virtual machine vary from run to run: run it a few times.

Usage: ``python benchmarks/sim.py [--json] [--robot NAME] [--scenario NAME] [--repeat N] [--control-dt S]
[--physics-dt S]``
"""

from __future__ import annotations

import argparse
import dataclasses
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


def _step_times(robot: RobotModel, config: SimConfig, targets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Wall time of each ``mj_step`` and of each contact measurement (s) with ``targets`` replayed, one row per
    control tick, ``substeps`` physics steps each."""
    sim = build_sim_model(robot, config)
    data = sim.new_data()
    clock = time.perf_counter
    steps, contacts = [], np.empty(len(targets))
    for k, row in enumerate(targets):
        data.ctrl[:] = row
        for _ in range(sim.substeps):
            began = clock()
            mujoco.mj_step(sim.model, data)
            steps.append(clock() - began)
        began = clock()
        measure_contacts(data, sim.left_sole_geom, sim.right_sole_geom)
        contacts[k] = clock() - began
    return np.array(steps), contacts


def parts(robot: RobotModel, scenario_name: str, config: SimConfig) -> dict[str, float]:
    """Median wall time (us) of each part of a tick, each timed in a loop of its own over the same walk."""
    sim = build_sim_model(robot, config)
    walk = robot_scenario(load_scenario(scenario_name), robot)
    planner = OnlinePlanner(walk.planner_config(), walk.strides())
    planner.start(0.0)
    dt = sim.control_dt
    n = round(planner.end_time / dt)
    clock = time.perf_counter
    samples, rows = np.empty(n), []
    for k in range(n):
        began = clock()
        values, _, _ = planner.sample_values(k * dt)
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
    steps, contacts = _step_times(robot, config, targets)
    plain, _ = _step_times(robot, dataclasses.replace(config, noslip_iterations=0), targets)
    no_legs, _ = _step_times(robot, dataclasses.replace(config, leg_collisions=False), targets)
    return {
        "control_dt_s": dt,
        "physics_dt_s": sim.timestep,
        "substeps": sim.substeps,
        "planner_sample_us": float(np.median(samples) * 1e6),
        "ik_solve_us": float(np.median(solves) * 1e6),
        "mj_step_us": float(np.median(steps) * 1e6),
        "mj_step_without_noslip_us": float(np.median(plain) * 1e6),
        "mj_step_without_leg_collisions_us": float(np.median(no_legs) * 1e6),
        "measure_contacts_us": float(np.median(contacts) * 1e6),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--robot", default="talos")
    parser.add_argument("--scenario", default="fig8")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--control-dt", type=float, default=None, help="control period (s); default the robot's")
    parser.add_argument("--physics-dt", type=float, default=0.001, help="physics step (s); default 0.001")
    args = parser.parse_args()
    robot = RobotModel.load(args.robot)
    config = SimConfig(control_dt=args.control_dt, physics_dt=args.physics_dt)
    sim = build_sim_model(robot, config)
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
        **parts(robot, args.scenario, dataclasses.replace(config, meshes=False)),
    }
    if args.json:
        print(json.dumps(report))
        return
    print(f"{robot.name}, {args.scenario}: {report['simulated_time_s']:.1f} s simulated per run")
    print("real-time factor per run: " + ", ".join(f"{f:.1f}" for f in factors))
    control, physics = report["control_dt_s"] * 1000, report["physics_dt_s"] * 1000
    tick = f"{control:g} ms tick, {report['substeps']} physics step(s) of {physics:g} ms"
    print(f"wall time per {tick} (median of runs): {report['tick_us_median_of_runs']:.0f} us")
    for key in (
        "planner_sample_us",
        "ik_solve_us",
        "mj_step_us",
        "mj_step_without_noslip_us",
        "mj_step_without_leg_collisions_us",
        "measure_contacts_us",
    ):
        print(f"  {key[:-3].replace('_', ' ')}: {report[key]:.1f} us (median)")


if __name__ == "__main__":
    main()
