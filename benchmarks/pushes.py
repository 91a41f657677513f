"""Largest push a robot survives in MuJoCo, per controller level, direction and walking phase (run on demand).

For every controller level asked for (``--controller``, :mod:`rtgait.control.controller`) and every horizontal
direction (``--directions``, evenly spaced from 0 = the walking direction +x, counter-clockwise: 90 = to the left),
the largest impulse survived is found by bisection. The push is a constant force for 0.1 s on the floating base
(the pelvis), at one of two instants of the middle step of the walk (step ``(n + 1) // 2`` of ``n``, the closing
step counted):

* ``single``: centred on the middle of its single support;
* ``double``: starting when the double support after its landing begins.

*Survived*: no fall, and the walk ends at rest (:attr:`rtgait.sim.result.SimResult.ended_at_rest`: past the walk's
planned end the COM is still, both feet flat on the floor). Each direction is also named relative to the foot that
carries the robot at the push (in double support, the one that carries the next single support): ``outward`` is
away from the other foot, ``inward`` toward it.

The bisection starts from an impulse that moves the DCM by 0.1 m (``0.1 m w`` kg m/s, 31 N s for Talos), doubles it
until the robot falls, then halves the bracket down to ``--tolerance`` (N s). A level that does not survive the
unpushed walk gets 0 everywhere. The runs are spread over worker processes (``--workers``, default 2: this
project's machine has 2 cores), with a progress bar on stderr.

For comparison, each direction also gets the *in-place bound*: the largest impulse a strategy that keeps the feet
where they are can withstand, from the planned DCM ``xi`` at the push's centre (:func:`in_place_bounds`):

* ``sole_bound_Ns = m w d``, with ``d = max_v (v . u) - xi . u`` how far ``xi`` may move along the push ``u``
  before it passes the support polygon's farthest point ``v`` along ``u`` (the stance sole in single support; both
  soles' convex hull in double support): the DCM's part along ``u`` obeys ``xi_u' = w (xi_u - p_u)`` with the ZMP's
  ``p_u`` at most that far, so past it the DCM diverges along ``u`` whatever the ankles do, until a step puts a
  foot farther along ``u``;
* ``lean_bound_Ns``: what the hip strategy's lean adds at most, ``m w`` times
  :meth:`rtgait.core.laws.hip_strategy.HipStrategyLimits.recoverable_offset` along the push (each heading axis leaning
  at
  its limit), with the robot's lean limits (:func:`rtgait.robot.lean.hip_strategy_limits`).

A push beyond their sum needs a step. Outward in single support there is none to take: the swing foot would have
to cross the stance leg, which the legs' collision shapes stop, as on the robot. The bounds treat the push as an
impulse at its centre (a 0.1 s push moves the DCM 1.005 times as far). They are upper bounds for the pendulum (the
lean starts at once and returns for free); the robot's DCM at the push is not exactly the plan's, so it may beat
them by a few per cent. ``--bounds-only`` prints them without running the physics.

Writes ``pushes.csv``, ``pushes.json`` and ``pushes.png`` (a polar plot per phase, one curve per level and the
in-place bound dashed) into ``--out`` (default ``out/pushes-<robot>``), and prints the table (or, with ``--json``,
the JSON document).

The controller acts on ``--state``: ``estimated`` (the default), the state estimated from the simulated sensors;
``truth``, the simulator's own (the in-place bounds are those of a controller that knows the state). The joints are
driven with ``--gains`` (``stiff``, the default, or ``robot``: the real robot's own gains with feed-forward torques) and
``--drive`` (``position``, the default, or ``torque``: a tenth of the robot's gains, the motion carried by the
feed-forward torques), :mod:`rtgait.sim.drive_mode`.

Usage: ``python benchmarks/pushes.py [--robot R] [--controller C ...] [--state S] [--json] [--scenario fig8]
[--phase single|double ...] [--directions 8] [--tolerance 1.0] [--workers 2] [--out DIR] [--physics-dt S]
[--gains stiff|robot] [--drive position|torque] [--option NAME=JSON ...] [--bounds-only]``
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import json
import math
import os
import sys
import time
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any

PUSH_DURATION = 0.1
"""Length of every push (s)."""
PHASES = ("single", "double")
START_DCM_SHIFT = 0.1
"""The bisection's first impulse moves the DCM by this much (m): ``m w`` times it (N s)."""
MAX_DOUBLINGS = 5


