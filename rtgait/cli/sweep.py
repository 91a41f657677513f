"""``rtgait sweep SPEC --out DIR [--physics [--robot R] [--controller C] [--state S]]
[--workers N | --scheduler ADDRESS]``.

Runs every case of the sweep file ``SPEC`` (:mod:`rtgait.sweep.spec`, ``docs/sweeps.md``): at the pendulum level in
this process, batched (:mod:`rtgait.sweep.pendulum`); with ``--physics`` also in MuJoCo, in worker processes
(``--workers N``, default one per core) or on a Dask cluster (``--scheduler ADDRESS``, or ``local`` for a
``LocalCluster``). Writes ``DIR/results.csv``, ``DIR/results.parquet``, ``DIR/sweep.json`` and the map
``DIR/map.png`` / ``map.pdf`` (:mod:`rtgait.sweep.maps`). A sweep run again into the same ``DIR`` continues where it
stopped (:mod:`rtgait.sweep.store`).

Bad input (the file, an option, more cases than the limits, an unreachable scheduler) raises ``ValueError`` with one
line before anything is written; a missing package raises ``RunError`` (exit 1); Ctrl-C writes the tables of the
cases finished and is raised again.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from rtgait.cli.common import RunError
from rtgait.core.planner.levels import CONTROLLER_LEVELS
from rtgait.estimation.estimator import DEFAULT_STATE, STATE_SOURCES
from rtgait.outputs import OutputError, check_destination, create_folder, write_text_atomic
from rtgait.sweep.spec import MAX_PHYSICS_CASES, SweepError, SweepSpec, case_id, load_spec
from rtgait.sweep.store import CSV_FILE, JOURNAL, PARQUET_FILE, ResultStore

DEFAULT_TIMEOUT = 900.0
"""Seconds one physics case may take before it is killed."""
SWEEP_FILE = "sweep.json"
MAP_FILES = ("map.png", "map.pdf")
PREVIEW_SKIPPED = "the preview baseline is evaluated at the pendulum level only"


def add_parser(subparsers: Any) -> None:
    """Add the ``sweep`` subcommand to an ``argparse`` subparsers object."""
    sweep = subparsers.add_parser(
        "sweep",
        help="run a sweep over scenario variants: ZMP margins per case, optionally walked in physics; the map",
        description="Run every case of a sweep file (a base scenario and axes: change.length, change.width, "
        "change.step, walk.step_length, timing.double_support, timing.single_support, connection) at the pendulum "
        "level, batched, and with --physics also in MuJoCo, in parallel. Writes results.csv, results.parquet, "
        "sweep.json and map.png/map.pdf into DIR; run again, it continues where it stopped. See docs/sweeps.md.",
    )
    sweep.add_argument("spec", metavar="SPEC", help="the sweep file (.toml)")
    sweep.add_argument("--out", metavar="DIR", type=_folder, help="output folder (default: out/<SPEC's name>)")
    sweep.add_argument("--physics", action="store_true", help="also walk every case in MuJoCo")
    sweep.add_argument("--robot", metavar="NAME_OR_FILE", help="robot for --physics (default talos)")
    sweep.add_argument("--controller", metavar="C", choices=CONTROLLER_LEVELS, help="controller level for --physics")
    sweep.add_argument(
        "--state", choices=STATE_SOURCES, help="what the controller acts on in --physics: estimated (default), the "
        "state estimated from the simulated sensors; truth, the simulator's own",
    )  # fmt: skip
    sweep.add_argument("--workers", metavar="N", type=int, help="physics cases at a time (default: one per core)")
    sweep.add_argument("--scheduler", metavar="ADDRESS", help="run physics cases on this Dask scheduler ('local': a "
                       "LocalCluster of --workers processes)")  # fmt: skip
    sweep.add_argument(
        "--timeout",
        metavar="S",
        type=float,
        default=DEFAULT_TIMEOUT,
        help=f"seconds a physics case may take before it is killed (default {DEFAULT_TIMEOUT:g})",
    )
    sweep.add_argument("--no-figures", action="store_true", help="skip map.png and map.pdf")
    sweep.add_argument("--quiet", action="store_true", help="print nothing on success")


def _folder(text: str) -> Path:
    if not text:
        raise argparse.ArgumentTypeError("must name a folder, got an empty string")
    return Path(text)


def run(args: argparse.Namespace) -> int:
    """Run the sweep ``args`` describe (:func:`add_parser`); returns the exit code (0)."""
    spec = load_spec(args.spec)
    out: Path = args.out if args.out is not None else Path("out") / Path(args.spec).stem
    _check_options(args, spec)
    figures = not args.no_figures
    _require(args, figures)
    check_destination(out, [CSV_FILE, PARQUET_FILE, JOURNAL, SWEEP_FILE, *(MAP_FILES if figures else ())])
    executor = _executor(args) if args.physics else None  # an unreachable scheduler is refused before writing
    began = time.perf_counter()
    cases = [(case_id(spec.fingerprint(), values), values) for values in spec.cases()]
    store = ResultStore(out)
    try:
        create_folder(out)  # every check has passed: from here on the sweep writes
        with _writing(out):
            store.load()
            write_text_atomic(out / SWEEP_FILE, json.dumps(_description(spec, args), indent=2) + "\n")
        _pendulum_stage(spec, cases, store, args.quiet)
        if executor is not None:
            _physics_stage(spec, cases, store, executor, args)
    finally:
        try:
            rows = store.write_tables(spec.axis_names, cases, args.physics) if store.loaded else 0
        finally:  # the journal and the executor (a Dask cluster's processes) are closed whatever happened
            store.close()
            if executor is not None:
                executor.close()
    maps: list[str] = []
    if figures:
        from rtgait.sweep.maps import write_map

        with _writing(out):
            maps = [path.name for path in write_map(out)]  # none when the axes make no map (docs/sweeps.md)
    if not args.quiet:
        sys.stdout.write(_report(spec, store, cases, out, rows, time.perf_counter() - began, args.physics, maps))
    return 0


@contextlib.contextmanager
def _writing(out: Path) -> Iterator[None]:
    """An ``OSError`` while the sweep writes into ``out`` as one :class:`OutputError` line."""
    try:
        yield
    except OSError as error:
        raise OutputError(f"cannot write outputs to {out}: {error.strerror or error}") from None


def _check_options(args: argparse.Namespace, spec: SweepSpec) -> None:
    if not args.physics:
        for option in ("robot", "controller", "state", "workers", "scheduler"):
            if getattr(args, option) is not None:
                raise SweepError(f"--{option} is for the physics cases: add --physics")
    if args.workers is not None and args.workers < 1:
        raise SweepError(f"--workers must be at least 1, got {args.workers}")
    if not (math.isfinite(args.timeout) and args.timeout > 0.0):
        raise SweepError(f"--timeout must be a number of seconds > 0, got {args.timeout}")
    if args.physics and spec.n_cases > MAX_PHYSICS_CASES:
        raise SweepError(
            f"the sweep has {spec.n_cases} cases, more than the {MAX_PHYSICS_CASES} one sweep may walk in physics"
        )


def _require(args: argparse.Namespace, figures: bool) -> None:
    needs = [("pyarrow", "results.parquet needs pyarrow: pip install pyarrow")]
    if figures:
        needs.append(("matplotlib", "the map needs matplotlib: pip install 'rtgait[viz]', or pass --no-figures"))
    if args.physics:
        needs += [("mujoco", "--physics needs MuJoCo and Pinocchio: pip install 'rtgait[robot,sim]'"),
                  ("pinocchio", "--physics needs MuJoCo and Pinocchio: pip install 'rtgait[robot,sim]'")]  # fmt: skip
    if args.scheduler is not None:
        needs.append(("distributed", "--scheduler needs dask.distributed: pip install 'dask[distributed]'"))
    import importlib.util

    for module, message in needs:
        if importlib.util.find_spec(module) is None:
            raise RunError(message)


def _executor(args: argparse.Namespace):
    from rtgait.sweep.executors import DaskExecutor, LocalExecutor

    if args.scheduler is None:
        return _Closing(LocalExecutor(args.workers))
    try:
        return DaskExecutor(args.scheduler, args.workers, quiet=args.quiet)
    except RuntimeError as error:
        raise RunError(str(error)) from None


class _Closing:
    """A local executor with the ``close`` the Dask one has."""

    def __init__(self, executor) -> None:
        self.executor = executor

    def run(self, *a, **k) -> None:
        self.executor.run(*a, **k)

    def close(self) -> None:
        pass


def _bar(total: int, label: str, quiet: bool):
    try:
        from tqdm import tqdm
    except ImportError:  # pragma: no cover - tqdm comes with the sweep's dependencies
        return None
    # disable=None: no bar where stderr is not a terminal; the rate is in cases per second, with the time left.
    return tqdm(total=total, desc=label, unit=" case", file=sys.stderr, disable=True if quiet else None,
                dynamic_ncols=True, leave=False)  # fmt: skip


def _pendulum_stage(spec: SweepSpec, cases, store: ResultStore, quiet: bool) -> None:
    from rtgait.sweep.pendulum import evaluate_cases

    todo = [(key, values) for key, values in cases if key not in store.done("pendulum")]
    bar = _bar(len(todo), "pendulum", quiet) if todo else None

    def done(results: dict[str, dict[str, Any]]) -> None:
        store.append("pendulum", results)
        if bar is not None:
            bar.update(len(results))

    try:
        evaluate_cases(spec, todo, done)
    finally:
        if bar is not None:
            bar.close()


def _physics_stage(spec: SweepSpec, cases, store: ResultStore, executor, args: argparse.Namespace) -> None:
    walked = store.done("physics")
    todo = [(key, values) for key, values in cases if key not in walked]
    skipped = {key: {"physics": "skipped", "physics_error": PREVIEW_SKIPPED} for key, values in todo
               if values.get("connection") == "preview"}  # fmt: skip
    store.append("physics", skipped)
    robot = args.robot or "talos"
    jobs = [{"id": key, "document": spec.base_document, "values": values, "robot": robot,
             "controller": args.controller, "state": args.state} for key, values in todo
            if key not in skipped]  # fmt: skip
    if not jobs:
        return
    bar = _bar(len(jobs), "physics", args.quiet)

    def done(key: str, fields: dict[str, Any]) -> None:
        store.append("physics", {key: fields})
        if bar is not None:
            bar.update(1)

    try:
        executor.run(jobs, args.timeout, done)
    finally:
        if bar is not None:
            bar.close()


def _description(spec: SweepSpec, args: argparse.Namespace) -> dict[str, Any]:
    """What the map needs besides the rows: the base scenario's numbers and the axes."""
    base = spec.base
    return {
        "spec": str(args.spec),
        "base": base.name,
        "base_fingerprint": spec.fingerprint(),
        "step_length": base.step_length,
        "change_length": base.changes[0].length if base.changes else None,
        "change_step": base.changes[0].step if base.changes else None,
        "connection": base.connection,
        "single_support": base.timing.single_support,
        "double_support": base.timing.double_support,
        "dt": base.dt,
        "axes": {name: list(values) for name, values in spec.axes},
        "cases": spec.n_cases,
        "physics": bool(args.physics),
        "robot": (args.robot or "talos") if args.physics else None,
        "controller": args.controller,
        "state": (args.state or DEFAULT_STATE) if args.physics else None,
    }


def _report(spec, store, cases, out: Path, rows: int, wall: float, physics: bool, maps: list[str]) -> str:
    pendulum = store.done("pendulum")
    by_method: dict[str, list[bool]] = {}
    for key, values in cases:
        if key in pendulum:
            method = values.get("connection", spec.base.connection)
            by_method.setdefault(method, []).append(not pendulum[key]["zmp_outside"])
    lines = [f"sweep       {spec.base.name}: {spec.n_cases} cases over {', '.join(spec.axis_names)} ({wall:.1f} s)"]
    for method, inside in by_method.items():
        lines.append(f"inside      {method}: {sum(inside)} of {len(inside)} cases keep the ZMP inside")
    if physics:
        walked = store.done("physics").values()
        fell = sum(1 for r in walked if r.get("fell"))
        failed = sum(1 for r in walked if r.get("physics") == "failed")
        lines.append(f"physics     {len(walked)} cases: {fell} fell, {failed} failed to run")
    files = [CSV_FILE, PARQUET_FILE, SWEEP_FILE, *maps]
    lines.append(f"outputs     {out}{os.sep}: {', '.join(files)} ({rows} rows)")
    return "\n".join(lines) + "\n"


__all__ = ["add_parser", "run"]
