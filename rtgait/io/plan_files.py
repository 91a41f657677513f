"""Plain-file outputs of a rollout: the per-tick trajectory as CSV and the whole set of a plan's outputs (its
summary from :mod:`rtgait.io.plan_summary`, the figures, the replay); the lines the command line prints from a summary
are made by :mod:`rtgait.io.plan_report`.

Kept apart from the command-line tool so that scripts driving the planner can write the same files. Every file
is written through a temporary name (:func:`rtgait.outputs.write_atomic`), so none is ever seen half written.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rtgait.core.analysis.rollout import Rollout
from rtgait.core.planner.online import SAMPLE_FIELDS
from rtgait.io.obstacle_outputs import obstacle_summary
from rtgait.io.plan_summary import summarize
from rtgait.io.summary_json import summary_text
from rtgait.outputs import Staging, staged_outputs, write_atomic
from rtgait.scenario.scenario import Scenario
from rtgait.viz.figure_files import OBSTACLE_FIGURE, figure_file, plan_figure_files

if TYPE_CHECKING:  # the robot layer is optional (the [robot] extra)
    from rtgait.core.obstacle.walk import ObstacleRun
    from rtgait.robot.pipeline import RobotRun

__all__ = [
    "CSV_COLUMNS",
    "CSV_HEAD_COLUMNS",
    "plan_files",
    "write_joints_csv",
    "write_plan_outputs",
    "write_trajectory_csv",
]

CSV_HEAD_COLUMNS = (
    "t", "cog_x", "cog_y", "cog_z", "cog_vx", "cog_vy", "cog_ax", "cog_ay", "zmp_x", "zmp_y",
    "lfoot_x", "lfoot_y", "lfoot_z", "lfoot_yaw", "rfoot_x", "rfoot_y", "rfoot_z", "rfoot_yaw", "support",
)  # fmt: skip
"""The first columns of ``trajectory.csv``, a stable interface for downstream tools (SI units, yaw in rad)."""

CSV_EXTRA_COLUMNS = ("zmp_ref_x", "zmp_ref_y", "zmp_margin", "phase", "cog_vz", "cog_az", "dcm_x", "dcm_y")
"""Columns after :data:`CSV_HEAD_COLUMNS`: reference ZMP (m), signed ZMP margin (m, > 0 inside), phase
index, the vertical COG velocity and acceleration (zero for the constant-height model), and the divergent
component of motion (capture point) ``xi = c + c'/w`` (m)."""

CSV_COLUMNS = CSV_HEAD_COLUMNS + CSV_EXTRA_COLUMNS

# 10 significant digits: sub-micrometre for positions within 100 m, exact for the tick times of usual periods.
_FLOAT_FORMAT = "%.10g"


def write_joints_csv(header: tuple[str, ...], rows: np.ndarray, path: Path) -> int:
    """Write a joint table (``t``, ``base_x`` .. ``base_qw``, one column per joint) to ``path``; returns the rows."""

    def write(temporary: Path) -> None:
        with open(temporary, "w", encoding="utf-8", newline="") as stream:
            stream.write(",".join(header) + "\n")
            np.savetxt(stream, rows, fmt=_FLOAT_FORMAT, delimiter=",")

    write_atomic(path, write)
    return len(rows)


def write_trajectory_csv(rollout: Rollout, path: Path) -> int:
    """Write one row per control tick to ``path`` with the header :data:`CSV_COLUMNS`; returns the row count."""
    numeric: dict[str, np.ndarray] = {"t": rollout.times, "zmp_margin": rollout.margin}
    for name in SAMPLE_FIELDS:
        numeric[name] = rollout.column(name)
    columns: list[np.ndarray] = []
    for name in CSV_COLUMNS:
        if name == "support":
            columns.append(rollout.support.astype(str))
        elif name == "phase":
            columns.append(rollout.phase.astype(int).astype(str))
        else:
            # Vectorised formatting: a Python-level loop over every value would dominate long runs.
            columns.append(np.char.mod(_FLOAT_FORMAT, numeric[name]))
    table = np.stack(columns, axis=1)

    def write(temporary: Path) -> None:
        with open(temporary, "w", encoding="utf-8", newline="") as stream:
            stream.write(",".join(CSV_COLUMNS) + "\n")
            stream.writelines(",".join(row) + "\n" for row in table.tolist())

    write_atomic(path, write)
    return len(table)


# ----- the whole set of a plan's outputs ------------------------------------------------------------------------