@dataclasses.dataclass(frozen=True)
class Site:
    """Where and when the pushes of one phase act: the step, the window's start (s, walk clock) and the stance
    foot's side and heading."""

    phase: str
    step: int
    start: float
    stance_side: str
    stance_yaw: float


def push_site(scenario: Any, robot: Any, phase: str) -> Site:
    """The push instant of ``phase`` on the middle step of ``scenario`` walked by ``robot`` (its planned footprints)."""
    from rtgait.core.planner.online import OnlinePlanner
    from rtgait.robot.motion import robot_scenario

    walk = robot_scenario(scenario, robot)
    step = (len(walk.strides()) + 1) // 2
    planner = OnlinePlanner(walk.planner_config(), walk.strides())
    planner.start(0.0)
    single = planner.phase_start(2 * step - 1)  # step k's single support is phase 2k - 1
    timing = walk.timing
    if phase == "single":
        start = single + 0.5 * timing.single_support - 0.5 * PUSH_DURATION
        stance = planner.footprints()[step]  # F[k] carries step k's single support
    else:
        start = single + timing.single_support
        stance = planner.footprints()[step + 1]  # the foot that just landed carries the next single support
    return Site(phase, step, start, stance.side, stance.yaw)


def direction_name(site: Site, angle_deg: float) -> str:
    """``forward``, ``backward``, ``outward``, ``inward`` or the diagonal between them, relative to the stance foot."""
    relative = math.degrees(math.remainder(math.radians(angle_deg) - site.stance_yaw, math.tau)) % 360.0
    left = site.stance_side == "left"
    names = {0: "forward", 90: "outward" if left else "inward", 180: "backward", 270: "inward" if left else "outward"}
    nearest = round(relative / 45.0) * 45 % 360
    if abs(relative - nearest) > 1.0:
        return f"{relative:.0f} deg"
    if nearest in names:
        return names[nearest]
    a, b = names[(nearest - 45) % 360], names[(nearest + 45) % 360]
    first, second = (a, b) if a in ("forward", "backward") else (b, a)
    return f"{first}-{second}"


def in_place_bounds(
    scenario: Any, robot: Any, site: Site, angles: Sequence[float], max_lean: float | None = None
) -> dict[float, tuple[float, float]]:
    """The in-place bound of the module docstring at ``site``, per direction (deg): ``(sole, lean)`` (N s).

    ``max_lean`` (rad): the lean's limit (default: :class:`~rtgait.control.controller.ControllerOptions`'s).
    """
    import numpy as np

    from rtgait.control.controller import ControllerOptions
    from rtgait.core.analysis.rollout import rollout
    from rtgait.core.geometry.footsteps import mean_heading
    from rtgait.core.planner.online import OnlinePlanner
    from rtgait.robot.lean import hip_strategy_limits
    from rtgait.robot.motion import robot_scenario

    walk = robot_scenario(scenario, robot)
    centre = site.start + 0.5 * PUSH_DURATION
    planner = OnlinePlanner(walk.planner_config(), walk.strides())
    walked = rollout(planner, walk.dt, walk.sole, walk.changes, duration=centre)  # the walk unpushed, to the push
    dcm = np.array([walked.column("dcm_x")[-1], walked.column("dcm_y")[-1]])
    feet = [walked.footprints[site.step]] if site.phase == "single" else walked.footprints[site.step : site.step + 2]
    corners = np.vstack([walk.sole.corners(foot) for foot in feet])
    heading = feet[0].yaw if len(feet) == 1 else mean_heading(feet[0].yaw, feet[1].yaw)
    w = math.sqrt(scenario.gravity / robot.description.cog_height)
    limits = hip_strategy_limits(robot, ControllerOptions().max_lean if max_lean is None else max_lean)
    forward, lateral = limits.recoverable_offset(robot.mass, w, scenario.gravity)
    bounds = {}
    for angle in angles:
        a = math.radians(angle)
        u = np.array([math.cos(a), math.sin(a)])
        # The polygon's farthest point along u is one of the soles' corners: no hull needed.
        sole = robot.mass * w * max(float(np.max(corners @ u) - dcm @ u), 0.0)
        # Each heading axis leans at its own limit: the CMP's reach along u is the box's support function.
        lean = robot.mass * w * (abs(math.cos(a - heading)) * forward + abs(math.sin(a - heading)) * lateral)
        bounds[angle] = (sole, lean)
    return bounds


