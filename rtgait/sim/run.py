"""One scenario walked in physics, and its output files: what the command line's ``rtgait simulate`` needs.

``simulate(scenario, robot)`` builds the MuJoCo model (or reuses one), plans the scenario with the robot's COG
height, step width and sole, and runs the closed loop of :mod:`rtgait.sim.loop`, one tick per control period
(``control_dt``) with ``physics_dt`` steps of physics in it. ``write_sim_outputs(result, out_dir)`` writes
``sim.csv`` (one row per control tick, with the joint torques), ``summary.json`` and ``zmp_sim.png`` (planned vs
measured ZMP), each to a temporary name first and renamed when complete, and returns the summary.

Before a long run, :func:`planned_walk` gives the walk the robot will be asked to follow (to check that it can,
kinematically) and :func:`simulated_time` how long the run will be; :func:`mujoco_messages` collects MuJoCo's
warnings, which it would otherwise append to a file in the working folder.
"""

from __future__ import annotations

import contextlib
import dataclasses
import inspect
import json
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from rtgait.core.online import OnlinePlanner, VelocityCommand
from rtgait.core.rollout import Rollout, ScheduledChange, rollout
from rtgait.outputs import write_atomic, write_text_atomic
from rtgait.robot.model import RobotModel
from rtgait.robot.motion import robot_scenario
from rtgait.scenario import Scenario
from rtgait.sim.loop import LoopOptions, Push, SimResult, Stabilizer, run_closed_loop
from rtgait.sim.model import SimConfig, SimModel, build_sim_model

__all__ = [
    "SIM_CSV_COLUMNS",
    "SIM_FILES",
    "TORQUE_COLUMN_PREFIX",
    "loop_options",
    "mujoco_messages",
    "planned_walk",
    "replay_paths",
    "sim_config",
    "sim_csv_columns",
    "simulate",
    "simulated_time",
    "write_sim_outputs",
    "write_sim_replay",
]

SIM_CSV_COLUMNS = (
    "t", "zmp_x", "zmp_y", "zmp_planned_x", "zmp_planned_y",
    "base_x", "base_y", "base_z", "base_qx", "base_qy", "base_qz", "base_qw",
    "cog_x", "cog_y", "cog_z", "left_contact", "right_contact",
)  # fmt: skip
"""The first columns of ``sim.csv``: time (s), measured and planned ZMP (m; measured is ``nan`` while no foot
touches the floor), base position (m) and orientation (unit quaternion x, y, z, w), measured COG (m), feet on the
floor (0/1). Then one column ``tau_<joint>`` per actuated joint (:data:`TORQUE_COLUMN_PREFIX`): the joint torque
the servo applied (N m), its mean over the tick's physics substeps. One row per control tick."""

TORQUE_COLUMN_PREFIX = "tau_"
"""Prefix of the joint torque columns of ``sim.csv``, followed by the URDF joint name."""

SIM_FILES = ("sim.csv", "summary.json", "zmp_sim.png")
"""Files written by :func:`write_sim_outputs` (the figure only when asked for)."""

_FLOAT_FORMAT = "%.10g"


def loop_options(
    push: Push | Sequence[Push] | None = None,
    stabilizer: bool | Stabilizer = False,
    options: LoopOptions | None = None,
) -> LoopOptions:
    """``options`` (default :class:`LoopOptions`) with these pushes and stabiliser (see :func:`simulate`)."""
    if push is None:
        pushes: tuple[Push, ...] = ()
    elif isinstance(push, Push):
        pushes = (push,)
    else:
        pushes = tuple(push)
    feedback = stabilizer if isinstance(stabilizer, Stabilizer) else (Stabilizer() if stabilizer else None)
    return dataclasses.replace(options or LoopOptions(), stabilizer=feedback, pushes=pushes)


