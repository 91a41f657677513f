"""Where a sweep keeps its results: an append-only journal while it runs, the tables when it stops.

``DIR/sweep_journal.jsonl`` gets one JSON line per finished result (a batch of pendulum-level cases, or one physics
case), flushed and synced to disk before the sweep goes on, so an interrupted sweep loses at most the cases that
were running. A line cut short by a crash is ignored when the journal is read again. Each line names its case by
:func:`rtgait.sweep.spec.case_id` and its kind (``"pendulum"`` or ``"physics"``); a sweep run again skips every case
whose result of that kind is there, so no case runs twice.

``DIR/results.csv`` and ``DIR/results.parquet`` are rewritten from the journal (each through a temporary name, so
never seen half written) whenever the sweep stops: at the end, after Ctrl-C, after an error. One row per case of
the sweep, in the order of its axes; the cases not done yet are left out.

A file that cannot be read or written (a full disk, a folder made read-only meanwhile) raises
:class:`~rtgait.outputs.OutputError` with one line naming the folder.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import math
import os
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

from rtgait.outputs import OutputError, write_atomic, write_text_atomic

JOURNAL = "sweep_journal.jsonl"
CSV_FILE = "results.csv"
PARQUET_FILE = "results.parquet"

PENDULUM_COLUMNS = (
    "zmp_margin_min", "zmp_margin_min_time", "zmp_outside", "zmp_deviation_max", "zmp_deviation_max_x",
    "zmp_deviation_max_y", "decision",
)  # fmt: skip
"""Pendulum-level results: signed ZMP margin (m), its time (s), whether the ZMP leaves the polygon, the largest
``|ZMP - reference|`` (m, the larger axis, then x and y) and, for auto, the connection each change took."""
TERRAIN_COLUMNS = ("cog_z_min", "cog_z_max", "zmp_error_max", "zmp_error_rms")
"""Pendulum-level results of a base with a ``[terrain]`` (after :data:`PENDULUM_COLUMNS`): the planned COG height's
lowest and highest value (m), and the largest and RMS error the vertical motion adds to the horizontal ZMP (m, the
full point-mass ZMP equation, as ``summary.json``'s ``terrain`` entry). Sweeps on the flat floor have no such
columns."""
PHYSICS_COLUMNS = ("physics", "fell", "tipped", "fall_time", "steps_completed", "steps_planned", "physics_error")
"""Physics results (``--physics``): ``physics`` is ``ok``, ``failed`` or ``skipped``; a fall's time (s); touch-downs
completed of those planned; why a case failed or was skipped."""


TEXT_COLUMNS = frozenset({"case", "connection", "decision", "physics", "physics_error"})
"""Columns read back as text whatever they look like (a case id such as ``3e14...`` is no number)."""


class ResultStore:
    """The journal of one sweep folder (module docstring)."""

    def __init__(self, folder: Path) -> None:
        self.folder = Path(folder)
        self.path = self.folder / JOURNAL
        self._done: dict[str, dict[str, dict[str, Any]]] = {}  # kind -> case id -> result
        self._stream: io.TextIOWrapper | None = None
        self.loaded = False  # until load() has read the journal: tables written before would hold nothing

    def load(self) -> None:
        """Read what earlier runs finished (a missing journal is an empty one)."""
        self._done = {"pendulum": {}, "physics": {}}
        with _file_errors(f"cannot read {self.path}"):
            self._load()
        self.loaded = True

    def _load(self) -> None:
        if not self.path.exists():
            return
        with open(self.path, encoding="utf-8", errors="replace") as stream:  # a damaged line is skipped below
            for line in stream:
                try:
                    record = json.loads(line)
                    kind, results = record["kind"], record["results"]
                except (ValueError, KeyError, TypeError):
                    continue  # a line cut short by a crash: its cases run again
                self._done.setdefault(kind, {}).update(results)

    def done(self, kind: str) -> dict[str, dict[str, Any]]:
        """Results of ``kind`` by case id."""
        return self._done.setdefault(kind, {})

    def append(self, kind: str, results: dict[str, dict[str, Any]]) -> None:
        """Record finished results (case id -> fields) durably before going on."""
        if not results:
            return
        line = json.dumps({"kind": kind, "results": results}, allow_nan=False, default=_json) + "\n"
        with _file_errors(self._cannot_write):
            if self._stream is None:
                self.folder.mkdir(parents=True, exist_ok=True)
                self._stream = open(self.path, "a", encoding="utf-8")  # noqa: SIM115  # kept open for the sweep
            self._stream.write(line)
            self._stream.flush()
            os.fsync(self._stream.fileno())
        self.done(kind).update(results)

    def close(self) -> None:
        stream, self._stream = self._stream, None
        if stream is not None:
            with _file_errors(self._cannot_write):
                stream.close()

    @property
    def _cannot_write(self) -> str:
        return f"cannot write outputs to {self.folder}"

    def write_tables(self, axes: Sequence[str], cases: Iterable[tuple[str, dict[str, Any]]], physics: bool) -> int:
        """Write ``results.csv`` and ``results.parquet`` for the ``(id, axis values)`` cases done; returns the rows."""
        pendulum, walked = self.done("pendulum"), self.done("physics")
        terrain = TERRAIN_COLUMNS if any(TERRAIN_COLUMNS[0] in result for result in pendulum.values()) else ()
        columns = ["case", *axes, *PENDULUM_COLUMNS, *terrain, *(PHYSICS_COLUMNS if physics else ())]
        rows = []
        for key, values in cases:
            if key not in pendulum or (physics and key not in walked):
                continue
            rows.append({"case": key, **values, **pendulum[key], **(walked[key] if physics else {})})
        text = io.StringIO()
        writer = csv.DictWriter(text, fieldnames=columns, extrasaction="ignore", lineterminator="\n")
        writer.writeheader()
        for row in rows:
            writer.writerow({k: _cell(row.get(k)) for k in columns})
        with _file_errors(self._cannot_write):
            write_text_atomic(self.folder / CSV_FILE, text.getvalue())
            _write_parquet(self.folder / PARQUET_FILE, columns, rows)
        return len(rows)


@contextlib.contextmanager
def _file_errors(what: str) -> Iterator[None]:
    """An ``OSError`` in the block as one :class:`~rtgait.outputs.OutputError` line: ``what: reason``."""
    try:
        yield
    except OSError as error:
        raise OutputError(f"{what}: {error.strerror or error}") from None


def read_results(folder: Path) -> list[dict[str, Any]]:
    """The rows of ``folder/results.csv``, numbers as floats, booleans as bools, empty cells as ``None``."""
    with open(Path(folder) / CSV_FILE, encoding="utf-8", newline="") as stream:
        return [{k: v if k in TEXT_COLUMNS else _parse(v) for k, v in row.items()} for row in csv.DictReader(stream)]


def _cell(value: Any) -> Any:
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)  # shortest exact form: the CSV holds the same numbers as the parquet file
    return value


def _parse(text: str) -> Any:
    if text == "":
        return None
    if text in ("True", "False"):
        return text == "True"
    try:
        return float(text)
    except ValueError:
        return text


def _json(value: Any) -> Any:
    """numpy scalars in the journal."""
    if hasattr(value, "item"):
        return value.item()
    raise TypeError(f"cannot store {type(value).__name__} in the journal")


def _write_parquet(path: Path, columns: Sequence[str], rows: list[dict[str, Any]]) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    data = {}
    for column in columns:
        values = [row.get(column) for row in rows]
        if all(v is None or isinstance(v, bool) for v in values):
            kind = pa.bool_()
        elif all(v is None or (isinstance(v, (int, float)) and not isinstance(v, bool)) for v in values):
            kind = pa.float64()
            values = [None if v is None or (isinstance(v, float) and math.isnan(v)) else float(v) for v in values]
        else:
            kind = pa.string()
            values = [None if v is None else str(v) for v in values]
        data[column] = pa.array(values, type=kind)
    table = pa.table(data)
    write_atomic(path, lambda temporary: pq.write_table(table, temporary))


__all__ = [
    "CSV_FILE", "JOURNAL", "PARQUET_FILE", "PENDULUM_COLUMNS", "PHYSICS_COLUMNS", "TERRAIN_COLUMNS", "ResultStore",
    "read_results",
]  # fmt: skip
