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
from collections.abc import Callable, Iterator, Sequence

import mujoco

from rtgait.control.control_table import at_gains, control_options, walk_defaults
from rtgait.control.controller import ControllerOptions, WalkingController, make_controller
from rtgait.core.analysis.rollout import Rollout, ScheduledChange, rollout
from rtgait.core.obstacle.avoid import ObstacleReaction
from rtgait.core.planner.levels import ControllerLevel, check_level
from rtgait.core.planner.online import OnlinePlanner, VelocityCommand
from rtgait.core.push import Push
from rtgait.io.sim_files import (
    SIM_CSV_COLUMNS,
    SIM_FILES,
    TORQUE_COLUMN_PREFIX,
    replay_paths,
    sim_csv_columns,
    write_sim_outputs,
    write_sim_replay,
)
from rtgait.robot.controller_info import robot_info
from rtgait.robot.model import RobotModel
from rtgait.robot.motion import robot_scenario, walking_robot
from rtgait.scenario.scenario import Scenario
from rtgait.sim.loop import LoopOptions, SimResult
from rtgait.sim.model import SimConfig, SimModel, build_sim_model
from rtgait.sim.run_loop import run_sim_loop

__all__ = [
    "SIM_CSV_COLUMNS",
    "SIM_FILES",
    "TORQUE_COLUMN_PREFIX",
    "loop_options",
    "mujoco_messages",
    "planned_walk",
    "replay_paths",
    "robot_and_scenario_options",
    "sim_config",
    "sim_csv_columns",
    "simulate",
    "simulated_time",
    "write_sim_outputs",
    "write_sim_replay",
]


def loop_options(push: Push | Sequence[Push] | None = None, options: LoopOptions | None = None) -> LoopOptions:
    """``options`` (default :class:`LoopOptions`) with these pushes (see :func:`simulate`)."""
    if push is None:
        pushes: tuple[Push, ...] = ()
    elif isinstance(push, Push):
        pushes = (push,)
    else:
        pushes = tuple(push)
    return dataclasses.replace(options or LoopOptions(), pushes=pushes)


