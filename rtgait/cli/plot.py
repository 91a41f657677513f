"""``rtgait plot DIR``: draw a finished run's figures again from its files, in any format.

A ``plan`` run is read from ``trajectory.csv`` and ``summary.json``, a ``simulate --model lipm`` run from ``sim.csv``
and ``summary.json`` (:mod:`rtgait.viz.run_data`), a ``simulate`` run in MuJoCo from ``sim.parquet`` (or, without it,
``sim.csv`` and ``summary.json``: :func:`rtgait.viz.sim_figure.read_zmp_sim_run`); the figures are the ones the run
wrote, drawn by the same code from the same numbers. Only figures are written (all or nothing, like a run's
outputs); ``summary.json`` is left as the run wrote it. A MuJoCo run's ``replay.html`` is not a figure and needs the
robot's meshes: it is not remade (``rtgait simulate --html`` writes it).
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from pathlib import Path
from typing import Any

from rtgait.cli.common import add_format_option, out_folder, require_extras
from rtgait.outputs import check_destination, staged_outputs
from rtgait.viz.figure_files import PENDULUM_FIGURE, figure_file, plan_figure_files
from rtgait.viz.run_data import read_plan_run
from rtgait.viz.run_files import RunFilesError, run_kind


def add_parser(commands: Any) -> None:
    plot = commands.add_parser(
        "plot",
        help="draw a finished run's figures again from its files (rtgait plan, rtgait simulate)",
        description="Read the files of a finished run in DIR (trajectory.csv and summary.json of rtgait plan, "
        "sim.csv and summary.json of rtgait simulate --model lipm, sim.parquet (or sim.csv and summary.json) of "
        "rtgait simulate in MuJoCo) and write its figures again, in the format asked for.",
    )
    plot.add_argument("folder", metavar="DIR", type=out_folder, help="the output folder of a finished run")
    add_format_option(plot)
    plot.add_argument("--out", metavar="OUT", type=out_folder, help="write the figures there (default: DIR)")
    plot.add_argument("--quiet", action="store_true", help="print nothing on success")


def run(args: argparse.Namespace) -> int:
    folder: Path = args.folder
    out: Path = args.out if args.out is not None else folder
    fmt: str = args.figure_format
    # Everything is read and checked before anything is drawn: a bad DIR is one line and exit 2 (RunFilesError is a
    # ValueError), and the output folder is not touched.
    try:
        kind = run_kind(folder)
    except OSError as error:  # a name the file system refuses, an unreadable folder
        raise RunFilesError(f"cannot read {folder}: {error.strerror or error}") from None
    require_extras(figures=True, html=False)
    if kind == "mujoco":
        from rtgait.viz.sim_figure import ZMP_SIM_FIGURE, read_zmp_sim_run

        simulation = read_zmp_sim_run(folder)
        names = [figure_file(ZMP_SIM_FIGURE, fmt)]
    elif kind == "plan":
        plan, info, summary = read_plan_run(folder)
        names = plan_figure_files(fmt)
        if any(name.startswith("multibody_zmp.") for name in summary.get("files", [])):
            # The multibody ZMP comes from the robot's whole-body motion, which the files do not hold.
            warnings.warn("multibody_zmp is not drawn again: the run's files do not hold the robot's multibody ZMP",
                          stacklevel=1)  # fmt: skip
    else:
        from rtgait.viz.pendulum import read_pendulum_run  # after require_extras: it needs matplotlib

        pendulum, _ = read_pendulum_run(folder)
        names = [figure_file(PENDULUM_FIGURE, fmt)]
    check_destination(out, names)
    with staged_outputs(out) as staging:
        if kind == "mujoco":
            from rtgait.viz.sim_figure import plot_zmp_sim

            plot_zmp_sim(simulation, staging.folder / names[0])
        elif kind == "plan":
            from rtgait.viz.figures import render_all

            render_all(plan, info, staging.folder, fmt)
        else:
            from rtgait.viz.pendulum import plot_pendulum

            plot_pendulum(pendulum, staging.folder / names[0])
        for name in names:
            staging.add(name)
    if not args.quiet:
        what = "MuJoCo simulation" if kind == "mujoco" else f"{kind} run"
        sys.stdout.write(f"figures     {out}{os.sep}: {', '.join(names)} (from the {what} in {folder})\n")
    return 0