# ----- the worker side ----------------------------------------------------------------------------------------------
_CACHE: dict[str, Any] = {}


PHYSICS_DT: dict[str, float | None] = {"value": None}
"""The physics step of the runs (s; ``--physics-dt``), handed to every worker by :func:`_init_worker`."""
STATE: dict[str, str | None] = {"value": None}
"""What the controller acts on (``--state``; ``None``: the loop's default), handed to every worker likewise."""
DRIVE: dict[str, str] = {"gains": "stiff", "drive": "position"}
"""The drives' own gains and the drive mode (``--gains``, ``--drive``), handed to every worker likewise."""


def _init_worker(
    physics_dt: float | None, state: str | None = None, gains: str = "stiff", drive: str = "position"
) -> None:
    PHYSICS_DT["value"] = physics_dt
    STATE["value"] = state
    DRIVE["gains"], DRIVE["drive"] = gains, drive


def _setup(robot_name: str, scenario_name: str) -> tuple[Any, Any, Any]:
    """The robot, its MuJoCo model (no meshes: the same physics; the ``--physics-dt`` step) and the scenario, built
    once per process."""
    key = f"{robot_name}|{scenario_name}|{PHYSICS_DT['value']}|{DRIVE['gains']}"
    if key not in _CACHE:
        from rtgait.robot.model import RobotModel
        from rtgait.scenario.loading import load_scenario
        from rtgait.sim.model import SimConfig, build_sim_model

        robot = RobotModel.load(robot_name)
        sim = build_sim_model(robot, SimConfig(meshes=False, physics_dt=PHYSICS_DT["value"], gains=DRIVE["gains"]))
        _CACHE[key] = (robot, sim, load_scenario(scenario_name))
    return _CACHE[key]


def survives(
    robot_name: str,
    scenario_name: str,
    controller: str,
    push: tuple[float, float, float] | None,
    options: dict[str, Any] | None = None,
) -> bool:
    """Whether the walk with ``push`` = ``(start, fx, fy)`` (s, N, N; or ``None``) ends at rest without a fall;
    ``options`` are :class:`~rtgait.control.controller.ControllerOptions` fields."""
    from rtgait.control.controller import ControllerOptions
    from rtgait.core.push import Push
    from rtgait.io.sim_run import mujoco_messages, simulate
    from rtgait.sim.loop_options import LoopOptions

    robot, sim, scenario = _setup(robot_name, scenario_name)
    pushes = None if push is None else Push(push[0], PUSH_DURATION, (push[1], push[2], 0.0))
    level = ControllerOptions(**options) if options else None
    loop = LoopOptions(drive=DRIVE["drive"])  # type: ignore[arg-type]
    if STATE["value"] is not None:
        loop = dataclasses.replace(loop, state=STATE["value"])
    with mujoco_messages():
        result = simulate(scenario, robot, sim=sim, controller=controller, push=pushes, controller_options=level,  # type: ignore[arg-type]
                          options=loop)  # fmt: skip
    return not result.fell and result.ended_at_rest


