"""Reading back the files a finished run wrote (``trajectory.csv``, ``sim.csv``, ``summary.json``), and telling which
kind of run a folder holds; every refusal a one-line :class:`RunFilesError` naming the file (numpy and the core)."""

from __future__ import annotations

import json
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from rtgait.core.geometry.terrain import TerrainKind, terrain_from_fields

__all__ = ["RunFilesError", "read_floats", "read_summary", "read_table", "read_terrain", "require_keys", "run_kind"]

PLAN_CSV = "trajectory.csv"
SIM_CSV = "sim.csv"
SIM_PARQUET = "sim.parquet"
SUMMARY = "summary.json"
# Columns only the MuJoCo loop writes into its sim.csv (rtgait.io.sim_run.SIM_CSV_COLUMNS): a run that has them is a
# simulation of the robot, whose figure is not drawn here.
_MUJOCO_COLUMNS = ("base_qw", "left_contact")


class RunFilesError(ValueError):
    """A folder does not hold the files of a run the figures can be drawn from (one line, names the file)."""


def read_table(path: Path, required: Sequence[str]) -> dict[str, np.ndarray]:
    """The columns of a CSV file written by rtgait, as text arrays by name; refuses one missing ``required``."""
    try:
        with open(path, encoding="utf-8") as stream, warnings.catch_warnings():
            # An empty body is no warning here (its stream's repr would be the message): "no rows" is said below.
            warnings.simplefilter("ignore")
            header = stream.readline().strip().split(",")
            # ndmin=2: a run of a single tick is still a table of one row.
            table = np.loadtxt(stream, delimiter=",", dtype=str, ndmin=2)
    except OSError as error:
        raise RunFilesError(f"cannot read {path}: {error.strerror or error}") from None
    except UnicodeDecodeError:
        raise RunFilesError(f"cannot read {path}: not a text file") from None
    except ValueError as error:  # numpy's "the number of columns changed from 27 to 22 at row 132; use `usecols`..."
        detail = str(error).split(";")[0]
        raise RunFilesError(f"cannot read {path}: it is cut short or damaged ({detail})") from None
    if table.shape[0] < 1:  # first: a header cut short also lacks columns, but "cut short" is the news
        raise RunFilesError(f"{path} has no rows: it is cut short or damaged")
    missing = [name for name in required if name not in header]
    if missing:
        raise RunFilesError(f"{path} has no column {missing[0]}: not a file rtgait wrote for this kind of run")
    if table.shape[1] != len(header):
        raise RunFilesError(f"{path} has rows that do not match its header: it is cut short or damaged")
    return {name: table[:, index] for index, name in enumerate(header)}


def read_floats(columns: dict[str, np.ndarray], names: Sequence[str], path: Path) -> np.ndarray:
    """The columns ``names`` of a :func:`read_table` as one float array ``(k, len(names))``."""
    try:
        return np.column_stack([columns[name].astype(float) for name in names])
    except ValueError as error:
        raise RunFilesError(f"{path}: a value of {', '.join(names)} is not a number ({error})") from None


def read_summary(folder: Path) -> dict[str, Any]:
    """The ``summary.json`` of the run in ``folder``."""
    path = Path(folder) / SUMMARY
    try:
        summary = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise RunFilesError(f"{path} is missing: {folder} does not hold a finished rtgait run") from None
    except (OSError, UnicodeDecodeError, ValueError) as error:
        raise RunFilesError(f"cannot read {path}: {error}") from None
    if not isinstance(summary, dict):
        raise RunFilesError(f"{path} is not a run's summary (not a JSON object)")
    return summary


def require_keys(summary: dict[str, Any], keys: Sequence[str], folder: Path, kind: str) -> None:
    """Refuse a summary without one of ``keys``: not the summary of ``kind`` run, or one older than the figures."""
    missing = [key for key in keys if key not in summary]
    if missing:
        raise RunFilesError(
            f"{Path(folder) / SUMMARY} has no {missing[0]!r}: not the summary of {kind} run, or one written by an "
            "older rtgait (run it again)"
        )


def read_terrain(fields: Any) -> TerrainKind | None:
    """The terrain of a run's ``terrain`` entry (summary or log metadata: :func:`~rtgait.core.geometry.terrain.
    terrain_fields`), ``None`` without one (the flat floor)."""
    if fields is None:
        return None
    try:
        return terrain_from_fields(fields)
    except (ValueError, AttributeError) as error:
        raise RunFilesError(f"the run's terrain entry is not a terrain: {error}") from None


def _csv_header(path: Path) -> list[str]:
    try:
        with open(path, encoding="utf-8") as stream:
            return stream.readline().strip().split(",")
    except (OSError, UnicodeDecodeError) as error:
        raise RunFilesError(f"cannot read {path}: {error}") from None


def run_kind(folder: Path) -> str:
    """``"plan"``, ``"lipm"`` or ``"mujoco"``: the kind of finished run in ``folder``, told by its summary and its
    files (``sim.parquet`` or the robot's columns of ``sim.csv`` for a MuJoCo simulation).

    Raises:
        RunFilesError: not a folder, or no run in it.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise RunFilesError(f"{folder} is not a folder" if folder.exists() else f"{folder} does not exist")
    summary = read_summary(folder)
    sim = folder / SIM_CSV
    if summary.get("model") == "lipm":
        return "lipm"
    if (
        (folder / SIM_PARQUET).is_file()
        or summary.get("model") == "mujoco"
        or "walk_start" in summary
        or (sim.is_file() and set(_MUJOCO_COLUMNS) <= set(_csv_header(sim)))
    ):
        return "mujoco"
    if (folder / PLAN_CSV).is_file() or "zmp_margin_min" in summary:
        return "plan"
    raise RunFilesError(f"{folder} holds no trajectory.csv (rtgait plan) or sim.csv (rtgait simulate)")
