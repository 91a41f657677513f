"""The estimated state in closed loop: its errors against the simulator's truth, per robot and walk, and how the walks
degrade as the sensors get noisier and later (run on demand).

Every walk here is the adaptive controller acting on the state the kinematic-inertial estimator makes from the
simulated sensors (``state="estimated"``), each robot at its own physics step; the errors are ``summary.json``'s
``estimation`` (:mod:`rtgait.sim.estimation_errors`: RMS over the walk's ticks of the COM, the COM relative to the
stance sole, the COM velocity, the DCM and the DCM relative to the stance sole, the ZMP; the largest DCM error; the
share of ticks whose feet's load states are right, and of foot-ticks wrongly loaded (f.on) and wrongly unloaded
(f.off); the step landings missed, their detection delay's median, 95th percentile and worst, apart from the
re-landings of a foot that bounced; the worst step lift-off's delay).

* **Walks**: fig8 and, with ``--velocity-walks``, the walks by velocity command of ``benchmarks/sim.py --walks
  --velocity-walks`` (0.3 m/s forward, 0.1 m/s backward, 0.1 m/s sideways, 0.3 rad/s turning, and one changing
  between them), ``--walk-time`` seconds each (default 60; ``--quick``: 20), at the robot description's sensors
  (noise x1, its latency, seed 0).
* **Degradation**: fig8 at every sensor noise factor of ``--noise`` (default 0, 1, 2, 4: a factor on every noise,
  bias and offset of the description) and every latency of ``--latency`` (default 0 to 3 control periods): walked
  or not (no fall, every step landed, ended at rest), and the errors.

The runs are spread over ``--workers`` processes (default 2) with a progress bar on stderr; the result is a table,
or with ``--json`` one JSON document.

``--model-error SEED[,SEED...]`` adds a table of walks with a model error (:mod:`rtgait.sim.model_error`: the
simulated robot's masses, centres of mass and joint zeros drawn off its model from each seed): fig6, fig7, fig8 and,
with ``--velocity-walks``, the walks by command, each robot and seed, on the estimate (sensors as described) and, with
``--truth``, on the simulator's truth too; walked or not, the fall's time and the errors.

``--shadow`` measures the estimator alone instead, as a tuning bench: fig8 walked on the simulator's truth (the same
walk for every estimator setting) with the estimator updated in the shadow from the sensors each tick, with
``--yaw feet|imu`` (default the description's ``yaw_source``) and ``--velocity-cutoff HZ``; the same errors, at
``--noise`` (its first value) and ``--seed``, and at the physics step ``--physics-dt`` (default the robot's).
With ``--push IMPULSE`` (N s) the walk on the truth is pushed as ``benchmarks/pushes.py --phase single`` pushes it
(0.1 s on the base at mid single support of the middle step, along ``--push-direction`` degrees in the world,
default 0: forward in fig8's middle step), and the report adds the errors over the push window, from the push's start
to :data:`PUSH_WINDOW` after: the DCM's and the COM velocity's RMS and largest error, the DCM estimate's delay (the
shift of the true DCM that fits the estimate best, :func:`best_delay`) and the ticks at which the estimate has a foot
loaded that the truth has in the air (false contacts, which the controller may take for a landing).

Usage: ``python benchmarks/estimation.py [--robot R ...] [--velocity-walks] [--quick] [--walk-time S]
[--noise F ...] [--latency L ...] [--no-degradation] [--model-error SEEDS] [--truth] [--workers N] [--json]``
or ``python benchmarks/estimation.py --shadow [--robot R] [--scenario fig8] [--noise F] [--seed N]
[--yaw feet|imu] [--velocity-cutoff HZ] [--physics-dt S] [--push N_S [--push-direction DEG]]``
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))  # benchmarks/sim.py, for its walks

NOISE = (0.0, 1.0, 2.0, 4.0)
"""The sensor noise factors of the degradation table."""
LATENCY = (0, 1, 2, 3)
"""Its latencies (control periods)."""
PUSH_WINDOW = 0.6
"""The push window of ``--shadow --push`` (s from the push's start): the push (0.1 s), the swing it cuts short and the
landing after it."""
MAX_DELAY = 0.05
"""The largest delay :func:`best_delay` looks for (s)."""


SCENARIOS = ("fig6", "fig7", "fig8")
"""The scenarios walked as planned (the other walks are by velocity command, on fig8's timing)."""


def _job(
    robot: str,
    walk: str,
    seconds: float,
    noise: float = 1.0,
    latency: int | None = None,
    model_error: int | None = None,
    state: str = "estimated",
) -> dict[str, Any]:
    """A walk of ``benchmarks/sim.py``'s :func:`walk_case`, on the estimate (or ``state``), at these sensor settings
    and with this model error seed."""
    velocity = None if walk in SCENARIOS else walk
    sim_options: dict[str, Any] = {"sensors": {"noise": noise, "latency": latency, "seed": 0}}
    if model_error is not None:
        sim_options["model_error"] = model_error
    return {"robot": robot, "scenario": walk if velocity is None else "fig8", "controller": "adaptive",
            "velocity": velocity, "seconds": seconds, "physics_dt": None, "options": {}, "sim_options": sim_options,
            "state": state, "model_error": model_error}  # fmt: skip


def _row(case: dict[str, Any], job: dict[str, Any]) -> dict[str, Any]:
    """The fields reported of one walk."""
    estimation = case["estimation"] or {}
    return {
        "robot": case["robot"],
        "walk": case["walk"],
        "state": job["state"],
        "model_error": job["model_error"],
        "noise": case["sensors"]["noise"],
        "latency": case["sensors"]["latency"],
        "walked": case["walked"],
        "fell": case["fell"],
        "fall_time": case["fall_time"],
        "steps": f"{case['steps_completed']}/{case['steps_planned']}",
        "zmp_vs_plan_rms": case["zmp_vs_plan_rms"],
        "real_time_factor": case["real_time_factor"],
        **estimation,
    }


def run(args: argparse.Namespace) -> dict[str, Any]:
    """Every walk of the benchmark (module docstring), in worker processes with a progress bar."""
    from sim import VELOCITY_WALKS, walk_case
    from tqdm import tqdm

    seconds = args.walk_time if args.walk_time is not None else (20.0 if args.quick else 60.0)
    names = ["fig8"] + ([*VELOCITY_WALKS, "changes"] if args.velocity_walks else [])
    jobs = [("walks", _job(robot, walk, seconds)) for robot in args.robots for walk in names]
    if not args.no_degradation:
        jobs += [("degradation", _job(robot, "fig8", seconds, noise, latency))
                 for robot in args.robots for noise in args.noise for latency in args.latency]  # fmt: skip
    for seed in args.model_error or []:
        states = ("estimated", "truth") if args.truth else ("estimated",)
        jobs += [("model_error", _job(robot, walk, seconds, model_error=seed, state=state))
                 for robot in args.robots for walk in [*SCENARIOS, *names[1:]] for state in states]  # fmt: skip
    rows: dict[str, list[dict[str, Any]]] = {"walks": [], "degradation": [], "model_error": []}
    order = {id(job): i for i, (_, job) in enumerate(jobs)}
    done: list[tuple[int, str, dict[str, Any]]] = []
    with ProcessPoolExecutor(args.workers) as pool:
        futures = {pool.submit(walk_case, job): (table, job) for table, job in jobs}
        bar = tqdm(total=len(futures), desc="walks on the estimate", unit=" walk", disable=None, file=sys.stderr)
        for future in as_completed(futures):
            table, job = futures[future]
            done.append((order[id(job)], table, _row(future.result(), job)))
            bar.update(1)
        bar.close()
    for _, table, row in sorted(done, key=lambda item: item[0]):
        rows[table].append(row)
    return {"walk_time": seconds, **rows}


def _mm(value: float | None, scale: float = 1e3, digits: int = 1) -> str:
    return "-" if value is None or not math.isfinite(value) else f"{value * scale:.{digits}f}"


def _errors(row: dict[str, Any]) -> str:
    """The error columns of a row."""
    delay = row.get("landing_delay_worst")
    return (
        f"{_mm(row.get('com_rms'), digits=2):>6} {_mm(row.get('com_relative_rms'), digits=2):>6} "
        f"{_mm(row.get('com_velocity_rms')):>7} {_mm(row.get('dcm_rms'), digits=2):>6} {_mm(row.get('dcm_max')):>6} "
        f"{_mm(row.get('dcm_relative_rms'), digits=2):>6} {_mm(row.get('zmp_rms')):>6} "
        f"{_mm(row.get('contact_agreement'), 100.0, 2):>7} {_mm(row.get('contact_false_loaded'), 100.0, 2):>5} "
        f"{_mm(row.get('contact_false_unloaded'), 100.0, 2):>5} {row.get('landings_missed', '-')!s:>6} "
        f"{_mm(row.get('landing_delay_median'), digits=0):>4} {_mm(row.get('landing_delay_p95'), digits=0):>4} "
        f"{_mm(delay, digits=0):>5} {_mm(row.get('liftoff_delay_worst'), digits=0):>5}"
    )


HEADER = (f"{'COM':>6} {'rel.':>6} {'vel.':>7} {'DCM':>6} {'max':>6} {'rel.':>6} {'ZMP':>6} {'contact':>7} "
          f"{'f.on':>5} {'f.off':>5} {'missed':>6} {'med':>4} {'p95':>4} {'worst':>5} {'lift':>5}")  # fmt: skip
UNITS = (f"{'mm':>6} {'mm':>6} {'mm/s':>7} {'mm':>6} {'mm':>6} {'mm':>6} {'mm':>6} {'%':>7} {'%':>5} {'%':>5} "
         f"{'steps':>6} {'ms':>4} {'ms':>4} {'ms':>5} {'ms':>5}")  # fmt: skip


def print_tables(report: dict[str, Any]) -> None:
    """The walks, then the degradation table, as text."""

    def outcome(row: dict[str, Any]) -> str:
        if row["fell"]:
            return f"FELL at {row['fall_time']:.1f} s ({row['steps']})"
        return f"{'walked' if row['walked'] else 'stood'} {row['steps']}"

    if report["walks"]:
        print(f"walks on the estimate (walks by command: {report['walk_time']:g} s), sensors as described")
        print(f"{'robot':<6} {'walk':<18} {'outcome':<22} {HEADER}")
        print(f"{'':<6} {'':<18} {'':<22} {UNITS}")
        for row in report["walks"]:
            print(f"{row['robot']:<6} {row['walk']:<18} {outcome(row):<22} {_errors(row)}")
    if report["degradation"]:
        print("\nfig8 with noisier sensors (a factor on the description's noise and bias) and later ones (periods)")
        print(f"{'robot':<6} {'noise':>5} {'late':>4} {'outcome':<22} {HEADER}")
        print(f"{'':<6} {'':>5} {'':>4} {'':<22} {UNITS}")
        for row in report["degradation"]:
            print(f"{row['robot']:<6} {row['noise']:>5g} {row['latency']:>4} {outcome(row):<22} {_errors(row)}")
    if report.get("model_error"):
        print("\nwalks with a model error (seed), sensors as described")
        print(f"{'robot':<6} {'walk':<18} {'seed':>4} {'state':<9} {'outcome':<22} {'ZMP':>6} {HEADER}")
        print(f"{'':<6} {'':<18} {'':>4} {'':<9} {'':<22} {'mm':>6} {UNITS}")
        for row in report["model_error"]:
            zmp = _mm(row["zmp_vs_plan_rms"])
            print(f"{row['robot']:<6} {row['walk']:<18} {row['model_error']:>4} {row['state']:<9} "
                  f"{outcome(row):<22} {zmp:>6} {_errors(row)}")  # fmt: skip


# ----- the estimator alone, in the shadow of a walk on the truth ----------------------------------------------------
def best_delay(times: np.ndarray, estimate: np.ndarray, truth: np.ndarray, window: np.ndarray) -> float:
    """The delay ``d`` (s, ``0 <= d <= MAX_DELAY``, a whole number of ticks) that minimises the RMS of
    ``estimate(t) - truth(t - d)`` over the ticks of ``window`` (rows of ``(k, n)`` arrays at the ticks ``times``):
    how late the estimate follows the truth."""
    import numpy as np

    dt = float(np.median(np.diff(times)))
    rows = np.nonzero(window)[0]
    best, best_rms = 0.0, math.inf
    for lag in range(round(MAX_DELAY / dt) + 1):
        if rows[0] - lag < 0:
            break
        rms = float(np.sqrt(np.mean(np.sum((estimate[rows] - truth[rows - lag]) ** 2, axis=1))))
        if rms < best_rms:
            best, best_rms = lag * dt, rms
    return best


def push_errors(times: np.ndarray, estimate: Any, truth: Any, start: float) -> dict[str, Any]:
    """The errors over the push window from ``start`` (s) of the :class:`~rtgait.sim.estimation_errors.StateTrack`
    ``estimate`` against ``truth`` (whose ``loaded`` is set): DCM and COM velocity RMS and largest (m, m/s), the DCM's
    delay (s) and the ticks of false contacts."""
    import numpy as np

    window = (times >= start) & (times <= start + PUSH_WINDOW)
    dcm = np.linalg.norm(estimate.dcm[window] - truth.dcm[window], axis=1)
    velocity = np.linalg.norm(estimate.com_velocity[window, :2] - truth.com_velocity[window, :2], axis=1)
    false = estimate.loaded[window] & ~truth.loaded[window]
    return {
        "push_dcm_rms": float(np.sqrt(np.mean(dcm**2))), "push_dcm_max": float(dcm.max()),
        "push_com_velocity_rms": float(np.sqrt(np.mean(velocity**2))), "push_com_velocity_max": float(velocity.max()),
        "push_dcm_delay": best_delay(times, estimate.dcm, truth.dcm, window),
        "push_false_contact_ticks": int(false.any(axis=1).sum()),
        "push_first_false_contact": (float(times[window][false.any(axis=1)][0] - start) if false.any() else None),
    }  # fmt: skip


def shadow(
    robot_name: str, scenario_name: str, noise: float, seed: int, push: tuple[float, float] | None = None,
    physics_dt: float | None = None, **settings: object,
) -> dict[str, Any]:  # fmt: skip
    """The errors of the estimator with ``settings`` (:class:`~rtgait.estimation.kinematic_inertial.
    KinematicInertialEstimator`'s) updated each tick from the sensors of a walk driven on the truth (module
    docstring), against the ground-truth estimator's state of the same instant; ``push``: ``(impulse, direction)``
    (N s, deg) of a push at mid single support of the middle step, and the push window's errors; ``physics_dt``: the
    physics step (s; ``None``: the robot's)."""
    import numpy as np
    from pushes import PUSH_DURATION, push_site

    from rtgait.core.push import Push
    from rtgait.estimation.ground_truth import GroundTruthEstimator
    from rtgait.estimation.torque_landing import torque_landing_force
    from rtgait.io.sim_run import _controller, robot_and_scenario_options
    from rtgait.robot.model import RobotModel
    from rtgait.robot.motion import robot_scenario
    from rtgait.scenario import load_scenario
    from rtgait.sim.config import SensorSettings, SimConfig
    from rtgait.sim.estimation_errors import StateTrack, estimation_errors
    from rtgait.sim.loop import ClosedLoop, LoopOptions
    from rtgait.sim.model import build_sim_model
    from rtgait.stack.estimators import kinematic_inertial_estimator
    from rtgait.stack.setup import start_pose

    robot = RobotModel.load(robot_name)
    config = SimConfig(meshes=False, physics_dt=physics_dt, sensors=SensorSettings(noise=noise, seed=seed))
    sim = build_sim_model(robot, config)
    scenario = load_scenario(scenario_name)
    walk = robot_scenario(scenario, robot)
    level, changes, stop_after = _controller(walk, None, "adaptive", sim, robot_and_scenario_options(robot, scenario))
    # On the truth: the loop reads no sensor, so each tick's readings are read here once.
    pushes: tuple[Push, ...] = ()
    if push is not None:
        start = push_site(scenario, robot, "single").start
        force = push[0] / PUSH_DURATION
        direction = math.radians(push[1])
        pushes = (Push(start, PUSH_DURATION, (force * math.cos(direction), force * math.sin(direction), 0.0)),)
    options = LoopOptions(changes=changes, stop_after_steps=stop_after, state="truth", pushes=pushes)
    loop = ClosedLoop(sim, level, options)
    _, left, right = start_pose(level.planner)
    weight = robot.mass * float(-sim.model.opt.gravity[2])
    if noise > 1.0 and robot.description.sensors.feet is None and "landing_force" not in settings:
        # As the closed loop's estimator (rtgait.stack.estimators.make_estimator): the landing force from joint
        # torques scaled with the sensors' noise.
        settings = {**settings, "landing_force": torque_landing_force(weight, noise)}
    estimator = kinematic_inertial_estimator(
        robot, level.planner.w, start_feet=(tuple(left), tuple(right)), **settings
    )  # fmt: skip
    truth = GroundTruthEstimator(level.planner.w, weight)
    times, pairs = [], []
    while loop.step() and not loop.done:
        if loop.k < loop.k0:
            continue
        t = loop.time_of(loop.k)
        readings = loop.robot.read()
        readings = readings._replace(t=readings.t - (loop.data.time - t))
        pairs.append((estimator.update(readings), truth.update(None, loop.robot.ground_truth(t))))
        times.append(t)

    def track(side: int) -> StateTrack:
        states = [pair[side] for pair in pairs]
        return StateTrack(
            com=np.array([m.com for m in states]),
            com_velocity=np.array([m.com_vel for m in states]),
            dcm=np.array([m.dcm for m in states]),
            soles=np.array([[m.left.pose[:3], m.right.pose[:3]] for m in states]),
            normal_force=np.array([[m.left.normal_force, m.right.normal_force] for m in states]),
            loaded=np.array([[m.left.loaded, m.right.loaded] for m in states]),
            zmp=np.array([m.zmp for m in states]),
        )

    at = np.array(times)
    errors = estimation_errors(at, track(0), track(1), weight)
    report = {"robot": robot_name, "scenario": scenario_name, "noise": noise, "seed": seed, **settings,
              "fell": loop.fell, **errors.summary(), "landing_delays": list(errors.landing_delays)}  # fmt: skip
    if push is not None:
        report |= {"push_impulse": push[0], "push_direction": push[1], "push_start": pushes[0].start,
                   **push_errors(at, track(0), track(1), pushes[0].start)}  # fmt: skip
    return report


def _seeds(text: str) -> list[int]:
    """``--model-error``'s comma-separated seeds (integers >= 0)."""
    try:
        seeds = [int(part) for part in text.split(",")]
    except ValueError:
        seeds = [-1]
    if any(seed < 0 for seed in seeds):
        raise argparse.ArgumentTypeError(f"seeds must be integers >= 0 separated by commas, got {text!r}")
    return seeds


def main() -> None:
    from rtgait.interface.sensor_spec import YAW_SOURCES

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", action="append", dest="robots", help="robot(s) (default talos and g1)")
    parser.add_argument("--velocity-walks", action="store_true", help="the walks by velocity command too")
    parser.add_argument("--quick", action="store_true", help="walks by command of 20 s instead of 60")
    parser.add_argument("--walk-time", type=float, help="length of a walk by command (s)")
    parser.add_argument("--noise", type=float, action="append", help=f"noise factor(s) (default {NOISE})")
    parser.add_argument("--latency", type=int, action="append", help=f"latency(ies), periods (default {LATENCY})")
    parser.add_argument("--no-degradation", action="store_true", help="the walks only")
    parser.add_argument(
        "--model-error",
        type=_seeds,
        metavar="SEED[,SEED...]",
        help="a table of fig6, fig7, fig8 (and the walks by command) with each model error seed",
    )
    parser.add_argument("--truth", action="store_true", help="--model-error: on the simulator's truth too")
    parser.add_argument("--workers", type=int, default=2, help="worker processes (default 2)")
    parser.add_argument("--json", action="store_true", help="print one JSON document")
    parser.add_argument("--shadow", action="store_true", help="the estimator alone, beside a walk on the truth")
    parser.add_argument("--scenario", default="fig8", help="--shadow: built-in scenario (default fig8)")
    parser.add_argument("--seed", type=int, default=0, help="--shadow: the sensors' seed (default 0)")
    parser.add_argument("--yaw", choices=YAW_SOURCES, default=None,
                        help="--shadow: the base's yaw source (default: the description's yaw_source)")  # fmt: skip
    parser.add_argument("--velocity-cutoff", type=float, default=3.5, help="--shadow: velocity filter cut-off, Hz")
    parser.add_argument("--no-rocking", action="store_true", help="--shadow: hold the sole origins still, not the CoPs")
    parser.add_argument("--physics-dt", type=float, help="--shadow: the physics step, s (default the robot's)")
    parser.add_argument("--push", type=float, help="--shadow: a push at mid single support of the middle step, N s")
    parser.add_argument("--push-direction", type=float, default=0.0, help="--shadow: its direction, deg (default 0)")
    args = parser.parse_args()
    args.robots = args.robots or ["talos", "g1"]
    args.noise = args.noise or list(NOISE)
    args.latency = args.latency or list(LATENCY)
    if any(not (math.isfinite(n) and n >= 0.0) for n in args.noise) or any(n < 0 for n in args.latency):
        parser.error("--noise must be finite factors >= 0 and --latency whole periods >= 0")
    if args.shadow:
        if args.push is not None and not (math.isfinite(args.push) and args.push > 0.0):
            parser.error(f"--push must be an impulse > 0 N s, got {args.push}")
        push = None if args.push is None else (args.push, args.push_direction)
        settings = {} if args.yaw is None else {"yaw": args.yaw}
        report = shadow(args.robots[0], args.scenario, args.noise[0], args.seed, push, args.physics_dt, **settings,
                        velocity_cutoff=args.velocity_cutoff, rocking=not args.no_rocking)  # fmt: skip
        if args.physics_dt is not None:
            report["physics_dt"] = args.physics_dt
        print(json.dumps(report))
        return
    began = time.perf_counter()
    report = run(args)
    report["seconds"] = time.perf_counter() - began
    if args.json:
        print(json.dumps(report))
        return
    print_tables(report)
    print(f"({report['seconds']:.0f} s on {args.workers} workers)")


if __name__ == "__main__":
    main()
