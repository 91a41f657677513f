"""Speed of the closed loop in physics: planner + whole-body IK + MuJoCo (run on demand, not in tests).

Walks a built-in scenario (fig8 by default) with the robot in MuJoCo via :func:`rtgait.io.sim_run.simulate` a few
times and reports the real-time factor (simulated seconds per wall-clock second) and the wall time per control
tick; then times the parts of one tick separately on the same walk: the planner's sample, the IK solve, one
``mj_step`` (with the IK's joint references replayed; a tick takes ``control_dt / physics_dt`` of them), the
contact measurement, and ``mj_step`` again without the no-slip solver and without the leg collision boxes, to
show what each costs; then, inside one more run of the walk, the mean time per tick of each part of the real
loop (``in_loop_*_us``: IK, physics, controller, measurement, feed-forward torques, contact record, complete log,
servos, walk inputs and the loop's own ``rest``), which is what the real-time factor pays: each part there runs with
the caches the others leave, about twice as slow as alone; and ``in_loop_stack_us``, the whole control tick of the
walk (:class:`~rtgait.stack.walking_stack.WalkingStack`'s estimate and control: safety checks, estimator, controller,
IK, feed-forward, joint command) per tick that ran it, the timers of its parts inside. ``machine_reference_us`` is the
best time of ``sum(range(1000))`` before and after (about 9 us on the usual machine): quote it with any timing.

Wall times on a shared virtual machine vary from run to run: run it a few times.

With ``--walks`` it reports outcomes instead: the paper's cases fig6, fig7 and fig8 at each controller level asked
for (``--controller``, default all three) and, with ``--velocity-walks`` (``--velocity-only``: these alone), walks
by velocity command of ``--walk-time`` seconds (default 60): 0.3 m/s forward, 0.1 m/s backward, 0.1 m/s sideways,
0.3 rad/s turning, and one that changes between them every fifth of its time. Per walk: whether it walked (no
fall, every step landed, ended at rest), whether the planner clamped the command to the robot's step limits, the
speed the robot really walked (walks of one command: the measured COM's velocity along and across the base's
heading, and the base's yaw rate, from the walk's third step to three steps before its end), the ZMP errors
(measured vs planned, vs the multibody ZMP of the commanded motion, single support, RMS), the largest stance-foot
slip, the share of ticks at which the legs' collision boxes touched and the real-time factor, over worker
processes (``--workers``, default 2). ``--sim-option NAME=JSON`` sets a field of the MuJoCo model's
:class:`~rtgait.sim.model.SimConfig` (e.g. ``leg_collisions=false``, to see what the legs' collision boxes cost);
``motor_model=true`` brings the description's command delay with it, as ``rtgait simulate --motor-model`` does, unless
``command_delay`` is given too.

Every run drives the joints with ``--gains`` (``stiff``, the default: the derived stiff servos; ``robot``: the real
robot's own gains, with feed-forward torques) and ``--drive`` (``position``, the default; ``torque``: the motion carried
by the feed-forward torques under a tenth of the robot's gains), :mod:`rtgait.sim.drive_mode`; with ``--walks`` each
walk's row has ``summary.json``'s ``drive`` entry (COM tracking RMS vs the plan, estimated and true, the shares of
saturated ticks, the peak joint torque and speed against their bounds).

Every run's controller acts on ``--state`` (``estimated``, the default: the state estimated from the simulated
sensors; ``truth``: the simulator's own); with ``--walks`` on the estimate, each walk's row has its estimation
errors (``summary.json``'s ``estimation``).

With ``--envelope`` it sweeps velocity commands x the timings of fig6, fig7 and fig8 per robot (default both) on
``--state``, each a walk of ``--steps`` steps (default 6) of one command with the adaptive controller
(:mod:`envelope`: the directions and shares of the step limits), and prints the largest command walked per
direction; ``--quick`` takes a coarse grid, ``--record FILE`` writes the summary as JSON (docs/velocity_envelope.json
is the one the robots' limits are checked against, walked on the truth).

Usage: ``python benchmarks/sim.py [--json] [--robot NAME] [--scenario NAME] [--repeat N] [--control-dt S]
[--physics-dt S] [--controller C] [--state S] [--gains G] [--drive D]`` or ``python benchmarks/sim.py --walks
[--velocity-walks] [--robot NAME ...] [--velocity-only] [--controller C ...] [--state S] [--walk-time S] [--workers N]
[--physics-dt S] [--gains G] [--drive D] [--option NAME=JSON ...] [--sim-option NAME=JSON ...] [--json]`` or ``python
benchmarks/sim.py --envelope [--robot NAME ...] [--state S] [--quick] [--steps N] [--workers N] [--record FILE]
[--json]``
"""