def simulate(
    scenario: Scenario,
    robot: RobotModel | str,
    *,
    controller: ControllerLevel = "adaptive",
    controller_options: ControllerOptions | None = None,
    velocity: VelocityCommand | tuple[float, float, float] | Sequence[tuple[float, float, float, float]] | None = None,
    push: Push | Sequence[Push] | None = None,
    progress: Callable[[float], None] | None = None,
    sim: SimModel | None = None,
    config: SimConfig | None = None,
    options: LoopOptions | None = None,
    control_dt: float | None = None,
    physics_dt: float | None = None,
) -> SimResult:
    """Walk ``scenario`` with ``robot`` in MuJoCo, in closed loop at a controller level: measurement, controller,
    whole-body IK and physics once per control period (the robot's: 1 kHz for Talos, 500 Hz for G1).

    The scenario is walked with the robot's nominal COG height, its step width at half-sitting and its sole
    (:func:`rtgait.robot.motion.robot_scenario`); its footstep changes are handed to the planner at their
    connection mode's deadline. The walk is not checked for reach first (``rtgait simulate`` does, with
    :func:`planned_walk`), and MuJoCo's warnings go to its default handler unless the call is wrapped in
    :func:`mujoco_messages`.

    Args:
        scenario: the walk (a built-in scenario or one loaded from a file).
        robot: a loaded robot, or a built-in robot name / description file path.
        controller: ``"adaptive"`` (default: feedback, foot force control, measured-state replanning,
            re-anchoring, step adjustment, landing detection), ``"stabilized"`` (feedback and foot force control)
            or ``"open-loop"`` (the plan alone, the paper's assumption); :mod:`rtgait.control.controller`.
        controller_options: the levels' gains and landing handling; default :class:`ControllerOptions` with the
            ``[control]`` tables of the robot description and then of the scenario applied
            (:func:`robot_and_scenario_options`).
        velocity: walk by velocity command ``(vx, vy, wz)`` (m/s, m/s, rad/s) instead of the scenario's footsteps:
            ``scenario.steps`` steps, then a closing step; the scenario's changes do not apply. A sequence of
            ``(t, vx, vy, wz)`` changes the command at each time ``t`` (s, walk clock; the first at ``t <= 0`` is the
            start's). Without it, a scenario with a ``[guide]`` path is walked led by the hand
            (:func:`rtgait.sim.guided.simulate_guided`).
        push: external force(s) on the robot, e.g. ``Push(start=5.0, duration=0.1, force=(0, 100, 0))``; times
            are on the walk's clock (0 when the walk starts, after the start transition).
        progress: called now and then with the fraction simulated, for long runs.
        sim: a MuJoCo model built for this robot, to reuse (building one takes about 0.5 s with meshes).
        config: physics parameters for a new model (ignored when ``sim`` is given).
        options: further loop settings (start transition, fall limits); ``changes``, ``pushes`` and
            ``stop_after_steps`` in it are replaced by the ones derived from the arguments above.
        control_dt: the control period (s), overriding ``config`` and the robot description's
            ``actuation.control_dt``; with ``sim``, it must be the model's.
        physics_dt: the physics step (s), overriding ``config``'s and the robot description's
            ``actuation.physics_dt``; it must divide the control period; with ``sim``, it must be the model's.

    Returns:
        The per-tick record and the outcome.

    Raises:
        ValueError: ``sim`` was built for another robot or with other periods, a physics step longer than the
            control period or not dividing it, an unknown controller, or a bad push (beyond physical sense:
            :meth:`Push.check`) or velocity, a ``[control]`` key or value the settings refuse.
        rtgait.robot.description.RobotError: the robot cannot be loaded or built.
    """
    check_level(controller)
    if not isinstance(robot, RobotModel):
        robot = RobotModel.load(robot)
    robot = walking_robot(robot, scenario)  # the COG height and toe release the scenario asks of it, if any
    walk = robot_scenario(scenario, robot)
    base_options = loop_options(push, options)
    for each in base_options.pushes:
        each.check(robot.mass, walk.cog_height, walk.gravity)
    if controller_options is None:
        gains = sim.config.gains if sim is not None else (config or SimConfig()).gains
        controller_options = robot_and_scenario_options(robot, scenario, gains=gains)
    if sim is None:
        terrain = None if walk.terrain is None else walk.terrain.terrain
        sim = build_sim_model(robot, sim_config(config, control_dt, physics_dt), walk.obstacles, terrain)
    elif sim.robot is not robot:
        raise ValueError(f"the simulation model was built for another model of {sim.robot.name!r}")
    else:
        _check_periods(sim, control_dt, physics_dt)
    if walk.guide is not None and velocity is None:
        # Led by the hand: the pull sets the steps (rtgait.sim.guided); the scenario's footsteps do not apply.
        from rtgait.sim.guided import simulate_guided

        return simulate_guided(
            sim, walk, dataclasses.replace(base_options, changes=()), controller=controller,
            controller_options=controller_options, progress=progress,
        )[0]  # fmt: skip
    command, schedule = _velocity_schedule(velocity)
    level, changes, stop_after = _controller(walk, command, controller, sim, controller_options)
    walk_options = dataclasses.replace(
        base_options, changes=changes, stop_after_steps=stop_after, velocity_changes=schedule,
        # The scenario's obstacles react when seen (a walk of footsteps), unless the caller made their reactions (to
        # read what they did).
        reactions=base_options.reactions or (obstacle_reactions(walk) if velocity is None else ()),
    )  # fmt: skip
    return run_sim_loop(sim, level, walk_options, progress=progress)


def obstacle_reactions(walk: Scenario) -> tuple[tuple[float, ObstacleReaction], ...]:
    """A reaction per obstacle of ``walk`` (as the robot walks it: its sole), each called when the obstacle is seen
    (:class:`~rtgait.core.obstacle.avoid.ObstacleReaction`, kept in the returned pairs for what it did)."""
    return tuple((box.seen_at, ObstacleReaction(box, walk.sole, walk.dt)) for box in walk.obstacles)


