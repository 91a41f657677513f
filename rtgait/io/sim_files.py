"""The files of a walk in physics: ``sim.csv``, ``sim.parquet`` (the complete log, :mod:`rtgait.sim.log_file`),
``summary.json``, the ZMP figure, the 3D replay, ``model_error.json`` for a robot simulated with a model error, and
the lines ``rtgait simulate`` prints about them.

Every file is written to a temporary name first and renamed when complete (:mod:`rtgait.outputs`). Times are on the
walk's clock (t = 0 when the walk starts; the start transition from half-sitting at negative times).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from rtgait.core.geometry.terrain import TerrainKind
from rtgait.core.obstacle.box import Obstacle
from rtgait.io.obstacle_outputs import sim_obstacle_lines
from rtgait.io.summary_json import summary_text
from rtgait.outputs import write_atomic, write_text_atomic
from rtgait.robot.model import RobotModel
from rtgait.sim.log_file import LOG_FILE, parquet_available, write_sim_log
from rtgait.sim.result import SimResult
from rtgait.viz.walk_title import velocity_commands, walk_title

__all__ = [
    "MODEL_ERROR_FILE",
    "SIM_CSV_COLUMNS",
    "SIM_FILES",
    "TORQUE_COLUMN_PREFIX",
    "replay_paths",
    "sim_csv_columns",
    "sim_figure_file",
    "sim_report",
    "write_sim_outputs",
    "write_sim_replay",
]

SIM_CSV_COLUMNS = (
    "t", "zmp_x", "zmp_y", "zmp_planned_x", "zmp_planned_y", "zmp_command_x", "zmp_command_y",
    "zmp_motion_x", "zmp_motion_y",
    "base_x", "base_y", "base_z", "base_qx", "base_qy", "base_qz", "base_qw",
    "cog_x", "cog_y", "cog_z", "left_contact", "right_contact",
)  # fmt: skip
"""The first columns of ``sim.csv``: time (s, the walk's clock), the measured ZMP (m; ``nan`` while no foot touches
the floor), the planner's ZMP, the ZMP the controller commanded, the multibody ZMP of the commanded motion (m;
:mod:`rtgait.sim.result`), base position (m) and orientation (unit quaternion x, y, z, w), measured COG (m), feet on
the floor (0/1). Then one column ``tau_<joint>`` per actuated joint (:data:`TORQUE_COLUMN_PREFIX`): the joint torque
the servo applied (N m), its mean over the tick's physics substeps. One row per control tick."""

TORQUE_COLUMN_PREFIX = "tau_"
"""Prefix of the joint torque columns of ``sim.csv``, followed by the URDF joint name."""

SIM_FILES = ("sim.csv", "sim.parquet", "summary.json", "zmp_sim.png")
"""Files written by :func:`write_sim_outputs` with the figure in PNG (``sim.parquet`` when pyarrow is installed, the
figure when asked for); and :data:`MODEL_ERROR_FILE` for a run with a model error."""

MODEL_ERROR_FILE = "model_error.json"
"""Every drawn value of a run's model error, by body and joint (:meth:`rtgait.sim.model_error.ModelError.values`);
``summary.json`` has its compact record."""

_FLOAT_FORMAT = "%.10g"
_PHASE_LABELS = {0: "double support", 1: "left support", 2: "right support"}


def sim_figure_file(fmt: str = "png") -> str:
    """The ZMP figure's file name in the format ``fmt`` (``png``, ``pdf`` or ``svg``)."""
    if fmt not in ("png", "pdf", "svg"):
        raise ValueError(f"figure format must be png, pdf or svg, got {fmt!r}")
    return f"zmp_sim.{fmt}"


def sim_csv_columns(result: SimResult) -> tuple[str, ...]:
    """The columns of ``result``'s ``sim.csv``: :data:`SIM_CSV_COLUMNS`, then ``tau_<joint>`` per actuated joint."""
    return SIM_CSV_COLUMNS + tuple(TORQUE_COLUMN_PREFIX + name for name in result.joint_names)


def _table(result: SimResult) -> np.ndarray:
    return np.column_stack(
        [
            result.times,
            result.zmp,
            result.zmp_planned,
            result.zmp_command,
            result.zmp_commanded_motion,
            result.base_position,
            result.base_quaternion,
            result.cog,
            result.contact.astype(float),
            result.torque,
        ]
    )