from __future__ import annotations

import argparse
import dataclasses
import gc
import json
import math
import statistics
import time
import timeit
import warnings
from concurrent.futures import ProcessPoolExecutor
from typing import Any

import mujoco
import numpy as np

from rtgait.core.planner.online import OnlinePlanner
from rtgait.estimation.estimator import DEFAULT_STATE, STATE_SOURCES
from rtgait.interface.command import GAIN_SETS
from rtgait.interface.task_targets import IKTargets
from rtgait.io.sim_run import simulate
from rtgait.robot.ik import WholeBodyIK
from rtgait.robot.model import RobotModel
from rtgait.robot.motion import robot_scenario
from rtgait.scenario.loading import load_scenario
from rtgait.sim.config import SensorSettings
from rtgait.sim.contact_reading import ContactReader
from rtgait.sim.loop_options import LoopOptions
from rtgait.sim.model import SimConfig, build_sim_model


def _step_times(robot: RobotModel, config: SimConfig, targets: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Wall time of each ``mj_step``, of each contact record and of each controller measurement (s) with
    ``targets`` replayed, one row per control tick, ``substeps`` physics steps each."""
    from rtgait.sim.measure import SimMeasurer
    from rtgait.sim.step_snapshot import read_snapshot

    sim = build_sim_model(robot, config)
    data = sim.new_data()
    measurer = SimMeasurer.for_sim(sim)
    reader = ContactReader.for_sim(sim)
    clock = time.perf_counter
    steps, contacts, measures = [], np.empty(len(targets)), np.empty(len(targets))
    for k, row in enumerate(targets):
        data.ctrl[:] = row
        for _ in range(sim.substeps):
            began = clock()
            mujoco.mj_step(sim.model, data)
            steps.append(clock() - began)
        began = clock()
        reader.read(data, read_snapshot(data))
        contacts[k] = clock() - began
        began = clock()
        measurer.measure(data, k * sim.control_dt)
        measures[k] = clock() - began
    return np.array(steps), contacts, measures


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
    first = rows[0]
    q, _ = ik.solve(IKTargets(first.cog, first.left_foot, first.right_foot), robot.q_half_sitting, 200, 1e-9)
    solves, targets = np.empty(n), np.empty((n, len(sim.joint_names)))
    for k, row in enumerate(rows):
        began = clock()
        q, _ = ik.solve(IKTargets(row.cog, row.left_foot, row.right_foot), q, max_iterations=1, tolerance=0.0)
        solves[k] = clock() - began
        targets[k] = q[7:]
    steps, contacts, measures = _step_times(robot, config, targets)
    plain, _, _ = _step_times(robot, dataclasses.replace(config, noslip_iterations=0), targets)
    no_legs, _, _ = _step_times(robot, dataclasses.replace(config, leg_collisions=False), targets)
    return {
        "control_dt_s": dt,
        "physics_dt_s": sim.timestep,
        "substeps": sim.substeps,
        "planner_sample_us": float(np.median(samples) * 1e6),
        "ik_solve_us": float(np.median(solves) * 1e6),
        "mj_step_us": float(np.median(steps) * 1e6),
        "mj_step_without_noslip_us": float(np.median(plain) * 1e6),
        "mj_step_without_leg_collisions_us": float(np.median(no_legs) * 1e6),
        "contact_reading_us": float(np.median(contacts) * 1e6),
        "controller_measurement_us": float(np.median(measures) * 1e6),
    }


# The in-loop breakdown's parts: what each timed callable of ClosedLoop.step is (the rest is the loop's own code).
IN_LOOP_PARTS = (
    "ik", "mj_step", "controller", "estimation", "feedforward", "contact_reading", "contact_monitor", "tick_log",
    "servo", "inputs",
)  # fmt: skip


def in_loop_parts(
    robot: RobotModel, scenario_name: str, controller: str, sim: Any, state: str, drive: str = "position"
) -> dict[str, float]:
    """Mean wall time per tick (us) of each part of :meth:`~rtgait.sim.loop.ClosedLoop.step` inside one real run:
    each callable the tick calls is wrapped in a timer (a tenth of a microsecond each, counted in ``rest``), so the
    parts add up to the tick and ``rest`` is the loop's own bookkeeping (the record, references, fall checks)."""
    from rtgait.sim.loop import ClosedLoop

    clock = time.perf_counter
    spent = dict.fromkeys((*IN_LOOP_PARTS, "tick", "stack"), 0.0)
    ticks, stack_ticks = [0], [0]

    def timed(part: str, call: Any) -> Any:
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            began = clock()
            out = call(*args, **kwargs)
            spent[part] += clock() - began
            return out

        return wrapper

    original_init, original_step = ClosedLoop.__init__, ClosedLoop.step

    def init(loop: ClosedLoop, *args: Any, **kwargs: Any) -> None:
        original_init(loop, *args, **kwargs)
        # The stack and the robot look their parts up at each call: the parts are wrapped where they live.
        stack, robot = loop.stack, loop.robot
        stack.ik.solve = timed("ik", stack.ik.solve)  # type: ignore[method-assign]
        stack.controller.tick = timed("controller", stack.controller.tick)  # type: ignore[method-assign]
        stack.estimator.update = timed("estimation", stack.estimator.update)  # type: ignore[method-assign]
        if stack.feedforward is not None:  # the feed-forward torques (robot gains, torque drive)
            stack.feedforward.torques = timed("feedforward", stack.feedforward.torques)  # type: ignore[method-assign]
        robot.reader.contacts.read = timed("contact_reading", robot.reader.contacts.read)  # type: ignore[method-assign]
        loop.contacts.record = timed("contact_monitor", loop.contacts.record)  # type: ignore[method-assign]
        if loop.log is not None:
            loop.log.record = timed("tick_log", loop.log.record)  # type: ignore[method-assign]
        robot.drives.command = timed("servo", robot.drives.command)  # type: ignore[method-assign]
        robot._apply = timed("servo", robot.drives.apply)  # the substeps call the drives through it
        loop._walk_inputs = timed("inputs", loop._walk_inputs)
        # The whole control tick: the stack's estimate and control as the loop calls them (bound in its hot tuple).
        estimate, control = loop._hot[0], loop._hot[1]

        def counted_control(*args: Any) -> Any:
            stack_ticks[0] += 1
            return control(*args)

        loop._hot = (timed("stack", estimate), timed("stack", counted_control), *loop._hot[2:])

    def step(loop: ClosedLoop) -> bool:
        began = clock()
        out = original_step(loop)
        spent["tick"] += clock() - began
        ticks[0] += 1
        return out

    original_mj_step = mujoco.mj_step
    ClosedLoop.__init__, ClosedLoop.step = init, step  # type: ignore[method-assign]
    mujoco.mj_step = timed("mj_step", original_mj_step)
    try:
        gc.collect()
        options = LoopOptions(state=state, drive=drive)  # type: ignore[arg-type]
        simulate(load_scenario(scenario_name), robot, sim=sim, controller=controller, options=options)
    finally:
        ClosedLoop.__init__, ClosedLoop.step = original_init, original_step  # type: ignore[method-assign]
        mujoco.mj_step = original_mj_step
    n = max(ticks[0], 1)
    report = {f"in_loop_{part}_us": spent[part] / n * 1e6 for part in IN_LOOP_PARTS}
    report["in_loop_tick_us"] = spent["tick"] / n * 1e6
    report["in_loop_rest_us"] = (spent["tick"] - sum(spent[part] for part in IN_LOOP_PARTS)) / n * 1e6
    report["in_loop_stack_us"] = spent["stack"] / max(stack_ticks[0], 1) * 1e6
    return report


def machine_reference_us() -> float:
    """The machine's speed: the best of five times ``sum(range(1000))`` in us (about 9 on this project's usual
    machine; quote it next to any timing)."""
    return min(timeit.repeat("sum(range(1000))", number=10000, repeat=5)) / 10000 * 1e6


VELOCITY_WALKS = {
    "forward 0.3 m/s": (0.3, 0.0, 0.0),
    "backward 0.1 m/s": (-0.1, 0.0, 0.0),
    "sideways 0.1 m/s": (0.0, 0.1, 0.0),
    "turning 0.3 rad/s": (0.0, 0.0, 0.3),
}
"""The walks by velocity command of ``--velocity-walks`` (m/s, m/s, rad/s), and one that changes between them."""


def velocity_schedule(name: str, seconds: float) -> list[tuple[float, float, float, float]]:
    """The ``(t, vx, vy, wz)`` commands of walk ``name``: one command, or ``"changes"``: forward, sideways, turning,
    backward, forward again, each a fifth of ``seconds``."""
    if name != "changes":
        return [(0.0, *VELOCITY_WALKS[name])]
    order = [(0.3, 0.0, 0.0), (0.0, 0.1, 0.0), (0.1, 0.0, 0.3), (-0.1, 0.0, 0.0), (0.3, 0.0, 0.0)]
    return [(i * seconds / len(order), *command) for i, command in enumerate(order)]


def walked_velocity(result: Any, start: float, period: float, steps: int) -> tuple[float, float, float]:
    """The velocity the robot really walked: the measured COM's mean velocity along and across the base's heading
    (m/s) and the base's mean yaw rate (rad/s), from the walk's third step to three steps before its last one (the
    start and the stop left out); NaN when the walk is too short or the robot fell before the window's end."""
    t0, t1 = start + 2.0 * period, start + (steps - 3) * period
    times = result.times
    if t1 <= t0 or times[-1] < t1:
        return math.nan, math.nan, math.nan
    qx, qy, qz, qw = result.base_quaternion.T
    yaw = np.unwrap(np.arctan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz)))
    window = (times >= t0) & (times <= t1)
    velocity = np.gradient(result.cog[:, :2], times, axis=0)[window]
    heading = yaw[window]
    c, s = np.cos(heading), np.sin(heading)
    along = float(np.mean(c * velocity[:, 0] + s * velocity[:, 1]))
    across = float(np.mean(-s * velocity[:, 0] + c * velocity[:, 1]))
    a, b = np.searchsorted(times, [t0, t1])
    return along, across, float((yaw[b] - yaw[a]) / (times[b] - times[a]))


