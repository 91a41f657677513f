"""Which part of the estimated state costs a walk its push margin: the walk of ``benchmarks/pushes.py --phase single``
with the controller on the estimate, one part of which is replaced by the simulator's truth (run on demand).

* ``--part feet``: the COM, its velocity and the DCM estimated, the feet (wrenches, loads, landings, poses) and the ZMP
  the truth's: what the COM and DCM estimate costs;
* ``--part com``: the COM, its velocity and the DCM the truth's, the feet and the ZMP estimated: what the contact
  estimate costs;
* ``--part none``: the estimate as it is (``--state estimated``); ``--part all``: the truth (``--state truth``).

Each impulse of ``--impulses`` (N s, along ``--direction`` degrees in the world) is one walk; the answer is whether it
survived (no fall, at rest at the end). Survival near a threshold is not monotonic in the impulse, hence a scan rather
than a bisection. Without ``--impulses``, fig8 unpushed, at ``--noise`` times the sensors' noise with ``--latency``
control periods (default the description's: noise x1, seed 0). The estimator is updated from the sensors each tick
beside the ground-truth estimator (with a latency, the estimated part is late, the truth's is not).

The MuJoCo loop builds its estimator by name (:func:`rtgait.stack.estimators.make_estimator`); this script swaps in
the composed one and reads the sensors through the loop's robot, which is why it patches the loop module's names.

Usage: ``python benchmarks/estimate_attribution.py --robot R --part feet|com|none|all [--direction DEG]
[--impulses 20,30,40] [--noise F] [--latency L]``
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))  # benchmarks/pushes.py, for the push site

PARTS = ("feet", "com", "none", "all")


class ComposedEstimator:
    """The kinematic-inertial estimate with one part replaced by the ground-truth estimator's (module docstring)."""

    reads_truth = True  # the loop hands it the truth; it reads the sensors itself through ``robot``

    def __init__(self, estimated: Any, truth: Any, part: str, robot: dict[str, Any]) -> None:
        self.estimated, self.truth, self.part, self._robot = estimated, truth, part, robot

    def reset(self) -> None:
        self.estimated.reset()
        self.truth.reset()

    def update(self, readings: Any, truth: Any) -> Any:
        sensed = self._robot["robot"].read()
        m = self.estimated.update(sensed._replace(t=truth.t), None)
        g = self.truth.update(None, truth)
        if self.part == "feet":
            return m._replace(zmp=g.zmp, normal_force=g.normal_force, left=g.left, right=g.right, landings=g.landings)
        return g._replace(zmp=m.zmp, normal_force=m.normal_force, left=m.left, right=m.right, landings=m.landings)


def install(part: str) -> None:
    """Make the MuJoCo loop build :class:`ComposedEstimator` for ``part`` (``feet`` or ``com``)."""
    import rtgait.sim.loop as loop
    import rtgait.sim.loop_stack as loop_stack
    from rtgait.stack.estimators import make_estimator

    robot: dict[str, Any] = {}
    sim_robot = loop.SimRobot

    def keep(*args: Any, **kwargs: Any) -> Any:
        robot["robot"] = made = sim_robot(*args, **kwargs)
        return made

    def composed(state: str, model: Any, omega: float, **kwargs: Any) -> Any:
        estimated = make_estimator("estimated", model, omega, **kwargs)
        return ComposedEstimator(estimated, make_estimator("truth", model, omega, **kwargs), part, robot)

    loop.SimRobot = keep
    loop_stack.make_estimator = composed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="talos", help="built-in robot (default talos)")
    parser.add_argument("--part", choices=PARTS, required=True, help="the part taken from the truth")
    parser.add_argument("--direction", type=float, default=0.0, help="push direction, deg in the world (default 0)")
    parser.add_argument("--impulses", help="comma-separated impulses, N s (default: none, the walk unpushed)")
    parser.add_argument("--noise", type=float, default=1.0, help="sensor noise factor (default 1)")
    parser.add_argument("--latency", type=int, help="sensor latency, control periods (default the description's)")
    args = parser.parse_args()
    impulses: list[float | None] = [None]
    if args.impulses is not None:
        try:
            impulses = [float(value) for value in args.impulses.split(",")]
        except ValueError:
            parser.error(f"--impulses must be comma-separated numbers, got {args.impulses!r}")
        if not all(value is not None and math.isfinite(value) and value > 0.0 for value in impulses):
            parser.error(f"--impulses must be > 0 N s, got {args.impulses!r}")
    if not (math.isfinite(args.noise) and args.noise >= 0.0) or (args.latency is not None and args.latency < 0):
        parser.error("--noise must be a factor >= 0 and --latency whole periods >= 0")

    import pushes

    from rtgait.core.push import Push
    from rtgait.io.sim_run import mujoco_messages, simulate
    from rtgait.robot.model import RobotModel
    from rtgait.scenario.loading import load_scenario
    from rtgait.sim.config import SensorSettings
    from rtgait.sim.loop_options import LoopOptions
    from rtgait.sim.model import SimConfig, build_sim_model

    if args.part in ("feet", "com"):
        install(args.part)
    robot, scenario = RobotModel.load(args.robot), load_scenario("fig8")
    sensors = SensorSettings(noise=args.noise, latency=args.latency)
    sim = build_sim_model(robot, SimConfig(meshes=False, sensors=sensors))
    start = pushes.push_site(scenario, robot, "single").start
    u = (math.cos(math.radians(args.direction)), math.sin(math.radians(args.direction)))
    options = LoopOptions(state="truth" if args.part == "all" else "estimated")
    outcomes = []
    for impulse in impulses:
        push = None
        if impulse is not None:
            force = impulse / pushes.PUSH_DURATION
            push = Push(start, pushes.PUSH_DURATION, (force * u[0], force * u[1], 0.0))
        with mujoco_messages():
            result = simulate(scenario, robot, sim=sim, controller="adaptive", push=push, options=options)
        outcome = "walks" if not result.fell and result.ended_at_rest else "does not end at rest"
        if result.fell:
            outcome = f"falls at {result.fall_time:.1f} s"
        outcomes.append(outcome if impulse is None else f"{impulse:g} N s {outcome}")
        print(outcomes[-1], flush=True)
    print(f"{args.robot}, noise x{args.noise:g}, latency {args.latency}, {args.direction:g} deg, the {args.part} part "
          f"from the truth: {', '.join(outcomes)}")  # fmt: skip


if __name__ == "__main__":
    main()