def simulate(
    scenario: Scenario,
    robot: RobotModel | str,
    *,
    velocity: VelocityCommand | tuple[float, float, float] | None = None,
    push: Push | Sequence[Push] | None = None,
    stabilizer: bool | Stabilizer = False,
    progress: Callable[[float], None] | None = None,
    sim: SimModel | None = None,
    config: SimConfig | None = None,
    options: LoopOptions | None = None,
    control_dt: float | None = None,
    physics_dt: float | None = None,
) -> SimResult:
    """Walk ``scenario`` with ``robot`` in MuJoCo, planner + whole-body IK + physics in closed loop, one tick per
    control period (the robot's: 1 kHz for Talos, 500 Hz for G1).

    The scenario is walked with the robot's nominal COG height, its step width at half-sitting and its sole
    (:func:`rtgait.robot.motion.robot_scenario`); its footstep changes are handed to the planner at their
    connection mode's deadline. The walk is not checked for reach first (``rtgait simulate`` does, with
    :func:`planned_walk`), and MuJoCo's warnings go to its default handler unless the call is wrapped in
    :func:`mujoco_messages`.

    Args:
        scenario: the walk (a built-in scenario or one loaded from a file).
        robot: a loaded robot, or a built-in robot name / description file path.
        velocity: walk by velocity command ``(vx, vy, wz)`` (m/s, m/s, rad/s) instead of the scenario's footsteps:
            ``scenario.steps`` steps, then a closing step; the scenario's changes do not apply. Without it, a
            scenario with a ``[guide]`` path is walked led by the hand (:func:`rtgait.sim.guided.simulate_guided`).
        push: external force(s) on the robot, e.g. ``Push(start=5.0, duration=0.1, force=(0, 100, 0))``; times
            are from the start of the run, whose walk begins after the start transition
            (:attr:`SimResult.walk_start`).
        stabilizer: ``True`` for the default ZMP feedback (:class:`~rtgait.sim.loop.Stabilizer`), or one with your
            gains; ``False`` (default): the planner alone, as in the paper.
        progress: called now and then with the fraction simulated, for long runs.
        sim: a MuJoCo model built for this robot, to reuse (building one takes about 0.5 s with meshes).
        config: physics parameters for a new model (ignored when ``sim`` is given).
        options: further loop settings (start transition, fall limits); ``changes``, ``pushes``, ``stabilizer``
            and ``stop_after_steps`` in it are replaced by the ones derived from the arguments above.
        control_dt: the control period (s), overriding ``config`` and the robot description's
            ``actuation.control_dt``; with ``sim``, it must be the model's.
        physics_dt: the physics step (s), overriding ``config``'s (default 1 ms); it must divide the control
            period; with ``sim``, it must be the model's.

    Returns:
        The per-tick record and the outcome.

    Raises:
        ValueError: ``sim`` was built for another robot or with other periods, a physics step longer than the
            control period or not dividing it, or a bad push / velocity.
        rtgait.robot.description.RobotError: the robot cannot be loaded or built.
    """
    if not isinstance(robot, RobotModel):
        robot = RobotModel.load(robot)
    if sim is None:
        sim = build_sim_model(robot, sim_config(config, control_dt, physics_dt))
    elif sim.robot is not robot:
        raise ValueError(f"the simulation model was built for another model of {sim.robot.name!r}")
    else:
        _check_periods(sim, control_dt, physics_dt)
    base_options = loop_options(push, stabilizer, options)
    walk = robot_scenario(scenario, robot)
    if walk.guide is not None and velocity is None:
        # Led by the hand: the pull sets the steps (rtgait.sim.guided); the scenario's footsteps do not apply.
        from rtgait.sim.guided import simulate_guided

        return simulate_guided(sim, walk, dataclasses.replace(base_options, changes=()), progress=progress)[0]
    planner, changes, stop_after = _planner(walk, velocity)
    walk_options = dataclasses.replace(base_options, changes=changes, stop_after_steps=stop_after)
    return run_closed_loop(sim, planner, walk_options, progress=progress)


def sim_config(
    config: SimConfig | None = None, control_dt: float | None = None, physics_dt: float | None = None
) -> SimConfig:
    """``config`` (default :class:`SimConfig`) with these periods, when given (s).

    Raises:
        ValueError: a period that is not > 0, a physics step longer than the control period, or one that does not
            divide it (checked here when both are known, else when the model is built).
    """
    config = config or SimConfig()
    changes: dict[str, float] = {}
    if control_dt is not None:
        changes["control_dt"] = control_dt
    if physics_dt is not None:
        changes["physics_dt"] = physics_dt
    return dataclasses.replace(config, **changes) if changes else config


