"""The kinematic-inertial estimator's cost per update, on the readings of a walk.

Records the simulated sensors' readings of ``--seconds`` of the robot's fig8 walk (driven on the simulator's truth),
then times :meth:`KinematicInertialEstimator.update` over them, and apart the Pinocchio kinematics it calls and the
estimator's own work (the kinematics' outputs replayed); for a robot whose feet's wrenches come from the joint
torques, also the legs' inverse dynamics (Pinocchio, part of the own work). Each is run in blocks of the whole
recording; a block's median per update is taken, and the least of the blocks is printed (JSON, microseconds): on a
shared machine the other blocks are those another process interrupted. ``compiled_us`` is the floor of the update's
compiled calls alone, with the least Python around them (Pinocchio's forward kinematics, COM, frame placements and
velocities; for joint torques also the inverse dynamics, the Jacobians and the two LAPACK solves); ``goal_us`` the
issue's goal for the whole update. ::

    python benchmarks/estimator.py --robot talos

``--updates N`` runs the first update and ``N`` more, untimed, for instructions counts, which the machine's load does
not change. The ``N`` updates are marked by a ``time.sleep(0)`` before and after them: with callgrind dumping its
counts before each, the second dump (``cg.2``) counts them alone, its ``summary`` line / ``N`` the instructions per
update::

    PYTHONHASHSEED=0 OPENBLAS_NUM_THREADS=1 valgrind --tool=callgrind --dump-before=time_sleep \
        --callgrind-out-file=cg python benchmarks/estimator.py --robot g1 --updates 1000

(``PYTHONHASHSEED=0``: the strings' hashes, random otherwise, change the count a little). The whole run's count, the
recording and the imports included, moves by tens of millions of instructions from run to run (the difference of an
``--updates 1000`` and an ``--updates 0`` run by up to 70,000 an update); the marked updates' count repeats within
0.2 %.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import numpy as np
import pinocchio as pin
from scipy.linalg.lapack import dgesv

from rtgait.io.sim_run import _controller, robot_and_scenario_options
from rtgait.robot.model import RobotModel
from rtgait.robot.motion import robot_scenario
from rtgait.scenario import load_scenario
from rtgait.sim.config import SimConfig
from rtgait.sim.loop import ClosedLoop, LoopOptions
from rtgait.sim.model import build_sim_model
from rtgait.stack.estimators import kinematic_inertial_estimator
from rtgait.stack.setup import start_pose


def record(robot_name: str, seconds: float) -> tuple[list, object, object]:
    """The readings of the walk's first ``seconds`` (walk clock) and the estimator for them."""
    robot = RobotModel.load(robot_name)
    sim = build_sim_model(robot, SimConfig(meshes=False))
    scenario = load_scenario("fig8")
    walk = robot_scenario(scenario, robot)
    level, changes, stop_after = _controller(walk, None, "adaptive", sim, robot_and_scenario_options(robot, scenario))
    # On the truth: the loop then reads no sensor, and each tick's readings are read here once.
    loop = ClosedLoop(sim, level, LoopOptions(changes=changes, stop_after_steps=stop_after, state="truth"))
    _, left, right = start_pose(level.planner)
    readings = []
    while loop.step() and not loop.done:
        t = loop.time_of(loop.k)
        if loop.k >= loop.k0:
            reading = loop.robot.read()
            readings.append(reading._replace(t=reading.t - (loop.data.time - t)))
        if t > seconds:
            break
    estimator = kinematic_inertial_estimator(robot, level.planner.w, start_feet=(tuple(left), tuple(right)))
    return readings, estimator, robot


def blocks(run, items: list, repeats: int) -> float:
    """The least over ``repeats`` blocks of the median time of ``run(item)`` over ``items`` (us)."""
    best = float("inf")
    clock = time.perf_counter
    for _ in range(repeats):
        times = []
        for item in items:
            start = clock()
            run(item)
            times.append(clock() - start)
        best = min(best, statistics.median(times))
    return best * 1e6


