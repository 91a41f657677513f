"""Wall time of the stack's feed-forward torques per tick on a planned walk (run on demand, not in the test suite).

The fig8 scenario is planned for the robot and sampled at the control period; each tick solves the whole-body IK
once (warm-started, as the stack does) and then times :meth:`rtgait.stack.feedforward.FeedForward.torques` with the
plan's support and ZMP standing in for the controller's output. Reported: median and p99 wall time per tick (us), the
same for the IK, for the inverse dynamics' update alone and per distribution method (closed form, one foot, QP), and
how many ticks each method served.

With ``--sensed`` the feed-forward is torque drive's, computed at the sensed state
(:mod:`rtgait.stack.measured_motion`): the encoders read the IK's joints and their rates, the estimate's feet are the
IK's soles (the support's feet loaded); ``sensed_state_us`` is the sensed state's own part. The estimator's kinematics
of the encoders' readings, which the stack shares with the sensed state, are computed outside the timed part (the
estimator runs them in any case); ``--unshared`` times the sensed state computing its own instead.

Wall times on a shared virtual machine vary from run to run: run it a few times.

Usage: ``python benchmarks/feedforward.py [--json] [--robot NAME] [--dt S] [--sensed [--unshared]]``
"""

from __future__ import annotations

import argparse
import dataclasses
import gc
import json
import time

import numpy as np
import pinocchio as pin

from rtgait.control.settings import ControlTargets
from rtgait.core.analysis.rollout import rollout
from rtgait.core.planner.online import OnlinePlanner
from rtgait.core.planner.sample import SampleColumns
from rtgait.estimation.state import FootState, Measurement
from rtgait.interface.task_targets import FootOffsets, IKTargets
from rtgait.robot.ik import WholeBodyIK
from rtgait.robot.kinematics import PinocchioKinematics
from rtgait.robot.model import RobotModel
from rtgait.robot.motion import robot_scenario
from rtgait.scenario.loading import load_scenario
from rtgait.stack.feedforward import FeedForward
from rtgait.stack.measured_motion import MeasuredMotion


def _stats(micro: np.ndarray) -> dict[str, float]:
    return {"median": float(np.median(micro)), "p99": float(np.percentile(micro, 99))} if len(micro) else {}


def _sensed(robot: RobotModel, q: np.ndarray, support: str, data: pin.Data | None = None) -> Measurement:
    """An estimate whose feet are the IK's soles at ``q``, those of ``support`` loaded (``data``: the model's data to
    use, default a new one)."""
    model = robot.model
    data = model.createData() if data is None else data
    pin.framesForwardKinematics(model, data, q)
    feet = []
    for side, frame in (("left", robot.left_sole_id), ("right", robot.right_sole_id)):
        placement = data.oMf[frame]
        roll, pitch, yaw = pin.rpy.matrixToRpy(placement.rotation)
        x, y, z = placement.translation
        force = 400.0 if support in ("double", side) else 0.0
        feet.append(FootState((0.0, 0.0, force), (0.0, 0.0, 0.0), force, (x, y), (0.0, 0.0), (x, y, z, yaw), roll,
                              pitch, 0.0, force > 0.0, 4))  # fmt: skip
    nan2 = (float("nan"), float("nan"))
    return Measurement(0.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), nan2, nan2, 800.0, feet[0], feet[1], (), 0)