def _write_csv(result: SimResult, path: Path) -> None:
    table = _table(result)
    columns = sim_csv_columns(result)
    with open(path, "w", encoding="utf-8", newline="") as stream:
        stream.write(",".join(columns) + "\n")
        # Contacts as integers; every other column in 10 significant digits (sub-micrometre positions).
        formats = [_FLOAT_FORMAT] * (len(SIM_CSV_COLUMNS) - 2) + ["%d", "%d"]
        formats += ["%.6g"] * (len(columns) - len(SIM_CSV_COLUMNS))  # torques: 1 uN m on 100 N m is plenty
        np.savetxt(stream, table, fmt=formats, delimiter=",")


def replay_paths(result: SimResult) -> tuple[np.ndarray, np.ndarray]:
    """The measured COG (m, shape ``(m, 3)``) and ZMP (m, shape ``(m, 2)``) at the replay's ticks.

    The measured ZMP is NaN while no foot touches the floor (and the replay cannot draw NaN): such rows hold the
    last measured value, or the planned ZMP before the first measurement.
    """
    index = result.replay_index
    cog = result.cog[index]
    first = result.zmp_planned[index[0]] if len(index) else np.zeros(2)
    return cog, _held(result.zmp[index], first)


def _held(values: np.ndarray, first: np.ndarray) -> np.ndarray:
    """``values`` with each row that is not finite replaced by the last finite row before it (``first`` before any)."""
    values, last = values.copy(), first
    for row in values:  # a few hundred rows: a plain loop is clearer than a vectorised forward fill
        if np.isfinite(row).all():
            last = row.copy()
        else:
            row[:] = last
    return values


def write_sim_replay(
    result: SimResult,
    robot: RobotModel,
    path: str | Path,
    *,
    sole: Any = None,
    title: str = "",
    background: str = "sky",
    terrain: TerrainKind | None = None,
    obstacles: Sequence[Obstacle] = (),
) -> Path:
    """Write ``path`` (HTML): the 3D replay of the SIMULATED motion from the walk's start on (its clock is the
    walk's), with the planner's footprints, the measured COG and ZMP, the planned COG (the IK's target) and ZMP, the
    planned phase under the clock, and the terrain and obstacles the walk was simulated with (needs meshcat; see
    :func:`rtgait.viz.replay.write_replay_html`).

    Args:
        result: a simulated walk, with its configurations recorded (:attr:`SimResult.replay_q`).
        robot: the robot it was simulated with (its full model and visual meshes are drawn).
        path: the HTML file; its folder must exist.
        sole: the footprints' sole rectangle (m), e.g. the walked scenario's ``sole``; the replay's default if
            ``None``.
        title: the page title.
        background: ``"sky"`` or ``"white"`` (:func:`rtgait.viz.replay.write_replay_html`).
        terrain, obstacles: the terrain (``None``: the flat floor) and the obstacles of the simulated scene.

    Returns:
        The path written.

    Raises:
        ValueError: fewer than two configurations were recorded in the walk, or they are for another robot.
    """
    from rtgait.robot.pipeline import visual_model
    from rtgait.viz.replay import write_replay_html

    keep = result.replay_times >= -1e-9  # the walk only: the replay's clock then reads the walk's
    if int(keep.sum()) < 2:
        raise ValueError("the replay needs at least two recorded configurations of the walk (the run was too short)")
    if result.replay_q.shape[1] != robot.full_model.nq:
        raise ValueError(f"the recorded configurations are not those of {robot.name}'s full model")
    cog, zmp = replay_paths(result)
    index = result.replay_index[keep]
    return write_replay_html(
        path,
        robot.full_model,
        visual_model(robot),
        result.times[index],
        result.replay_q[keep],
        footprints=result.footprints,
        sole=sole,
        cog=cog[keep],
        zmp=zmp[keep],
        # Once the stack damps (its safety layer tripped) there is no plan: the planned paths stop where it began.
        planned_cog=_held(result.cog_planned[index], result.cog_planned[index[0]]),
        planned_zmp=_held(result.zmp_planned[index], result.zmp_planned[index[0]]),
        phases=[_PHASE_LABELS[int(code)] for code in result.support[index]],
        path_source="measured",
        title=title or f"rtgait: {result.robot} in MuJoCo",
        background=background,
        terrain=terrain,
        obstacles=obstacles,
    )


