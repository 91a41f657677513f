"""The kinematic-inertial estimator's errors against the simulator's truth on a whole walk.

The walk is driven by the ground-truth estimator (``state="truth"``, so that every estimator setting sees the same
walk); each tick the kinematic-inertial estimator updates from the simulated sensors' readings in the shadow, and
its state is compared with the ground-truth estimator's of the same instant. Prints JSON: RMS errors of the COM
(absolute, and relative to the more loaded sole), of the COM velocity and the DCM, the largest DCM error, the RMS error
of the measured ZMP (over the ticks both have one), the share of ticks whose feet's contact states agree, and each
true landing's delay until the estimate's: the landings of steps (the foot in the air for at least
``RELANDING_AIR_TIME`` before), and apart the re-landings after a bounce (a foot that touched, left the ground for at
least the load detection's 50 ms, and came down again), which an estimate may see as part of the step's landing. ::

    python benchmarks/estimation_errors.py --robot talos --noise 1
"""

from __future__ import annotations

import argparse
import json
import math

import numpy as np

from rtgait.estimation.ground_truth import GroundTruthEstimator
from rtgait.io.sim_run import _controller, robot_and_scenario_options
from rtgait.robot.model import RobotModel
from rtgait.robot.motion import robot_scenario
from rtgait.scenario import load_scenario
from rtgait.sim.config import SensorSettings, SimConfig
from rtgait.sim.loop import ClosedLoop, LoopOptions
from rtgait.sim.model import build_sim_model
from rtgait.stack.estimators import kinematic_inertial_estimator
from rtgait.stack.setup import start_pose

RELANDING_AIR_TIME = 0.2
"""A true landing after less time than this in the air (s) is a re-landing after a bounce, not a step's."""


def shadow(robot_name: str, scenario_name: str, noise: float, seed: int, **settings: object) -> list:
    """Each tick's pair (estimate, truth) of the walk (module docstring)."""
    robot = RobotModel.load(robot_name)
    sim = build_sim_model(robot, SimConfig(meshes=False, sensors=SensorSettings(noise=noise, seed=seed)))
    scenario = load_scenario(scenario_name)
    walk = robot_scenario(scenario, robot)
    level, changes, stop_after = _controller(walk, None, "adaptive", sim, robot_and_scenario_options(robot, scenario))
    loop = ClosedLoop(sim, level, LoopOptions(changes=changes, stop_after_steps=stop_after))
    _, left, right = start_pose(level.planner)
    estimator = kinematic_inertial_estimator(
        robot, level.planner.w, start_feet=(tuple(left), tuple(right)), **settings
    )  # fmt: skip
    truth = GroundTruthEstimator(level.planner.w, robot.mass * float(-sim.model.opt.gravity[2]))
    pairs = []
    while loop.step() and not loop.done:
        if loop.k < loop.k0:
            continue
        t = loop.time_of(loop.k)
        readings = loop.robot.read()
        readings = readings._replace(t=readings.t - (loop.data.time - t))
        pairs.append((estimator.update(readings), truth.update(None, loop.robot.ground_truth(t))))
    return pairs


def errors(pairs: list) -> dict:
    """The errors of module docstring (mm, mm/s, per cent, ms)."""

    def rms(values: list) -> float:
        return float(np.sqrt(np.mean(np.sum(np.square(values), axis=1))))

    com, relative, velocity, dcm, zmp = [], [], [], [], []
    for m, g in pairs:
        if np.all(np.isfinite(m.zmp)) and np.all(np.isfinite(g.zmp)):
            zmp.append(np.subtract(m.zmp, g.zmp))
        i = 0 if g.left.normal_force >= g.right.normal_force else 1
        estimated, true = (m.left, m.right)[i], (g.left, g.right)[i]
        com.append(np.subtract(m.com, g.com))
        relative.append(np.subtract(m.com, estimated.pose[:3]) - np.subtract(g.com, true.pose[:3]))
        velocity.append(np.subtract(m.com_vel, g.com_vel))
        dcm.append(np.subtract(m.dcm, g.dcm))
    agree = np.mean([m.left.loaded == g.left.loaded and m.right.loaded == g.right.loaded for m, g in pairs])
    seen = [(landing.t, landing.side) for m, _ in pairs for landing in m.landings]
    delays, relandings = [], []
    for landing, air in true_landings(pairs):
        after = [t - landing.t for t, side in seen if side == landing.side and -0.05 < t - landing.t < 0.3]
        (delays if air >= RELANDING_AIR_TIME else relandings).append(
            round(1e3 * min(after, key=abs), 1) if after else math.inf
        )
    return {
        "com_mm": round(1e3 * rms(com), 2), "com_relative_mm": round(1e3 * rms(relative), 2),
        "com_velocity_mm_s": round(1e3 * rms(velocity), 1), "dcm_mm": round(1e3 * rms(dcm), 2),
        "dcm_max_mm": round(1e3 * float(np.max(np.linalg.norm(dcm, axis=1))), 1), "zmp_mm": round(1e3 * rms(zmp), 1),
        "contact_agree_percent": round(100.0 * float(agree), 2), "landing_delays_ms": delays,
        "relanding_delays_ms": relandings,
    }  # fmt: skip


def true_landings(pairs: list) -> list:
    """Each landing of the truth with the time its foot was in the air before it (s)."""
    out, last_loaded = [], {"left": -math.inf, "right": -math.inf}
    for _, g in pairs:
        for landing in g.landings:
            out.append((landing, landing.t - last_loaded[landing.side]))
        for side, foot in (("left", g.left), ("right", g.right)):
            if foot.loaded and not any(landing.side == side for landing in g.landings):
                last_loaded[side] = g.t
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="talos", help="built-in robot (default talos)")
    parser.add_argument("--scenario", default="fig8", help="built-in scenario (default fig8)")
    parser.add_argument("--noise", type=float, default=1.0, help="factor on the sensors' noise (default 1; 0: none)")
    parser.add_argument("--seed", type=int, default=0, help="the sensors' seed (default 0)")
    parser.add_argument("--yaw", choices=("feet", "imu"), default="feet", help="the base's yaw source")
    parser.add_argument("--velocity-cutoff", type=float, default=3.5, help="velocity filter cut-off, Hz (inf: none)")
    args = parser.parse_args()
    pairs = shadow(
        args.robot, args.scenario, args.noise, args.seed, yaw=args.yaw, velocity_cutoff=args.velocity_cutoff
    )  # fmt: skip
    print(json.dumps({"robot": args.robot, "scenario": args.scenario, "noise": args.noise, **errors(pairs)}))


if __name__ == "__main__":
    main()