def _check_periods(sim: SimModel, control_dt: float | None, physics_dt: float | None) -> None:
    for name, asked, built in (("control_dt", control_dt, sim.control_dt), ("physics_dt", physics_dt, sim.timestep)):
        if asked is not None and abs(asked - built) > 1e-12:
            raise ValueError(f"{name} {asked:g} s differs from the given simulation model's {built:g} s")


def _planner(
    walk: Scenario, velocity: VelocityCommand | tuple[float, float, float] | None
) -> tuple[OnlinePlanner, tuple[ScheduledChange, ...], int | None]:
    """The planner of ``walk`` (by its footsteps, or by the ``velocity`` command), the changes to hand it and,
    for a walk by command, the steps after which it stops."""
    config = walk.planner_config()
    if velocity is None:
        return OnlinePlanner(config, walk.strides()), walk.changes, None
    command = velocity if isinstance(velocity, VelocityCommand) else VelocityCommand(*velocity)
    planner = OnlinePlanner(config, None)
    planner.set_velocity(command.vx, command.vy, command.wz)
    return planner, (), walk.steps


def planned_walk(
    scenario: Scenario, robot: RobotModel, velocity: VelocityCommand | tuple[float, float, float] | None = None
) -> Rollout:
    """The walk :func:`simulate` asks ``robot`` to follow, planned alone (no physics) at the scenario's period.

    Hand it to :func:`rtgait.robot.motion.whole_body_motion` to refuse, before simulating, a walk the robot cannot
    reach, exactly as ``rtgait plan --robot`` does. A walk of footsteps is planned whole, with its changes; a walk
    by ``velocity`` command over its ``steps`` steps (the closing step and the settling add nothing a walk of
    footsteps would not check); a hand-guided walk, whose steps the pull sets only while walking, over its start
    and one step in place: the robot's COG height and stance.
    """
    walk = robot_scenario(scenario, robot)
    guided = walk.guide is not None and velocity is None
    planner, changes, stop_after = _planner(walk, VelocityCommand() if guided else velocity)
    if stop_after is None:
        return rollout(planner, walk.dt, walk.sole, changes)
    steps = 1 if guided else stop_after
    return rollout(planner, walk.dt, walk.sole, duration=walk.timing.start + steps * walk.timing.step_period)


def simulated_time(
    scenario: Scenario,
    *,
    velocity: VelocityCommand | tuple[float, float, float] | None = None,
    options: LoopOptions | None = None,
) -> float:
    """How much time (s) :func:`simulate` will simulate: the start transition, the walk until its COG is at rest
    and ``options.after``; for a hand-guided walk, the start transition, the person's walk and the time the robot
    is given to catch up with them (:func:`rtgait.sim.guided.guided_options`)."""
    options = options or LoopOptions()
    lead = options.start_ramp + options.start_hold
    if scenario.guide is not None and velocity is None:
        from rtgait.sim.guided import guided_options

        # guided_options owns the catch-up margin; reading its default keeps one source for the number.
        catch_up = inspect.signature(guided_options).parameters["margin"].default
        return lead + scenario.guide.duration + catch_up
    return lead + scenario.duration + options.after


@contextlib.contextmanager
def mujoco_messages() -> Iterator[list[str]]:
    """Collect MuJoCo's warnings while the block runs into the list it yields, and print none.

    Without a handler MuJoCo prints each warning and appends it to ``MUJOCO_LOG.TXT`` in the working folder, a
    file outside any run's outputs. (Its errors reach Python as exceptions and write nothing.) The handler is
    global to the process: the previous one is restored when the block ends.
    """
    previous = mujoco.get_mju_user_warning()
    messages: list[str] = []
    mujoco.set_mju_user_warning(messages.append)
    try:
        yield messages
    finally:
        mujoco.set_mju_user_warning(previous)


