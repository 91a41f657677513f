"""The command line's rough edges: staging folders left by killed runs, file-system errors while writing, late
velocity commands, damaged run files, footstep plans as sweep bases and without ``[walk]``, the order of play's
checks, Dask's log lines under ``--quiet``."""

from __future__ import annotations

import errno
import os
import signal
import subprocess
import sys
import uuid
from pathlib import Path

import pytest
from scenario_files import header_text

from rtgait.cli import plan as plan_command
from rtgait.cli import simulate_options
from rtgait.cli.main import main
from rtgait.core.analysis.rollout import rollout
from rtgait.core.planner.online import OnlinePlanner
from rtgait.io.plan_summary import summarize
from rtgait.outputs import staging_folders
from rtgait.scenario.loading import load_scenario
from rtgait.scenario.scenario import DEFAULT_STEP_HEIGHT, DEFAULT_STEP_WIDTH, ScenarioError
from rtgait.sweep import store as sweep_store
from rtgait.sweep.spec import case_scenario, load_spec, scenario_from_document
from rtgait.sweep.store import read_results

ROOT = Path(__file__).resolve().parents[1]
LONG = "a" * 300
"""A file name longer than a file system allows (255 bytes on Linux)."""


def one_error_line(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err
    assert err.startswith("rtgait: error: ") and len(err.splitlines()) == 1, err
    return err.strip()


def python(code: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=cwd, timeout=60)


# ----- 1. staging folders of runs killed outright ----------------------------------------------------------------


def dead_pid(tmp_path: Path) -> int:
    """The id of a process that has ended (and been reaped)."""
    pid = int(python("import os; print(os.getpid())", tmp_path).stdout)
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return pid
    pytest.skip("the id of the finished process was reused at once")


def staging(folder: Path, pid: int, host: str | None = None, prefix: str = "") -> Path:
    """A staging folder as a run of process ``pid`` names it (rtgait.outputs), with a half-written file in it."""
    name = f".{prefix}rtgait-staging.{host or staging_folders.host()}.{pid}.{uuid.uuid4().hex[:8]}.tmp"
    path = folder / name
    path.mkdir(parents=True)
    (path / "trajectory.csv").write_text("half", encoding="utf-8")
    return path


def test_only_the_staging_folders_of_dead_runs_on_this_host_are_removed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    fcntl = pytest.importorskip("fcntl")  # POSIX
    out = tmp_path / "o"
    dead = dead_pid(tmp_path)
    alive = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        stale = staging(out, dead)
        stale_beside = staging(tmp_path, dead, prefix="o.")  # a run that was creating `o` itself
        kept = {
            "this process": staging(out, os.getpid()),
            "another live process": staging(out, alive.pid),
            "another host": staging(out, dead, host="elsewhere"),
            "another output folder": staging(tmp_path, dead, prefix="o2."),
        }
        locked = staging(out, dead)  # its owner lives in another process namespace: it holds the lock
        kept["a locked folder"] = locked
        descriptor = os.open(locked, os.O_RDONLY)
        fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
        with_previous = staging(out, dead)  # killed while the files moved: the previous outputs are in it
        (with_previous / ".previous").mkdir()
        (with_previous / ".previous" / "summary.json").write_text("{}", encoding="utf-8")
        kept["previous outputs"] = with_previous
        try:
            assert main(["plan", "fig6", "--out", str(out), "--no-figures", "--quiet"]) == 0
        finally:
            os.close(descriptor)
    finally:
        alive.kill()
        alive.wait()
    assert not stale.exists() and not stale_beside.exists()
    assert [why for why, path in kept.items() if not path.is_dir()] == []
    err = capsys.readouterr().err
    assert err.startswith("rtgait: warning: ") and len(err.splitlines()) == 1 and str(with_previous) in err, err
    assert (out / "trajectory.csv").read_text(encoding="utf-8").startswith("t,")


@pytest.mark.parametrize("exists", [True, False], ids=["into an existing folder", "creating the folder"])
def test_a_run_killed_while_writing_leaves_a_folder_the_next_run_removes(exists: bool, tmp_path: Path) -> None:
    out = tmp_path / "o"
    if exists:
        out.mkdir()
    killed = python(
        "import os, signal\nfrom pathlib import Path\nfrom rtgait.outputs import staged_outputs\n"
        f"with staged_outputs(Path({str(out)!r})) as staging:\n"
        "    staging.add('trajectory.csv').write_text('half')\n"
        "    os.kill(os.getpid(), signal.SIGKILL)\n",
        tmp_path,
    )
    assert killed.returncode == -signal.SIGKILL
    left = [p.name for p in [*tmp_path.rglob(".*")] if "rtgait-staging" in p.name]
    assert len(left) == 1, left
    assert main(["plan", "fig6", "--out", str(out), "--no-figures", "--quiet"]) == 0
    assert [p.name for p in tmp_path.rglob(".*")] == []
    assert sorted(p.name for p in out.iterdir()) == ["summary.json", "trajectory.csv"]


# ----- 2. file-system errors while writing are one line ----------------------------------------------------------

NESTED = [
    ["plan", "fig6", "--no-figures"],
    ["simulate", "fig6", "--model", "lipm", "--no-figures"],
    ["plot", "RUN"],
    ["sweep", "SWEEP", "--no-figures"],
]


@pytest.mark.parametrize("command", NESTED, ids=[c[0] for c in NESTED])
def test_an_output_path_too_long_deep_inside_is_one_line(
    command: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run = tmp_path / "run"
    assert main(["plan", "fig6", "--out", str(run), "--no-figures", "--quiet"]) == 0
    (tmp_path / "s.toml").write_text('base = "fig6"\n[axes]\n"timing.double_support" = [0.2]\n', encoding="utf-8")
    command = [str(run) if c == "RUN" else str(tmp_path / "s.toml") if c == "SWEEP" else c for c in command]
    out = tmp_path / "x" / LONG / "y"
    assert main([*command, "--out", str(out), "--quiet"]) == 1
    assert one_error_line(capsys).endswith("File name too long")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run", "s.toml"]


def test_names_near_the_file_systems_limit_are_written(tmp_path: Path) -> None:
    # The staging folder beside a new output folder and a file's temporary name are longer than the name itself.
    out, export = tmp_path / ("o" * 250), tmp_path / ("f" * 245 + ".toml")
    assert main(["plan", "fig6", "--out", str(out), "--no-figures", "--quiet", "--export-footsteps", str(export)]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([out.name, export.name])


def test_an_export_file_name_too_long_is_refused_before_the_run(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(plan_command, "rollout", lambda *a, **k: pytest.fail("the rollout started"))
    args = ["plan", "fig6", "--out", str(tmp_path / "o"), "--export-footsteps", str(tmp_path / f"{LONG}.toml")]
    assert main(args) == 1
    assert one_error_line(capsys).endswith("File name too long")
    assert list(tmp_path.iterdir()) == []


def test_a_full_disk_while_the_footsteps_are_exported_is_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def full(path: Path, text: str) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(plan_command, "write_text_atomic", full)
    export = tmp_path / "f.toml"
    args = ["plan", "fig6", "--out", str(tmp_path / "o"), "--no-figures", "--export-footsteps", str(export)]
    assert main([*args, "--quiet"]) == 1
    assert (
        one_error_line(capsys) == f"rtgait: error: --export-footsteps: cannot write {export}: No space left on device"
    )


@pytest.mark.parametrize(
    ("module", "name", "error"),
    [
        (sweep_store, "write_text_atomic", OSError(errno.EACCES, "Permission denied")),  # results.csv
        (sweep_store.os, "fsync", OSError(errno.ENOSPC, "No space left on device")),  # the journal
    ],
    ids=["tables", "journal"],
)
def test_a_sweep_that_cannot_write_says_so_in_one_line(
    module: object,
    name: str,
    error: OSError,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    def fail(*args: object) -> None:
        raise error

    monkeypatch.setattr(module, name, fail)
    (tmp_path / "s.toml").write_text('base = "fig6"\n[axes]\n"timing.double_support" = [0.2]\n', encoding="utf-8")
    out = tmp_path / "o"
    assert main(["sweep", str(tmp_path / "s.toml"), "--out", str(out), "--no-figures", "--quiet"]) == 1
    assert one_error_line(capsys) == f"rtgait: error: cannot write outputs to {out}: {error.strerror}"


def test_any_other_os_error_is_one_line_naming_the_file(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from rtgait.cli import main as cli

    def command(args: object) -> int:
        raise PermissionError(errno.EACCES, "Permission denied", "/results/run/sim.csv")

    monkeypatch.setitem(cli._COMMANDS, "scenarios", command)
    assert main(["scenarios"]) == 1
    assert one_error_line(capsys) == "rtgait: error: /results/run/sim.csv: Permission denied"


def test_a_play_output_name_too_long_is_refused_before_anything_loads(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["play", "--summary", str(tmp_path / f"{LONG}.json")]) == 1
    assert one_error_line(capsys).endswith("File name too long")


def test_plot_of_a_folder_whose_name_is_too_long_is_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["plot", LONG]) == 2
    assert one_error_line(capsys).endswith("File name too long")


# ----- 3. a velocity command after the walk's last step ----------------------------------------------------------


def walked_footprints(name: str, command_at: float | None) -> list[tuple[float, float, float]]:
    """The footprints of ``name`` walked by command at 0.1 m/s with, at ``command_at`` (s), 0.25 m/s, through the
    MuJoCo loop's own scheduling of commands (rtgait.sim.loop_inputs) at 1 kHz, the planner alone."""
    pytest.importorskip("mujoco")
    from rtgait.sim.loop_inputs import WalkInputs
    from rtgait.sim.loop_options import LoopOptions

    scenario = load_scenario(name)
    planner = OnlinePlanner(scenario.planner_config(), None)
    planner.set_velocity(0.1, 0.0, 0.0)
    planner.start(0.0)
    changes = () if command_at is None else ((command_at, 0.25, 0.0, 0.0),)
    inputs = WalkInputs(planner, LoopOptions(velocity_changes=changes), scenario.steps)
    inputs.start()
    for k in range(round((scenario.duration + 1.0) / 0.001)):
        inputs.update(k * 0.001, None)  # type: ignore[arg-type]  # the hook that reads MuJoCo's data is not set
        planner.sample(k * 0.001)
    return [(f.x, f.y, f.yaw) for f in planner.footprints()]


@pytest.mark.parametrize("name", ["fig8", "fig8-real-time"])  # quasi-real-time, real-time
def test_a_velocity_command_is_refused_exactly_when_it_would_change_nothing(name: str) -> None:
    scenario = load_scenario(name)
    last = simulate_options.last_command_time(scenario)
    nominal = walked_footprints(name, None)
    assert walked_footprints(name, last) != nominal  # the last moment a command counts
    assert walked_footprints(name, last + 0.001) == nominal  # one tick later it is ignored
    texts = ["0.1,0,0", f"0.25,0,0@{last!r}"]
    simulate_options._check_command_times(texts, [(0.0, 0.1, 0, 0), (last, 0.25, 0, 0)], scenario)
    late = [(0.0, 0.1, 0, 0), (last + 0.001, 0.25, 0, 0)]
    with pytest.raises(ScenarioError, match="after the walk's last step is decided"):
        simulate_options._check_command_times(["0.1,0,0", f"0.25,0,0@{last + 0.001!r}"], late, scenario)


def test_a_late_velocity_command_is_refused_like_a_late_push(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    args = ["simulate", "fig8", "--out", str(tmp_path / "o"), "--velocity", "0.1,0,0", "--velocity", "0,0,0.3@50"]
    assert main(args) == 2
    assert one_error_line(capsys) == (
        "rtgait: error: --velocity 0,0,0.3@50 comes after the walk's last step is decided (at 8.10 s on the walk's "
        "clock): it would change nothing; more walk.steps make the walk longer"
    )
    assert list(tmp_path.iterdir()) == []


# ----- 4. damaged run files --------------------------------------------------------------------------------------


@pytest.mark.parametrize(("size", "words"), [(0, "has no rows"), (60, "has no rows"), (30_000, "cut short")])
def test_plot_of_a_truncated_csv_is_one_error_line(
    size: int, words: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run = tmp_path / "run"
    assert main(["plan", "fig6", "--out", str(run), "--no-figures", "--quiet"]) == 0
    path = run / "trajectory.csv"
    path.write_bytes(path.read_bytes()[:size])
    assert main(["plot", str(run), "--quiet"]) == 2
    err = one_error_line(capsys)  # no warning before it, no Python object in it
    assert words in err and str(path) in err and "<" not in err and "usecols" not in err, err


# ----- 5. footstep plans as sweep bases; 8. [walk] optional in footstep plans -----------------------------------

PLAN = (
    header_text("free-path", "quasi-real-time")
    + """{walk}
[[footstep]]
side = "right"
x = 0.10
y = -0.095
[[footstep]]
side = "left"
x = 0.22
y = 0.10
[[footstep]]
side = "right"
x = 0.30
y = -0.06
yaw = 0.15
{timing}"""
)


def footstep_plan(tmp_path: Path, walk: str = "", timing: str = "") -> Path:
    path = tmp_path / "plan.toml"
    path.write_text(PLAN.format(walk=walk, timing=timing), encoding="utf-8")
    return path


def test_a_footstep_plan_without_walk_takes_the_defaults(tmp_path: Path) -> None:
    without = load_scenario(footstep_plan(tmp_path))
    assert (without.step_width, without.step_height) == (DEFAULT_STEP_WIDTH, DEFAULT_STEP_HEIGHT) == (0.19, 0.05)
    explicit = load_scenario(footstep_plan(tmp_path, walk="[walk]\nstep_width = 0.19\nstep_height = 0.05"))
    assert without == explicit
    partial = load_scenario(footstep_plan(tmp_path, walk="[walk]\nstep_width = 0.2"))
    assert (partial.step_width, partial.step_height) == (0.2, DEFAULT_STEP_HEIGHT)
    with pytest.raises(ScenarioError, match=r"walk\.steps"):  # still a footstep plan's [walk]: width and height only
        load_scenario(footstep_plan(tmp_path, walk="[walk]\nsteps = 3"))
    assert main(["plan", str(footstep_plan(tmp_path)), "--out", str(tmp_path / "o"), "--no-figures", "--quiet"]) == 0


def test_a_sweep_over_a_footstep_plan_gives_what_rtgait_plan_reports(tmp_path: Path) -> None:
    footstep_plan(tmp_path)
    spec_path = tmp_path / "s.toml"
    spec_path.write_text('base = "plan.toml"\n[axes]\n"timing.double_support" = [0.1, 0.3]\n'
                         'connection = ["real-time", "preview"]\n', encoding="utf-8")  # fmt: skip
    assert main(["sweep", str(spec_path), "--out", str(tmp_path / "o"), "--no-figures", "--quiet"]) == 0
    spec = load_spec(spec_path)
    assert scenario_from_document(spec.base_document) == spec.base  # how a physics worker rebuilds it
    rows = read_results(tmp_path / "o")
    assert len(rows) == 4
    for row in rows:
        if row["connection"] == "preview":
            continue  # the preview baseline's numbers: tests/sweep/test_sweep_run.py
        scenario = case_scenario(spec.base, {"timing.double_support": row["timing.double_support"]})
        assert scenario.footholds is not None and scenario.timing.double_support == row["timing.double_support"]
        run = rollout(OnlinePlanner(scenario.planner_config(), scenario.strides()), scenario.dt, scenario.sole)
        summary = summarize(run, scenario)
        assert row["zmp_margin_min"] == pytest.approx(summary["zmp_margin_min"], abs=1e-12)
        assert row["zmp_margin_min_time"] == summary["zmp_margin_min_time"]


@pytest.mark.parametrize(
    ("axes", "timing", "words"),
    [
        ('"walk.step_length" = [0.1]', "", "axes.walk.step_length: the base free-path is a footstep plan, whose "
         "footholds are given one by one: it has no step length to vary"),
        ('"change.length" = [0.1]', "", "it has no [[walk.change]] to vary"),
        ('"timing.single_support" = [0.7]', "single_support = 0.9\n", "whose steps have their own timing"),
    ],
)  # fmt: skip
def test_a_sweep_axis_a_footstep_plan_does_not_have_is_one_clear_line(
    axes: str, timing: str, words: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    footstep_plan(tmp_path, timing=timing)
    (tmp_path / "s.toml").write_text(f'base = "plan.toml"\n[axes]\n{axes}\n', encoding="utf-8")
    assert main(["sweep", str(tmp_path / "s.toml"), "--out", str(tmp_path / "o")]) == 2
    err = one_error_line(capsys)
    assert words in err and "unknown" not in err, err


# ----- 6. play checks its files before the display ---------------------------------------------------------------


def test_play_with_a_bad_robot_file_and_no_display_reports_the_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("mujoco")
    pytest.importorskip("pinocchio")
    for name in ("DISPLAY", "WAYLAND_DISPLAY"):
        monkeypatch.delenv(name, raising=False)
    bad = tmp_path / "bad.toml"
    bad.write_text("name = \n", encoding="utf-8")
    assert main(["play", "--robot", str(bad)]) == 2
    err = one_error_line(capsys)
    assert "bad.toml" in err and "DISPLAY" not in err, err


# ----- 7. Dask's log lines under --quiet -------------------------------------------------------------------------


DASK_PROBE = """
import logging, sys
from rtgait.sweep.executors import DaskExecutor

def warn_in_a_worker():
    logging.getLogger("distributed.worker").warning("probe: worker warning")
    logging.getLogger("distributed.worker").error("probe: worker error")

if __name__ == "__main__":
    executor = DaskExecutor("local", 1, quiet=sys.argv[1] == "quiet")
    try:
        logging.getLogger("distributed.client").warning("probe: client warning")
        executor.client.run(warn_in_a_worker)  # in the worker's process, whose stderr is this one's
    finally:
        executor.close()
    logging.getLogger("distributed.client").warning("probe: after")  # closed: Dask's own levels are back
"""


@pytest.mark.parametrize("quiet", [True, False], ids=["quiet", "not quiet"])
def test_a_quiet_local_cluster_shows_dask_errors_only(quiet: bool, tmp_path: Path) -> None:
    pytest.importorskip("distributed")
    script = tmp_path / "probe.py"  # a file: the workers' processes import the main module again
    script.write_text(DASK_PROBE, encoding="utf-8")
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, str(script), "quiet" if quiet else "loud"], capture_output=True,
                          text=True, env=env, cwd=tmp_path, timeout=120)  # fmt: skip
    assert done.returncode == 0, done.stderr
    probes = sorted(line.split("probe: ")[1] for line in done.stderr.splitlines() if "probe: " in line)
    warnings_ = [] if quiet else ["client warning", "worker warning"]
    assert probes == sorted(["after", "worker error", *warnings_]), done.stderr