def robot_and_scenario_options(
    robot: RobotModel, scenario: Scenario, base: ControllerOptions | None = None, gains: str = "stiff"
) -> ControllerOptions:
    """``base`` (default :func:`~rtgait.control.control_table.walk_defaults` for the scenario's terrain) with the
    ``[control]`` table of ``robot``'s description as it applies at the drives' ``gains``
    (:func:`~rtgait.control.control_table.at_gains`) and then the one of ``scenario`` applied
    (:func:`rtgait.control.control_table.control_options`).

    Raises:
        rtgait.control.control_table.ControlSettingsError: a key or value the settings refuse.
    """
    if base is None:
        base = walk_defaults(None if scenario.terrain is None else scenario.terrain.terrain.kind)
    robot_layers = at_gains(robot.description.control, gains, f"robot {robot.name}")
    return control_options(*robot_layers, (f"scenario {scenario.name}", scenario.control), base=base)


def _velocity_schedule(
    velocity: VelocityCommand | tuple[float, float, float] | Sequence[tuple[float, float, float, float]] | None,
) -> tuple[VelocityCommand | tuple[float, float, float] | None, tuple[tuple[float, float, float, float], ...]]:
    """The command the walk starts with and the later changes ``(t, vx, vy, wz)`` of a ``velocity`` argument."""
    if velocity is None or isinstance(velocity, VelocityCommand):
        return velocity, ()
    items = list(velocity)
    if items and all(isinstance(v, int | float) for v in items):
        return tuple(items), ()  # type: ignore[return-value]  # one command (vx, vy, wz)
    schedule = tuple(tuple(float(v) for v in item) for item in items)
    if not schedule or any(len(item) != 4 for item in schedule):
        raise ValueError(f"velocity must be (vx, vy, wz) or a sequence of (t, vx, vy, wz), got {velocity!r}")
    first = schedule[0]
    if first[0] > 0.0:
        return (0.0, 0.0, 0.0), schedule  # type: ignore[return-value]
    return first[1:], schedule[1:]  # type: ignore[return-value]


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
    """The open-loop planner of ``walk`` (by its footsteps, or by the ``velocity`` command), the changes to hand it
    and, for a walk by command, the steps after which it stops."""
    config = walk.planner_config()
    if velocity is None:
        return OnlinePlanner(config, walk.strides()), walk.changes, None
    command = velocity if isinstance(velocity, VelocityCommand) else VelocityCommand(*velocity)
    planner = OnlinePlanner(config, None)
    planner.set_velocity(command.vx, command.vy, command.wz)
    return planner, (), walk.steps


def _controller(
    walk: Scenario,
    velocity: VelocityCommand | tuple[float, float, float] | None,
    level: ControllerLevel,
    sim: SimModel,
    options: ControllerOptions | None,
) -> tuple[WalkingController, tuple[ScheduledChange, ...], int | None]:
    """The controller of ``level`` for ``walk`` (by its footsteps, or by the ``velocity`` command), the changes to
    hand its planner and, for a walk by command, the steps after which it stops."""
    strides = walk.strides() if velocity is None else None
    info = robot_info(sim.robot, gains=sim.config.gains)  # the lean bounded by the hips' servos at the robot's gains
    controller = make_controller(
        level, walk.planner_config(), strides, walk.sole, info, dt=sim.control_dt, options=options,
        terrain=walk.placed_on if velocity is None else None,  # a walk by command has no footholds on it
    )  # fmt: skip
    if velocity is None:
        return controller, walk.changes, None
    command = velocity if isinstance(velocity, VelocityCommand) else VelocityCommand(*velocity)
    controller.planner.set_velocity(command.vx, command.vy, command.wz)
    return controller, (), walk.steps


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
    robot = walking_robot(robot, scenario)
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