def sim_csv_columns(result: SimResult) -> tuple[str, ...]:
    """The columns of ``result``'s ``sim.csv``: :data:`SIM_CSV_COLUMNS`, then ``tau_<joint>`` per actuated joint."""
    return SIM_CSV_COLUMNS + tuple(TORQUE_COLUMN_PREFIX + name for name in result.joint_names)


def _table(result: SimResult) -> np.ndarray:
    torque = result.torque if result.torque.shape[0] == len(result.times) else np.zeros((len(result.times), 0))
    return np.column_stack(
        [
            result.times,
            result.zmp,
            result.zmp_planned,
            result.base_position,
            result.base_quaternion,
            result.cog,
            result.contact.astype(float),
            torque,
        ]
    )


def _write_csv(result: SimResult, path: Path) -> None:
    table = _table(result)
    columns = sim_csv_columns(result)[: table.shape[1]]
    with open(path, "w", encoding="utf-8", newline="") as stream:
        stream.write(",".join(columns) + "\n")
        # Contacts as integers; every other column in 10 significant digits (sub-micrometre positions).
        formats = [_FLOAT_FORMAT] * (len(SIM_CSV_COLUMNS) - 2) + ["%d", "%d"]
        formats += ["%.6g"] * (len(columns) - len(SIM_CSV_COLUMNS))  # torques: 1 uN m on 100 N m is plenty
        np.savetxt(stream, table, fmt=formats, delimiter=",")