def largest_impulse(job: dict[str, Any]) -> dict[str, Any]:
    """One bisection (a worker's task): the largest impulse (N s) survived along ``job["direction_deg"]``."""
    began = time.perf_counter()
    robot, _, _ = _setup(job["robot"], job["scenario"])
    u = (math.cos(math.radians(job["direction_deg"])), math.sin(math.radians(job["direction_deg"])))
    runs = 0

    def ok(impulse: float) -> bool:
        nonlocal runs
        runs += 1
        force = impulse / PUSH_DURATION
        push = (job["start"], force * u[0], force * u[1])
        return survives(job["robot"], job["scenario"], job["controller"], push, job["options"])

    low, best = 0.0, 0.0
    if job["unpushed"]:
        high = job["first"]
        for _ in range(MAX_DOUBLINGS):
            if not ok(high):
                break
            low, high = high, 2.0 * high
        else:
            high = math.inf  # survived every doubling: the bracket's top is unknown
        while math.isfinite(high) and high - low > job["tolerance"]:
            middle = 0.5 * (low + high)
            if ok(middle):
                low = middle
            else:
                high = middle
        best = low
    return {
        **{key: job[key] for key in ("controller", "phase", "direction_deg", "direction", "step", "start")},
        "push_duration": PUSH_DURATION,
        "max_impulse_Ns": best,
        "unpushed_survives": job["unpushed"],
        "runs": runs,
        "seconds": time.perf_counter() - began,
        "mass": robot.mass,
    }


def _unpushed(args: tuple[str, str, str, dict[str, Any]]) -> tuple[str, bool]:
    return args[2], survives(args[0], args[1], args[2], None, args[3])


# ----- the driver ---------------------------------------------------------------------------------------------------
def run(
    robot_name: str,
    scenario_name: str,
    controllers: Sequence[str],
    phases: Sequence[str],
    directions: int,
    tolerance: float,
    workers: int,
    progress: bool = True,
    options: dict[str, Any] | None = None,
    physics_dt: float | None = None,
    state: str | None = None,
    gains: str = "stiff",
    drive: str = "position",
) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    """Every bisection of the benchmark; returns the cases and the settings. ``options``: controller options
    (:class:`~rtgait.control.controller.ControllerOptions` fields) for the closed-loop levels; ``physics_dt``: the
    physics step (s); ``state``: what the controller acts on (default the loop's); ``gains``, ``drive``: the drives'
    own gains and the drive mode (:mod:`rtgait.sim.drive_mode`)."""
    from tqdm import tqdm

    from rtgait.estimation.estimator import DEFAULT_STATE

    _init_worker(physics_dt, state, gains, drive)
    robot, _, scenario = _setup(robot_name, scenario_name)
    w = math.sqrt(scenario.gravity / robot.description.cog_height)
    first = START_DCM_SHIFT * robot.mass * w
    sites = {phase: push_site(scenario, robot, phase) for phase in phases}
    angles = [360.0 * i / directions for i in range(directions)]
    max_lean = (options or {}).get("max_lean")
    bounds = {phase: in_place_bounds(scenario, robot, site, angles, max_lean) for phase, site in sites.items()}
    with ProcessPoolExecutor(workers, initializer=_init_worker, initargs=(physics_dt, state, gains, drive)) as pool:
        options = options or {}
        levels = {c: (options if c != "open-loop" else {}) for c in controllers}
        unpushed = dict(pool.map(_unpushed, [(robot_name, scenario_name, c, levels[c]) for c in controllers]))
        common = {"robot": robot_name, "scenario": scenario_name, "first": first, "tolerance": tolerance}
        jobs = []
        for controller, phase, angle in itertools.product(controllers, phases, angles):
            site = sites[phase]
            where = {"phase": phase, "direction_deg": angle, "step": site.step, "start": site.start}
            jobs.append(
                {**common, **where, "controller": controller, "direction": direction_name(site, angle),
                 "unpushed": unpushed[controller], "options": levels[controller]}
            )  # fmt: skip
        cases = []
        futures = [pool.submit(largest_impulse, job) for job in jobs]
        bar = tqdm(total=len(futures), desc=f"pushes on {robot.name}", unit=" directions", disable=not progress)
        for future in as_completed(futures):
            case = future.result()
            case["sole_bound_Ns"], case["lean_bound_Ns"] = bounds[case["phase"]][case["direction_deg"]]
            cases.append(case)
            bar.update(1)
        bar.close()
    order = {(j["controller"], j["phase"], j["direction_deg"]): i for i, j in enumerate(jobs)}
    cases.sort(key=lambda c: order[(c["controller"], c["phase"], c["direction_deg"])])
    settings = {
        "robot": robot.name, "mass": robot.mass, "scenario": scenario.name, "push_duration": PUSH_DURATION,
        "push_body": "floating base", "tolerance_Ns": tolerance, "first_impulse_Ns": first, "workers": workers,
        "sites": {phase: dataclasses.asdict(site) for phase, site in sites.items()}, "controller_options": options,
        "physics_dt": physics_dt if physics_dt is not None else robot.description.actuation.physics_dt,
        "state": state or DEFAULT_STATE, "gains": gains, "drive": drive,
    }  # fmt: skip
    return cases, settings