GOAL_US = 20.0
"""The goal for one update (us, median)."""


def compiled_calls(kinematics, torques: bool):
    """One update's compiled calls alone (see the module docstring), as a function of the readings."""
    model, data, q, v = kinematics.model, kinematics.data, kinematics._q, kinematics._v
    frames = [frame for frame in kinematics._frames if frame >= 0]
    soles, legs = kinematics._soles, kinematics._leg_columns
    accelerations, rhs, world = np.zeros(model.nv), np.ones(len(kinematics.leg_joints[0])), pin.LOCAL_WORLD_ALIGNED

    def run(r) -> None:
        q[7:] = r.joint_positions
        v[6:] = r.joint_velocities
        pin.centerOfMass(model, data, q, v, False)
        for frame in frames:
            pin.updateFramePlacement(model, data, frame)
            pin.getFrameVelocity(model, data, frame, world)
        if torques:
            pin.rnea(model, data, q, v, accelerations)
            pin.computeJointJacobians(model, data)
            for sole, columns in zip(soles, legs, strict=True):
                dgesv(pin.getFrameJacobian(model, data, sole, pin.LOCAL)[:, columns].T, rhs)

    return run


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="talos", help="built-in robot (default talos)")
    parser.add_argument("--seconds", type=float, default=3.0, help="walk recorded, s (default 3)")
    parser.add_argument("--repeats", type=int, default=10, help="blocks timed (default 10)")
    parser.add_argument("--updates", type=int, default=None,
                        help="only the first update and this many more, untimed (instruction counts)")  # fmt: skip
    args = parser.parse_args()
    readings, estimator, _ = record(args.robot, args.seconds)
    if args.updates is not None:
        if not 0 <= args.updates < len(readings):
            parser.error(f"--updates must be within 0..{len(readings) - 1} (the readings recorded), got {args.updates}")
        estimator.update(readings[0])
        time.sleep(0)  # the markers of the updates counted (module docstring)
        for reading in readings[1 : args.updates + 1]:
            estimator.update(reading)
        time.sleep(0)
        print(json.dumps({"robot": args.robot, "updates": args.updates}))
        return
    kinematics = estimator.kinematics
    outputs = [kinematics.update(r.joint_positions, r.joint_velocities) for r in readings]

    def update(reading):
        return estimator.update(reading)

    whole = blocks(update, readings, args.repeats)
    alone = blocks(lambda r: kinematics.update(r.joint_positions, r.joint_velocities), readings, args.repeats)
    legs = {}
    if estimator.wrenches == "torques":
        upright, accelerations = (0.0, 0.0, 9.81, 0.0, 0.0, 0.0), np.zeros(kinematics.joint_count)

        def with_legs(r):
            kinematics.update(r.joint_positions, r.joint_velocities)
            kinematics.leg_dynamics((0.0, 0.0, 0.0), upright, accelerations)

        legs["leg_dynamics_us"] = round(blocks(with_legs, readings, args.repeats) - alone, 2)
    compiled = blocks(compiled_calls(kinematics, estimator.wrenches == "torques"), readings, args.repeats)
    # The estimator's own work: the kinematics' outputs of the same readings handed back without computing them.
    replay = iter(())
    estimator._kinematics_update = lambda q, v: next(replay)
    own = float("inf")
    for _ in range(args.repeats):
        replay = iter(outputs)
        estimator.reset()
        own = min(own, blocks(update, readings, 1))
    print(json.dumps({
        "robot": args.robot, "updates": len(readings), "wrenches": estimator.wrenches,
        "update_us": round(whole, 2), "kinematics_us": round(alone, 2), "own_us": round(own, 2), **legs,
        "compiled_us": round(compiled, 2), "goal_us": GOAL_US,
    }))  # fmt: skip


if __name__ == "__main__":
    main()
