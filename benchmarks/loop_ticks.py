"""Ticks of the MuJoCo closed loop for instruction counts: a deterministic measure of a control tick's cost.

Builds Talos's fig8 walk with the adaptive controller (on ``--state``, default the estimate; the drives at ``--gains``
and ``--drive``, default the stiff position servos), runs the 1.5 s start transition and 0.1 s of walking, then
``--ticks`` more ticks, and prints JSON (the ticks run and the walk's time).
Wall times on a shared machine vary by tens of per cent; instructions do not. Run it twice under callgrind and take
the difference::

    valgrind --tool=callgrind --callgrind-out-file=/dev/null python benchmarks/loop_ticks.py --ticks 0
    valgrind --tool=callgrind --callgrind-out-file=/dev/null python benchmarks/loop_ticks.py --ticks 1000

(instructions per tick = the difference of the two ``Collected`` totals / 1000; with ``PYTHONHASHSEED=0``, as the
strings' random hashes move the count by about 10,000).
"""

from __future__ import annotations

import argparse
import json

from rtgait.control.controller import make_controller
from rtgait.estimation.estimator import DEFAULT_STATE, STATE_SOURCES
from rtgait.interface.command import GAIN_SETS
from rtgait.robot.controller_info import robot_info
from rtgait.robot.description import load_robot
from rtgait.robot.model import RobotModel
from rtgait.robot.motion import robot_scenario
from rtgait.scenario import load_scenario
from rtgait.sim.config import SimConfig
from rtgait.sim.loop import ClosedLoop, LoopOptions
from rtgait.sim.model import build_sim_model

WARM_UP_TICKS = 1600
"""The start transition (1.5 s at 1 ms) and the walk's first 0.1 s, run before the ticks counted."""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=1000, help="ticks after the warm-up (default 1000)")
    parser.add_argument("--state", choices=STATE_SOURCES, default=DEFAULT_STATE,
                        help=f"what the controller acts on (default {DEFAULT_STATE})")  # fmt: skip
    parser.add_argument("--gains", choices=GAIN_SETS, default="stiff",
                        help="the drives' gains: stiff (default) or robot, with feed-forward torques")  # fmt: skip
    parser.add_argument("--drive", choices=("position", "torque"), default="position",
                        help="position (default) or torque: a tenth of the robot's gains, with FF torques")  # fmt: skip
    args = parser.parse_args()
    if not 0 <= args.ticks <= 10000:
        parser.error(f"--ticks must be within 0..10000 (the walk lasts about 13,000 ticks), got {args.ticks}")
    robot = RobotModel.load(load_robot("talos"))
    sim = build_sim_model(robot, SimConfig(gains=args.gains))
    walk = robot_scenario(load_scenario("fig8"), robot)
    info = robot_info(robot, gains=args.gains)
    controller = make_controller("adaptive", walk.planner_config(), walk.strides(), walk.sole, info, dt=sim.control_dt)
    loop = ClosedLoop(sim, controller, LoopOptions(state=args.state, drive=args.drive))
    for _ in range(WARM_UP_TICKS + args.ticks):
        loop.step()
    print(json.dumps({"ticks": args.ticks, "warm_up_ticks": WARM_UP_TICKS, "walk_time_s": loop.t,
                      "state": args.state, "gains": args.gains, "drive": args.drive}))  # fmt: skip


if __name__ == "__main__":
    main()