def table(cases: list[dict[str, Any]]) -> str:
    """The largest impulses (N s) as text, one row per level and phase, one column per direction."""
    angles = sorted({c["direction_deg"] for c in cases})
    names = {(c["phase"], c["direction_deg"]): c["direction"] for c in cases}
    lines = []
    for phase in PHASES:
        rows = [c for c in cases if c["phase"] == phase]
        if not rows:
            continue
        lines.append(f"{phase} support: " + ", ".join(f"{a:g} deg = {names[(phase, a)]}" for a in angles))
        lines.append(f"{'controller':<11}" + "".join(f"{a:>8g}" for a in angles) + "   (N s)")
        for controller in dict.fromkeys(c["controller"] for c in rows):
            values = {c["direction_deg"]: c for c in rows if c["controller"] == controller}
            text = "".join(f"{values[a]['max_impulse_Ns']:>8.1f}" for a in angles)
            falls = "" if values[angles[0]]["unpushed_survives"] else "  (falls unpushed)"
            lines.append(f"{controller:<11}{text}{falls}")
        if "sole_bound_Ns" in rows[0]:
            bound = {c["direction_deg"]: c for c in rows}
            lines.append(f"{'sole bound':<11}" + "".join(f"{bound[a]['sole_bound_Ns']:>8.1f}" for a in angles))
            both = (bound[a]["sole_bound_Ns"] + bound[a]["lean_bound_Ns"] for a in angles)
            lines.append(f"{'+ lean':<11}" + "".join(f"{value:>8.1f}" for value in both) + "   (in place)")
        lines.append("")
    return "\n".join(lines)


def write_outputs(cases: list[dict[str, Any]], settings: dict[str, Any], out: Path) -> list[Path]:
    """``pushes.csv``, ``pushes.json`` and ``pushes.png`` in ``out``."""
    from rtgait.outputs import write_text_atomic

    out.mkdir(parents=True, exist_ok=True)
    columns = list(cases[0]) if cases else []
    lines = [",".join(columns)] + [",".join(str(c[k]) for k in columns) for c in cases]
    paths = [write_text_atomic(out / "pushes.csv", "\n".join(lines) + "\n")]
    document = {"settings": settings, "cases": cases}
    paths.append(write_text_atomic(out / "pushes.json", json.dumps(document, indent=2) + "\n"))
    paths.append(plot(cases, settings, out / "pushes.png"))
    return paths