def plot_zmp_sim(result: SimResult, path: Path, title: str = "") -> None:
    """Planned and measured ZMP, x and y against time, with the walk's start, the double supports, and the
    tip-over and fall marked; written to ``path`` (PNG)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=(10.0, 6.0), dpi=100, layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.subplots(2, 1, sharex=True)
    t = result.times
    double = result.support == 0
    for axis, ax in enumerate(axes):
        # Shade the planned double supports: the measured ZMP moves between the feet there.
        edges = np.flatnonzero(np.diff(np.r_[0, double.astype(int), 0]))
        for start, stop in zip(edges[::2], edges[1::2], strict=True):
            ax.axvspan(t[start], t[min(stop, len(t) - 1)], color="0.9", lw=0, zorder=0)
        ax.plot(t, result.zmp_planned[:, axis], color="tab:blue", lw=1.4, label="planned ZMP")
        ax.plot(t, result.zmp[:, axis], color="tab:orange", lw=0.8, label="measured ZMP (contact CoP)")
        ax.plot(t, result.cog[:, axis], color="tab:red", lw=0.8, ls="--", label="measured COG")
        ax.axvline(result.walk_start, color="0.4", lw=0.8, ls=":", label="walk starts")
        if result.tip_time is not None:
            ax.axvline(result.tip_time, color="tab:purple", lw=1.2, ls="--", label=f"tipped ({result.tip_time:.2f} s)")
        if result.fell and result.fall_time is not None:
            ax.axvline(result.fall_time, color="tab:red", lw=1.6, label=f"fell ({result.fall_time:.2f} s)")
        ax.set_ylabel(f"{'xy'[axis]} (m)")
        ax.grid(True, lw=0.3)
    axes[0].legend(loc="upper left", fontsize=8, ncols=2)
    axes[1].set_xlabel("time (s)")
    outcome = (
        f"fell at {result.fall_time:.2f} s ({result.fall_cause})"
        if result.fell
        else f"walked {result.steps_completed}/{result.steps_planned} steps"
    )
    if result.tip_time is not None:
        outcome += f", a foot tipped over at {result.tip_time:.2f} s"
    axes[0].set_title(f"{title + ': ' if title else ''}{result.robot} in MuJoCo, {outcome}", fontsize=10)
    figure.savefig(path, format="png")


def replay_paths(result: SimResult) -> tuple[np.ndarray, np.ndarray]:
    """The measured COG (m, shape ``(m, 3)``) and ZMP (m, shape ``(m, 2)``) at the replay's ticks.

    The measured ZMP is NaN while no foot touches the floor (and the replay cannot draw NaN): such rows hold the
    last measured value, or the planned ZMP before the first measurement.
    """
    index = result.replay_index
    cog = result.cog[index]
    zmp = result.zmp[index].copy()
    last = result.zmp_planned[index[0]] if len(index) else np.zeros(2)
    for row in zmp:  # a few hundred rows: a plain loop is clearer than a vectorised forward fill
        if np.isfinite(row).all():
            last = row.copy()
        else:
            row[:] = last
    return cog, zmp


def write_sim_replay(
    result: SimResult, robot: RobotModel, path: str | Path, *, sole: Any = None, title: str = ""
) -> Path:
    """Write ``path`` (HTML): the 3D replay of the SIMULATED motion, with the planner's footprints, the measured
    COG and the measured ZMP (needs meshcat; see :func:`rtgait.viz.replay.write_replay_html`).

    Args:
        result: a simulated walk, with its configurations recorded (:attr:`SimResult.replay_q`).
        robot: the robot it was simulated with (its full model and visual meshes are drawn).
        path: the HTML file; its folder must exist.
        sole: the footprints' sole rectangle (m), e.g. the walked scenario's ``sole``; the replay's default if
            ``None``.
        title: the page title.

    Returns:
        The path written.

    Raises:
        ValueError: fewer than two configurations were recorded, or they are for another robot.
    """
    from rtgait.robot.pipeline import visual_model
    from rtgait.viz.replay import write_replay_html

    if len(result.replay_index) < 2:
        raise ValueError("the replay needs at least two recorded configurations (the run was too short)")
    if result.replay_q.shape[1] != robot.full_model.nq:
        raise ValueError(f"the recorded configurations are not those of {robot.name}'s full model")
    cog, zmp = replay_paths(result)
    return write_replay_html(
        path,
        robot.full_model,
        visual_model(robot),
        result.replay_times,
        result.replay_q,
        footprints=result.footprints,
        sole=sole,
        cog=cog,
        zmp=zmp,
        title=title or f"rtgait: {result.robot} in MuJoCo",
    )


def write_sim_outputs(
    result: SimResult,
    out_dir: str | Path,
    *,
    figure: bool = True,
    title: str = "",
    extra: dict[str, Any] | None = None,
    replay: RobotModel | None = None,
    sole: Any = None,
) -> dict[str, Any]:
    """Write ``sim.csv``, ``summary.json``, with ``figure`` ``zmp_sim.png`` and with ``replay`` ``replay.html``
    into ``out_dir``.

    Args:
        result: the simulated walk.
        out_dir: folder, created if missing; files of the same names are replaced, others are left alone.
        figure: also draw ``zmp_sim.png`` (needs matplotlib).
        title: prefix of the figure's and the replay's title (e.g. the scenario's name).
        extra: more entries for the summary (e.g. the scenario's name).
        replay: the robot simulated, to write the 3D replay of the simulated motion (:func:`write_sim_replay`,
            needs meshcat).
        sole: the replay's footprint rectangle (m): the sole the walk was planned with.

    Returns:
        The summary, also written as ``summary.json``: ``fell``, ``fall_time`` (s or null), ``fall_cause``,
        ``tipped``, ``tip_time``, ``steps_planned``, ``steps_completed``, ``distance_walked`` (m),
        ``zmp_tracking_error_rms`` and ``_max`` (m, single support), ``simulated_time`` and ``wall_time`` (s),
        ``real_time_factor``, ``walk_start`` and ``walk_end`` (s), ``legs_touched``, ``control_dt`` and
        ``physics_dt`` (s), ``rows`` and ``files``.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    files = ["sim.csv", "summary.json"]
    write_atomic(out / "sim.csv", lambda path: _write_csv(result, path))
    if figure:
        write_atomic(out / "zmp_sim.png", lambda path: plot_zmp_sim(result, path, title))
        files.append("zmp_sim.png")
    if replay is not None:
        label = f"{title} on {replay.name}" if title else replay.name
        write_sim_replay(result, replay, out / "replay.html", sole=sole, title=f"rtgait: {label} in MuJoCo")
        files.append("replay.html")
    summary: dict[str, Any] = {**(extra or {}), **result.summary(), "rows": len(result.times), "files": files}
    write_text_atomic(out / "summary.json", json.dumps(summary, indent=2, allow_nan=False) + "\n")
    return summary