def walk_case(job: dict[str, Any]) -> dict[str, Any]:
    """One walk of ``--walks`` (a worker's task): its outcome and measures."""
    from rtgait.control.controller import ControllerOptions
    from rtgait.core.walk.walk import CommandClampedWarning
    from rtgait.io.sim_run import mujoco_messages

    robot = RobotModel.load(job["robot"])
    sim_options = job.get("sim_options") or {}
    if "sensors" in sim_options and isinstance(sim_options["sensors"], dict):  # from JSON
        sim_options = {**sim_options, "sensors": SensorSettings(**sim_options["sensors"])}
    gains = job.get("gains", "stiff")
    sim = build_sim_model(robot, SimConfig(meshes=False, physics_dt=job["physics_dt"], gains=gains, **sim_options))
    scenario = load_scenario(job["scenario"])
    velocity = None
    if job["velocity"] is not None:
        period = scenario.timing.single_support + scenario.timing.double_support
        steps = math.ceil((job["seconds"] - scenario.timing.start) / period)
        scenario = dataclasses.replace(scenario, steps=steps)
        velocity = velocity_schedule(job["velocity"], job["seconds"])
    with mujoco_messages(), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", CommandClampedWarning)
        options = ControllerOptions(**job["options"]) if job["options"] else None
        result = simulate(
            scenario, robot, sim=sim, controller=job["controller"], velocity=velocity, controller_options=options,
            options=LoopOptions(state=job.get("state", DEFAULT_STATE), drive=job.get("drive", "position")),
        )  # fmt: skip
    summary = result.summary()
    clamped = any(issubclass(w.category, CommandClampedWarning) for w in caught)
    asked = walked = None
    if velocity is not None and len(velocity) == 1:
        asked = list(velocity[0][1:])
        walked = list(walked_velocity(result, scenario.timing.start, scenario.timing.step_period, scenario.steps))
    errors = result.zmp_errors()
    return {
        "robot": robot.name,
        "walk": job["velocity"] or job["scenario"],
        "controller": job["controller"],
        "walked": bool(result.all_steps_completed and result.ended_at_rest),
        "fell": result.fell,
        "fall_time": result.fall_time,
        "tipped": result.tipped,
        "steps_completed": result.steps_completed,
        "steps_planned": result.steps_planned,
        "distance_walked": result.distance_walked,
        "zmp_vs_plan_rms": errors["vs_plan"]["rms"],
        "zmp_vs_commanded_motion_rms": errors["vs_commanded_motion"]["rms"],
        "foot_slip_max": result.foot_slip_max,
        "step_adjustments": result.step_adjustment_count,
        "clamped": clamped,
        "velocity_asked": asked,
        "velocity_walked": walked,
        "legs_touch_share": float(np.mean(result.legs_touch)),
        "simulated_time": result.duration,
        "real_time_factor": result.real_time_factor,
        "state": result.state,
        "sensors": summary["sensors"],
        "estimation": summary["estimation"],
        "drive": summary["drive"],
    }