def run(robot_name: str, dt: float, sensed: bool = False, shared: bool = True) -> dict:
    robot = RobotModel.load(robot_name)
    scenario = dataclasses.replace(robot_scenario(load_scenario("fig8"), robot), dt=dt)
    walk = rollout(OnlinePlanner(scenario.planner_config(), scenario.strides()), dt, scenario.sole, scenario.changes)
    values = walk.values
    ik = WholeBodyIK(robot, max_iterations=1, tolerance=0.0)
    tracking = MeasuredMotion(robot) if sensed else None
    kinematics = PinocchioKinematics(robot) if sensed and shared else None  # the estimator's, untimed
    scratch = robot.model.createData()
    feedforward = FeedForward(robot, scenario.sole, dt, tracking=tracking)
    first = IKTargets(
        values[0, SampleColumns.cog], values[0, SampleColumns.left_foot], values[0, SampleColumns.right_foot]
    )
    q, _ = ik.solve(first, robot.q_half_sitting, 200, 1e-9)
    n = len(values) - 1
    ik_time, ff_time, update_time, sensed_time = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    methods: list[str] = []
    clock = time.perf_counter
    gc.collect()
    for k in range(1, len(values)):
        row = values[k]
        cog, left, right = (
            row[SampleColumns.cog].tolist(),
            row[SampleColumns.left_foot].tolist(),
            row[SampleColumns.right_foot].tolist(),
        )
        zmp = tuple(row[SampleColumns.zmp].tolist())
        targets = IKTargets(cog, left, right)
        start = clock()
        q, _ = ik.solve(targets, q, errors=False)
        ik_time[k - 1] = clock() - start
        out = ControlTargets(k * dt, cog, left, right, FootOffsets(), zmp, zmp, (0.0, 0.0), str(walk.support[k]), 0, ())
        state = None
        if tracking is not None:  # the encoders read the IK's joints at its last rates
            joints, velocities = q[7:], feedforward.rates.velocity[6:].copy()
            body = None if kinematics is None else kinematics.update(joints, velocities)
            state = (joints, joints, velocities, _sensed(robot, q, str(walk.support[k]), scratch), body)
        start = clock()
        feedforward.torques(q, targets, out, None, state)
        ff_time[k - 1] = clock() - start
        if tracking is not None:
            rates = feedforward.rates
            start = clock()
            tracking.update(q, rates.velocity, rates.acceleration, *state)
            sensed_time[k - 1] = clock() - start
        methods.append(feedforward.last.method)
        v, a = feedforward.rates.velocity, feedforward.rates.acceleration
        start = clock()
        feedforward.dynamics.update(q, v, a)
        update_time[k - 1] = clock() - start
    names = np.array(methods)
    return {
        "robot": robot.name,
        "dt": dt,
        "sensed": sensed,
        "shared_kinematics": sensed and shared,
        "ticks": n,
        "ik_us": _stats(ik_time * 1e6),
        "feedforward_us": _stats(ff_time * 1e6),
        "inverse_dynamics_update_us": _stats(update_time * 1e6),
        "sensed_state_us": _stats(sensed_time * 1e6) if sensed else {},
        "feedforward_us_by_method": {m: _stats(ff_time[names == m] * 1e6) for m in sorted(set(methods))},
        "ticks_by_method": {m: int((names == m).sum()) for m in sorted(set(methods))},
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--robot", default="talos", help="built-in robot name or description file (default talos)")
    parser.add_argument("--dt", type=float, default=0.001, help="control period (s), default 0.001")
    parser.add_argument("--sensed", action="store_true", help="torque drive's feed-forward, at the sensed state")
    parser.add_argument("--unshared", action="store_true",
                        help="with --sensed: the sensed state runs its own kinematics")  # fmt: skip
    args = parser.parse_args()
    result = run(args.robot, args.dt, args.sensed, not args.unshared)
    if args.json:
        print(json.dumps(result))
        return
    print(f"{result['robot']}, dt {result['dt']} s, {result['ticks']} ticks")
    for key in ("ik_us", "feedforward_us", "inverse_dynamics_update_us", "sensed_state_us"):
        if not result[key]:
            continue
        print(f"  {key}: median {result[key]['median']:.1f}, p99 {result[key]['p99']:.1f}")
    for method, stats in result["feedforward_us_by_method"].items():
        count = result["ticks_by_method"][method]
        print(f"  feed-forward, {method}: {count} ticks, median {stats['median']:.1f} us, p99 {stats['p99']:.1f} us")


if __name__ == "__main__":
    main()