def plan_files(figures: bool, robot: bool, html: bool, fmt: str = "png", obstacles: bool = False) -> list[str]:
    """The files :func:`write_plan_outputs` writes with these options (figures in the format ``fmt``: png, pdf or
    svg; ``obstacles``: the scenario has some, and its figure like the paper's Fig. 1 is added), in the order the
    summary lists them."""
    names = ["trajectory.csv", "summary.json"] + (["joints.csv"] if robot else [])
    if figures:
        names += [*plan_figure_files(fmt), *([figure_file("multibody_zmp", fmt)] if robot else [])]
        names += [figure_file(OBSTACLE_FIGURE, fmt)] if obstacles else []
    return names + (["replay.html"] if robot and html else [])


def write_plan_outputs(
    result: Rollout,
    scenario: Scenario,
    out: Path,
    *,
    figures: bool = True,
    robot_run: RobotRun | None = None,
    html: bool = False,
    fmt: str = "png",
    background: str = "sky",
    obstacle_runs: list[ObstacleRun] | None = None,
) -> dict[str, Any]:
    """Write what ``rtgait plan`` writes into the folder ``out``, replacing the previous outputs of the same names
    together or not at all (:func:`rtgait.outputs.staged_outputs`); returns the summary.

    Args:
        result: the rollout.
        scenario: the scenario rolled out (as the robot walks it, with a robot).
        out: the output folder, created if missing.
        figures: the four figures and, with a robot, the multibody ZMP figure (needs matplotlib).
        robot_run: the walk on a robot: adds ``joints.csv`` and the robot's numbers to the summary.
        html: with a robot, also the 3D replay ``replay.html`` (needs meshcat).
        fmt: the figures' file format, ``"png"``, ``"pdf"`` or ``"svg"``.
        background: the replay's background, ``"sky"`` or ``"white"``.
        obstacle_runs: with obstacles, the walk under each connection mode (:func:`rtgait.io.obstacle_outputs
            .obstacle_runs`): adds ``obstacle_walks`` to the summary and, with figures, the obstacle figure.

    Raises:
        rtgait.outputs.OutputError: the outputs could not be written; ``out`` is unchanged.
    """
    with staged_outputs(out) as staging:
        rows = write_trajectory_csv(result, staging.add("trajectory.csv"))
        summary_path = staging.add("summary.json")
        summary = summarize(result, scenario)
        if robot_run is not None:
            write_joints_csv(*robot_run.motion.table(), staging.add("joints.csv"))
            summary.update(robot_run.summary())
        if obstacle_runs:
            summary["obstacle_walks"] = obstacle_summary(obstacle_runs)
        if figures:
            _write_figures(result, scenario, robot_run, staging, fmt)
            if obstacle_runs:
                from rtgait.viz.obstacle_figure import plot_obstacle_walks

                path = staging.add(figure_file(OBSTACLE_FIGURE, fmt))
                plot_obstacle_walks(obstacle_runs, scenario.sole, scenario.name, path)
        if html and robot_run is not None:
            _write_replay(result, scenario, robot_run, staging.add("replay.html"), background)
        summary["rows"] = rows
        summary["files"] = list(staging.files)
        summary_path.write_text(summary_text(summary), encoding="utf-8")
    return summary


def _write_figures(result: Rollout, scenario: Scenario, robot_run: RobotRun | None, staging: Staging, fmt: str) -> None:
    from rtgait.viz.figures import FigureInfo, render_all
    from rtgait.viz.multibody_figure import plot_multibody_zmp

    info = FigureInfo(
        title=f"{scenario.name} ({scenario.connection})",
        sole=scenario.sole,
        nominal_footprints=scenario.nominal_footprints(),
        terrain=None if scenario.terrain is None else scenario.terrain.terrain,
    )
    for path in render_all(result, info, staging.folder, fmt):
        staging.add(path.name)
    if robot_run is not None:
        before = robot_run.uncompensated[1] if robot_run.uncompensated else robot_run.check
        after = robot_run.check if robot_run.uncompensated else None
        plot_multibody_zmp(
            result, info, staging.add(figure_file("multibody_zmp", fmt)), before.zmp,
            None if after is None else after.zmp, robot=robot_run.robot.name,
        )  # fmt: skip


def _write_replay(
    result: Rollout, scenario: Scenario, robot_run: RobotRun, path: Path, background: str = "sky"
) -> None:
    from rtgait.robot.pipeline import visual_model
    from rtgait.viz.replay import write_replay_html

    robot = robot_run.robot
    motion = robot_run.motion
    write_replay_html(
        path,
        robot.full_model,
        visual_model(robot),
        motion.times,
        motion.q_full,
        footprints=result.footprints,
        sole=scenario.sole,
        cog=robot_run.check.cog,
        zmp=np.column_stack([result.column("zmp_x"), result.column("zmp_y")]),
        title=f"rtgait: {scenario.name} on {robot.name}",
        background=background,
        terrain=None if scenario.terrain is None else scenario.terrain.terrain,
        obstacles=scenario.obstacles,
    )