def write_sim_outputs(
    result: SimResult,
    out_dir: str | Path,
    *,
    figure: bool = True,
    figure_format: str = "png",
    title: str = "",
    extra: dict[str, Any] | None = None,
    replay: RobotModel | None = None,
    sole: Any = None,
    log: bool = True,
    background: str = "sky",
    terrain: TerrainKind | None = None,
    obstacles: Sequence[Obstacle] = (),
) -> dict[str, Any]:
    """Write ``sim.csv``, ``summary.json``, with ``log`` ``sim.parquet`` (when pyarrow is installed and the result has
    its tick log), with ``figure`` ``zmp_sim.<figure_format>``, with ``replay`` ``replay.html`` and, for a robot
    simulated with a model error, :data:`MODEL_ERROR_FILE` into ``out_dir``.

    Args:
        result: the simulated walk.
        out_dir: folder, created if missing; files of the same names are replaced, others are left alone.
        figure: also draw the ZMP figure (needs matplotlib).
        figure_format: ``png``, ``pdf`` or ``svg``.
        title: prefix of the figure's and the replay's title (e.g. the scenario's name).
        extra: more entries for the summary (e.g. the scenario's name).
        replay: the robot simulated, to write the 3D replay of the simulated motion (:func:`write_sim_replay`,
            needs meshcat).
        sole: the replay's footprint rectangle (m): the sole the walk was planned with.
        background: the replay's background, ``"sky"`` or ``"white"``.
        log: also write ``sim.parquet``, the complete per-tick log (:mod:`rtgait.sim.log_file`, ``docs/logs.md``).
        terrain: the terrain walked on (``None``: the flat floor): drawn in the replay and, when not flat, in the
            figure's side view; ``extra``'s ``terrain`` entry (:func:`~rtgait.core.geometry.terrain.terrain_fields`)
            lets ``rtgait plot`` draw it again.
        obstacles: the scene's obstacles, drawn in the replay.

    Returns:
        The summary, also written as ``summary.json``: :meth:`SimResult.summary` (``fell``, ``fall_time``,
        ``fall_cause``, ``steps_completed``, ``steps_planned``, ``missed_landings``, ``step_adjustments``,
        ``foot_slip_max`` (m), ``zmp_error`` (m: ``vs_plan``, ``vs_command``, ``vs_commanded_motion``),
        ``real_time_factor``, ``pushes`` with their impulses (N s), ...), ``extra``, ``rows`` and ``files``.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    files = ["sim.csv", "summary.json"]
    write_atomic(out / "sim.csv", lambda path: _write_csv(result, path))
    if log and result.log is not None and parquet_available():
        facts = {**(extra or {}), "title": title}
        write_atomic(out / LOG_FILE, lambda path: write_sim_log(result, path, facts))
        files.insert(1, LOG_FILE)
    if figure:
        from rtgait.viz.sim_figure import ZmpSimRun, plot_zmp_sim

        name = sim_figure_file(figure_format)
        run = ZmpSimRun.from_result(result, title, terrain)
        write_atomic(out / name, lambda path: plot_zmp_sim(run, path, figure_format))
        files.append(name)
    if replay is not None:
        label = f"{title} on {replay.name}" if title else replay.name
        write_sim_replay(
            result, replay, out / "replay.html", sole=sole, title=f"rtgait: {label} in MuJoCo", background=background,
            terrain=terrain, obstacles=obstacles,
        )  # fmt: skip
        files.append("replay.html")
    if result.model_error is not None:
        values = result.model_error.values()
        write_text_atomic(out / MODEL_ERROR_FILE, summary_text(values))
        files.append(MODEL_ERROR_FILE)
    summary: dict[str, Any] = {**(extra or {}), **result.summary(), "rows": len(result.times), "files": files}
    write_text_atomic(out / "summary.json", summary_text(summary))
    return summary


def _mm(value: float | None) -> str:
    return "n/a" if value is None else f"{value * 1e3:.1f} mm"


def _spread(stats: dict[str, Any]) -> str:
    """An error measure of the summary as median, 95th percentile and RMS: the first two are the typical and the
    worse ticks, the RMS also weighs the few worst."""
    return f"median {_mm(stats['median'])}, 95th percentile {_mm(stats['p95'])}, RMS {_mm(stats['rms'])}"


def _left_out(stats: dict[str, Any]) -> str:
    """What the commanded-motion measure left out, if anything (:mod:`rtgait.sim.commanded_motion`)."""
    count = stats.get("reanchored_ticks", 0)
    return f" ({count} ticks of re-anchored swings left out)" if count else ""


def _state(summary: dict[str, Any]) -> str:
    """What the controller acted on, and the sensors' settings and model error it was estimated through."""
    sensors = summary.get("sensors")
    if summary.get("state") != "estimated" or sensors is None:
        text = "the controller on the simulator's truth"
    else:
        text = (
            f"the controller on the state estimated from the sensors (noise x{sensors['noise']:g}, latency "
            f"{sensors['latency']} period(s), seed {sensors['seed']})"
        )
    model_error = summary.get("model_error")
    if model_error:
        text += f"; the robot off its model (model error seed {model_error['seed']})"
    return text