def plot(cases: list[dict[str, Any]], settings: dict[str, Any], path: Path) -> Path:
    """A polar plot per phase: the largest impulse survived (N s, radius) against the push's direction."""
    from rtgait.viz.style import new_figure, save

    phases = [p for p in PHASES if any(c["phase"] == p for c in cases)]
    figure = new_figure(5.4 * len(phases), 5.6)
    colours = {"open-loop": "tab:gray", "stabilized": "tab:orange", "adaptive": "tab:blue"}
    top = max([c["max_impulse_Ns"] for c in cases] + [c.get("sole_bound_Ns", 0.0) + c.get("lean_bound_Ns", 0.0)
                                                        for c in cases] + [1.0])  # fmt: skip
    for i, phase in enumerate(phases):
        ax = figure.add_subplot(1, len(phases), i + 1, projection="polar")
        site = settings["sites"][phase]
        for controller in dict.fromkeys(c["controller"] for c in cases):
            rows = sorted((c for c in cases if c["phase"] == phase and c["controller"] == controller),
                          key=lambda c: c["direction_deg"])  # fmt: skip
            if not rows:
                continue
            theta = [math.radians(c["direction_deg"]) for c in rows] + [math.radians(rows[0]["direction_deg"])]
            radius = [c["max_impulse_Ns"] for c in rows] + [rows[0]["max_impulse_Ns"]]
            ax.plot(theta, radius, marker="o", ms=3, lw=1.4, color=colours.get(controller), label=controller)
        rows = sorted((c for c in cases if c["phase"] == phase), key=lambda c: c["direction_deg"])
        if rows and "sole_bound_Ns" in rows[0]:
            bound = {c["direction_deg"]: c["sole_bound_Ns"] + c["lean_bound_Ns"] for c in rows}
            angles = [*sorted(bound), min(bound)]
            ax.plot([math.radians(a) for a in angles], [bound[a] for a in angles], ls="--", lw=1.0, color="k",
                    label="in-place bound (sole + lean)")  # fmt: skip
        ax.set_ylim(0.0, 1.1 * top)
        resolution = f"within {settings['tolerance_Ns']:g} N s"
        ax.set_title(f"{phase} support (step {site['step']}, {site['stance_side']} foot stance)\n"
                     f"largest impulse survived [N s], {resolution}", fontsize=9)  # fmt: skip
        # Only the directions pushed are named: the lines between them join measurements, they are none.
        measured = sorted({c["direction_deg"] for c in rows})
        ax.set_xticks([math.radians(a) for a in measured])
        # The world's directions, named relative to the stance foot as in the table (fwd-out: forward and outward).
        named = Site(**site)
        short = {"forward": "fwd", "backward": "back", "outward": "out", "inward": "in"}
        labels = []
        for a in measured:
            name = direction_name(named, a)
            labels.append("-".join(short.get(part, part) for part in name.split("-")))
        ax.set_xticklabels(labels, fontsize=8)
    handles, labels = figure.axes[0].get_legend_handles_labels()
    figure.legend(handles, labels, loc="outside lower center", ncol=len(labels), fontsize=8, frameon=False)
    state = settings.get("state")
    on = f"\nthe controller on the {state} state" if state else ""  # a line of its own: the figure may be narrow
    figure.suptitle(f"{settings['robot']} in MuJoCo, {settings['scenario']}: 0.1 s pushes on the base{on}", fontsize=10)
    return save(figure, path)


def print_bounds(
    robot_name: str, scenario_name: str, phases: Sequence[str], directions: int, max_lean: float | None, as_json: bool
) -> None:
    """``--bounds-only``: the in-place bounds (N s) per phase and direction, as a table or a JSON document."""
    robot, _, scenario = _setup(robot_name, scenario_name)
    angles = [360.0 * i / directions for i in range(directions)]
    rows = []
    for phase in phases:
        site = push_site(scenario, robot, phase)
        for angle, (sole, lean) in in_place_bounds(scenario, robot, site, angles, max_lean).items():
            rows.append({"phase": phase, "direction_deg": angle, "direction": direction_name(site, angle),
                         "sole_bound_Ns": sole, "lean_bound_Ns": lean})  # fmt: skip
    if as_json:
        json.dump({"robot": robot.name, "mass": robot.mass, "scenario": scenario.name, "bounds": rows}, sys.stdout,
                  indent=2)  # fmt: skip
        print()
        return
    print(f"{robot.name} ({robot.mass:.1f} kg), {scenario.name}: in-place bounds (N s), from the planned DCM")
    for phase in phases:
        mine = [r for r in rows if r["phase"] == phase]
        print(f"{phase} support: " + ", ".join(f"{r['direction_deg']:g} deg = {r['direction']}" for r in mine))
        print(f"{'sole':<11}" + "".join(f"{r['sole_bound_Ns']:>8.1f}" for r in mine))
        print(f"{'lean':<11}" + "".join(f"{r['lean_bound_Ns']:>8.1f}" for r in mine))
        print(f"{'sole + lean':<11}" + "".join(f"{r['sole_bound_Ns'] + r['lean_bound_Ns']:>8.1f}" for r in mine))