def walks(args: argparse.Namespace) -> list[dict[str, Any]]:
    """The outcome table of ``--walks`` (module docstring)."""
    controllers = args.controller or ["open-loop", "stabilized", "adaptive"]
    common = {"physics_dt": args.physics_dt, "options": args.options, "sim_options": args.sim_options,
              "state": args.state, "gains": args.gains, "drive": args.drive}  # fmt: skip
    jobs = [
        {"robot": robot, "scenario": case, "controller": c, "velocity": None, "seconds": 0.0, **common}
        for robot in args.robots or ["talos"]
        for case in ("fig6", "fig7", "fig8")
        for c in controllers
        if not args.velocity_only
    ]
    if args.velocity_walks or args.velocity_only:
        jobs += [
            {"robot": robot, "scenario": "fig8", "controller": c, "velocity": name, "seconds": args.walk_time,
             **common}
            for robot in args.robots or ["talos"]
            for name in [*VELOCITY_WALKS, "changes"]
            for c in controllers
        ]  # fmt: skip
    with ProcessPoolExecutor(args.workers) as pool:
        return list(pool.map(walk_case, jobs))


def print_walks(rows: list[dict[str, Any]]) -> None:
    def mm(value: float | None) -> str:
        return "-" if value is None else f"{value * 1e3:.1f}"

    def speed(r: dict[str, Any]) -> str:
        walked = r.get("velocity_walked")
        if not walked:
            return "-"
        return "nan" if math.isnan(walked[0]) else "{:.3f},{:.3f},{:.3f}".format(*walked)

    def dcm_error(r: dict[str, Any]) -> str:
        estimation = r.get("estimation")
        return "-" if not estimation or estimation["dcm_rms"] is None else f"{estimation['dcm_rms'] * 1e3:.1f}"

    print(f"{'robot':<7} {'walk':<18} {'controller':<11} {'state':<9} {'outcome':<26} {'clamped':<7} "
          f"{'walked vx,vy,wz':<19} {'ZMP-plan':>8} {'ZMP-mb':>7} {'slip':>5} {'legs':>5} {'adj':>4} {'DCM-est':>7} "
          f"{'RTF':>5}")  # fmt: skip
    print(f"{'':<7} {'':<18} {'':<11} {'':<9} {'':<26} {'':<7} {'m/s,m/s,rad/s':<19} {'mm RMS':>8} {'mm RMS':>7} "
          f"{'mm':>5} {'touch':>5} {'':>4} {'mm RMS':>7} {'':>5}")  # fmt: skip
    for r in rows:
        if r["fell"]:
            outcome = f"FELL at {r['fall_time']:.1f} s ({r['steps_completed']}/{r['steps_planned']})"
        else:
            outcome = f"{'walked' if r['walked'] else 'stood'} {r['steps_completed']}/{r['steps_planned']}"
            outcome += ", tipped" if r["tipped"] else ""
        clamped = "yes" if r.get("clamped") else "no"
        print(f"{r['robot']:<7} {r['walk']:<18} {r['controller']:<11} {r.get('state', ''):<9} {outcome:<26} "
              f"{clamped:<7} {speed(r):<19} {mm(r['zmp_vs_plan_rms']):>8} {mm(r['zmp_vs_commanded_motion_rms']):>7} "
              f"{r['foot_slip_max'] * 1e3:>5.1f} {r.get('legs_touch_share', 0.0):>5.2f} {r['step_adjustments']:>4} "
              f"{dcm_error(r):>7} {r['real_time_factor']:>5.1f}")  # fmt: skip