def sim_report(summary: dict[str, Any], out: Path) -> str:
    """The lines ``rtgait simulate`` prints for a MuJoCo run written to ``out``: the walk and where its settings
    came from, the state the controller acted on (and on the estimate, its errors), the outcome, the ZMP errors,
    slip and steps, speed, MuJoCo's warnings if any, the outputs."""
    if summary["fell"]:
        outcome = f"FELL at {summary['fall_time']:.2f} s ({summary['fall_cause']})"
    else:
        outcome = f"walked {summary['steps_completed']} of {summary['steps_planned']} steps without falling"
        outcome += ", ended at rest" if summary["ended_at_rest"] else ", did NOT end at rest"
    if summary["tipped"]:
        outcome += f"; a loaded foot tipped over at {summary['tip_time']:.2f} s"
    if "guide" in summary:
        outcome += f"; led by the hand, the base ended {summary['guide']['base_error']:.3f} m from its goal"
    first = (summary.get("safety") or {}).get("first_event")
    if first is not None:
        outcome += f"; DAMPING from {first['t']:.3f} s ({first['kind']}: {first['detail']})"
    control, physics = summary["control_dt"] * 1e3, summary["physics_dt"] * 1e3
    title = walk_title(summary["scenario"], summary["connection"], velocity_commands(summary))
    lines = [
        f"scenario    {title}",
        f"robot       {summary['robot']} in MuJoCo, {summary['controller']}, control period {control:g} ms, physics "
        f"step {physics:g} ms",
    ]
    lines.append(f"state       {_state(summary)}")
    walk = summary.get("walk")
    if walk:
        sole = walk["sole"]
        lines.append(
            f"walk        COG height {walk['cog_height']:.3f} m, step width {walk['step_width']:.3f} m, sole "
            f"{sole['front'] + sole['back']:.3f} x {sole['inner'] + sole['outer']:.3f} m: {walk['source']}"
        )
    errors = summary["zmp_error"]
    pushes = summary["pushes"]
    lines += [
        f"outcome     {outcome}",
        f"walked      {summary['distance_walked']:.3f} m; {summary['missed_landings']} missed landing(s), "
        f"{summary['step_adjustments']} step adjustment(s), stance-foot slip at most "
        f"{summary['foot_slip_max'] * 1e3:.1f} mm",
        f"ZMP         measured, in single support, vs the plan: {_spread(errors['vs_plan'])}",
        f"            vs the multibody ZMP of the commanded motion: {_spread(errors['vs_commanded_motion'])}"
        + _left_out(errors["vs_commanded_motion"]),
    ]
    estimation = summary.get("estimation")
    if estimation and estimation["ticks"]:
        e = estimation
        lines.append(
            f"estimate    vs the truth: DCM {_mm(e['dcm_rms'])} RMS ({_mm(e['dcm_max'])} at most), COM "
            f"{_mm(e['com_relative_rms'])} RMS relative to the stance sole, the feet's contact states right at "
            f"{100.0 * e['contact_agreement']:.1f} % of the ticks, {e['landings_missed']} of {e['landings']} landings "
            "missed"
        )
    lines += sim_obstacle_lines(summary)
    if pushes:
        lines.append("pushes      " + ", ".join(f"{p['impulse_norm']:.1f} N s at {p['start']:.2f} s" for p in pushes))
    lines.append(
        f"speed       real-time factor {summary['real_time_factor']:.1f} "
        f"({summary['simulated_time']:.1f} s simulated in {summary['wall_time']:.1f} s)"
    )
    warnings = summary.get("mujoco_warnings") or []
    if warnings:
        lines.append(f"warnings    MuJoCo: {warnings[0]} ({len(warnings)} in all, listed in summary.json)")
    lines.append(f"outputs     {out}{os.sep}: {', '.join(summary['files'])} ({summary['rows']} rows)")
    return "\n".join(lines) + "\n"