def main(argv: Sequence[str] | None = None) -> None:
    from rtgait.core.planner.levels import CONTROLLER_LEVELS
    from rtgait.estimation.estimator import DEFAULT_STATE, STATE_SOURCES
    from rtgait.interface.command import GAIN_SETS

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="talos", help="built-in robot or description file (default talos)")
    parser.add_argument("--controller", action="append", choices=CONTROLLER_LEVELS, help="level(s) (default adaptive)")
    parser.add_argument("--state", choices=STATE_SOURCES, help=f"what the controller acts on (default {DEFAULT_STATE})")
    parser.add_argument("--json", action="store_true", help="print the JSON document instead of the table")
    parser.add_argument("--scenario", default="fig8", help="built-in scenario or TOML file (default fig8)")
    parser.add_argument("--phase", action="append", choices=PHASES, help="push instant(s) (default both)")
    parser.add_argument("--directions", type=int, default=8, help="directions, evenly spaced (default 8)")
    parser.add_argument("--tolerance", type=float, default=1.0, help="bisection resolution, N s (default 1)")
    parser.add_argument("--workers", type=int, default=2, help="worker processes (default 2)")
    parser.add_argument("--out", type=Path, help="output folder (default out/pushes-<robot>)")
    parser.add_argument("--physics-dt", type=float, default=None, help="physics step, s (default: the robot's)")
    parser.add_argument("--gains", choices=GAIN_SETS, default="stiff",
                        help="the drives' own gains: stiff (default) or robot, with feed-forward torques")  # fmt: skip
    parser.add_argument("--drive", choices=("position", "torque"), default="position",
                        help="position (default) or torque: a tenth of the robot's gains, with FF torques")  # fmt: skip
    parser.add_argument(
        "--option", action="append", default=[], metavar="NAME=JSON",
        help="a ControllerOptions field of the closed-loop levels, e.g. com_reference='\"planned\"' (for experiments)",
    )  # fmt: skip
    parser.add_argument("--bounds-only", action="store_true", help="print the in-place bounds only (no physics)")
    args = parser.parse_args(argv)
    if not 1 <= args.directions <= 72 or not args.tolerance > 0.0 or not 1 <= args.workers <= (os.cpu_count() or 1) * 4:
        parser.error("--directions must be 1-72, --tolerance > 0 N s, --workers 1 to 4 per core")
    controllers = args.controller or ["adaptive"]
    phases = args.phase or list(PHASES)
    began = time.perf_counter()
    try:
        options = {name: json.loads(value) for name, value in (text.split("=", 1) for text in args.option)}
    except ValueError:
        parser.error("--option needs NAME=JSON, e.g. replan_dcm_error=0.04")
    try:  # an unknown robot or scenario, or a robot without its own gains: one line, before any run
        _init_worker(args.physics_dt, args.state, args.gains, args.drive)
        _setup(args.robot, args.scenario)
    except (ValueError, LookupError) as error:  # RobotError, RobotDataError, ScenarioError
        parser.error(str(error))
    if args.bounds_only:
        print_bounds(args.robot, args.scenario, phases, args.directions, options.get("max_lean"), args.json)
        return
    cases, settings = run(args.robot, args.scenario, controllers, phases, args.directions, args.tolerance,
                          args.workers, progress=sys.stderr.isatty(), options=options,
                          physics_dt=args.physics_dt, state=args.state, gains=args.gains,
                          drive=args.drive)  # fmt: skip
    settings["seconds"] = time.perf_counter() - began
    out = args.out or Path("out") / f"pushes-{settings['robot']}"
    write_outputs(cases, settings, out)
    if args.json:
        json.dump({"settings": settings, "cases": cases}, sys.stdout, indent=2)
        print()
        return
    print(f"{settings['robot']} ({settings['mass']:.1f} kg) in MuJoCo, {settings['scenario']}, on the "
          f"{settings['state']} state, {settings['gains']} gains, {settings['drive']} drive: 0.1 s pushes on the "
          f"base, step {cases[0]['step'] if cases else '-'}, bisection to {args.tolerance:g} N s, "
          f"{settings['seconds']:.0f} s on {args.workers} workers; written to {out}{os.sep}")  # fmt: skip
    print(table(cases))


if __name__ == "__main__":
    main()