def run_envelope(args: argparse.Namespace) -> None:
    """``--envelope``: the sweep of :mod:`envelope`, its summary printed (or everything as JSON) and recorded."""
    from envelope import DIRECTIONS, envelope, print_summary, record_text

    if args.steps < 2:
        raise SystemExit("--steps must be at least 2")
    unknown = sorted(set(args.directions or ()) - set(DIRECTIONS))
    if unknown:
        raise SystemExit(f"--direction {unknown[0]!r}: known are {', '.join(DIRECTIONS)}")
    if args.shares is not None and not all(0.0 < share <= 1.0 for share in args.shares):
        raise SystemExit(f"--shares must be within (0, 1], got {args.shares}")
    report = envelope(args)
    if args.record:
        with open(args.record, "w", encoding="utf-8") as file:
            file.write(record_text(report))
    if args.json:
        print(json.dumps(report))
        return
    print_summary(report["summary"], report["state"])
    print(f"({report['seconds']:.0f} s on {args.workers} workers, {len(report['cases'])} cases)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--robot", action="append", dest="robots", help="robot(s) (default talos)")
    parser.add_argument("--scenario", default="fig8")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--control-dt", type=float, default=None, help="control period (s); default the robot's")
    parser.add_argument("--physics-dt", type=float, default=None, help="physics step (s); default: the robot's")
    parser.add_argument("--controller", action="append", choices=("open-loop", "stabilized", "adaptive"),
                        help="controller level(s); the speed report takes the first (default adaptive)")  # fmt: skip
    parser.add_argument("--state", choices=STATE_SOURCES, default=DEFAULT_STATE,
                        help=f"what the controller acts on (default {DEFAULT_STATE})")  # fmt: skip
    parser.add_argument("--gains", choices=GAIN_SETS, default="stiff",
                        help="the drives' own gains: stiff (default) or robot, with feed-forward torques")  # fmt: skip
    parser.add_argument("--drive", choices=("position", "torque"), default="position",
                        help="position (default) or torque: a tenth of the robot's gains, with FF torques")  # fmt: skip
    parser.add_argument("--walks", action="store_true", help="report the outcomes of fig6/7/8 instead of speed")
    parser.add_argument("--velocity-walks", action="store_true", help="with --walks: the walks by command too")
    parser.add_argument("--velocity-only", action="store_true", help="with --walks: the walks by command alone")
    parser.add_argument("--walk-time", type=float, default=60.0, help="length of a walk by command (s)")
    parser.add_argument("--workers", type=int, default=2, help="worker processes of --walks (default 2)")
    parser.add_argument("--envelope", action="store_true", help="sweep velocity commands x fig6/7/8 timings")
    parser.add_argument("--quick", action="store_true", help="with --envelope: a coarse grid")
    parser.add_argument("--steps", type=int, default=6, help="with --envelope: steps per walk (default 6)")
    parser.add_argument("--timing", action="append", dest="timings", choices=("fig6", "fig7", "fig8"),
                        help="with --envelope: the timing(s) (default all three)")  # fmt: skip
    parser.add_argument("--direction", action="append", dest="directions", metavar="NAME",
                        help="with --envelope: the direction(s) (default all, or the quick ones)")  # fmt: skip
    parser.add_argument("--shares", type=lambda text: tuple(float(v) for v in text.split(",")), default=None,
                        metavar="S,S,...", help="with --envelope: shares of the limits")  # fmt: skip
    parser.add_argument("--record", default=None, metavar="FILE", help="with --envelope: write the summary (JSON)")
    parser.add_argument(
        "--option", action="append", default=[], metavar="NAME=JSON",
        help="with --walks: a ControllerOptions field of the closed-loop levels, e.g. adapt_timing=true",
    )  # fmt: skip
    parser.add_argument(
        "--sim-option", action="append", default=[], metavar="NAME=JSON",
        help="with --walks: a SimConfig field of the MuJoCo model, e.g. leg_collisions=false",
    )  # fmt: skip
    args = parser.parse_args()
    for flag, texts, example in (("option", args.option, "adapt_timing=true"),
                                 ("sim_options", args.sim_option, "leg_collisions=false")):  # fmt: skip
        try:
            pairs = [text.split("=", 1) for text in texts]
            setattr(args, "options" if flag == "option" else flag, {name: json.loads(value) for name, value in pairs})
        except ValueError:
            parser.error(f"--{flag.replace('_options', '-option')} needs NAME=JSON, e.g. {example}")
    known = {f.name for f in dataclasses.fields(SimConfig)}
    unknown = sorted(set(args.sim_options) - known)
    if unknown:
        parser.error(f"--sim-option: SimConfig has no field {unknown[0]!r}")
    if args.sim_options.get("motor_model") is True:
        # The robot's motors come with its bus, as `rtgait simulate --motor-model` runs them: the command applied the
        # description's actuation.command_delay periods late, unless a command_delay is given.
        args.sim_options.setdefault("command_delay", None)
    if args.envelope:
        if args.gains != "stiff" or args.drive != "position":
            parser.error("--envelope sweeps the stiff position drives only (no --gains robot, --drive torque)")
        run_envelope(args)
        return
    if args.walks:
        began = time.perf_counter()
        rows = walks(args)
        if args.json:
            print(json.dumps({"walks": rows, "seconds": time.perf_counter() - began}))
        else:
            print_walks(rows)
            print(f"({time.perf_counter() - began:.0f} s on {args.workers} workers)")
        return
    robot = RobotModel.load((args.robots or ["talos"])[0])
    controller = (args.controller or ["adaptive"])[0]
    config = SimConfig(control_dt=args.control_dt, physics_dt=args.physics_dt, gains=args.gains)
    sim = build_sim_model(robot, config)
    scenario = load_scenario(args.scenario)
    factors, per_tick = [], []
    reference_before = machine_reference_us()
    for _ in range(args.repeat):
        gc.collect()
        options = LoopOptions(state=args.state, drive=args.drive)
        result = simulate(scenario, robot, sim=sim, controller=controller, options=options)
        factors.append(result.real_time_factor)
        per_tick.append(result.wall_time / len(result.times) * 1e6)
    report = {
        "robot": robot.name,
        "controller": controller,
        "state": args.state,
        "gains": args.gains,
        "drive": args.drive,
        "scenario": args.scenario,
        "simulated_time_s": result.duration,
        "real_time_factor": factors,
        "tick_us_median_of_runs": statistics.median(per_tick),
        "fell": result.fell,
        **parts(robot, args.scenario, dataclasses.replace(config, meshes=False)),
        **in_loop_parts(robot, args.scenario, controller, sim, args.state, args.drive),
    }
    report["machine_reference_us"] = [reference_before, machine_reference_us()]
    if args.json:
        print(json.dumps(report))
        return
    print(f"{robot.name}, {args.scenario}, {controller} on the {args.state} state: {report['simulated_time_s']:.1f} s "
          "simulated per run")  # fmt: skip
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
        "contact_reading_us",
        "controller_measurement_us",
    ):
        print(f"  {key[:-3].replace('_', ' ')}: {report[key]:.1f} us (median)")
    print(f"inside one run, per tick (mean): {report['in_loop_tick_us']:.0f} us")
    for part in (*IN_LOOP_PARTS, "rest"):
        print(f"  {part.replace('_', ' ')}: {report[f'in_loop_{part}_us']:.1f} us")
    print(f"the stack's control tick (safety, estimator, controller, IK), per walking tick: "
          f"{report['in_loop_stack_us']:.1f} us")  # fmt: skip
    before, after = report["machine_reference_us"]
    print(f"machine reference, sum(range(1000)): {before:.1f} us before, {after:.1f} us after (~9 usually)")


if __name__ == "__main__":
    main()
