"""The command line against hostile or careless input: sizes beyond the limits, destinations that cannot receive the
outputs, failures and Ctrl-C while the outputs move, option values that start with a minus sign."""

from __future__ import annotations

import os
import re
import signal
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from scenario_files import scenario_text

from rtgait import outputs
from rtgait.cli import main as cli
from rtgait.cli import plan as plan_command
from rtgait.cli.main import main
from rtgait.core import limits
from rtgait.outputs import destination

BASE = scenario_text()


def edited(*edits: tuple[str, str]) -> str:
    text = BASE
    for old, new in edits:
        assert old in text, old  # a typo in a case must not silently test the valid file
        text = text.replace(old, new, 1)
    return text


def one_error_line(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err
    assert err.startswith("rtgait: error: ") and len(err.splitlines()) == 1, err
    return err


@pytest.fixture
def no_planning(monkeypatch: pytest.MonkeyPatch) -> None:
    """Fail the test if the CLI starts a rollout: every check must come before any work."""

    def planned(*args: object, **kwargs: object) -> None:
        raise AssertionError("the rollout started before the input was refused")

    monkeypatch.setattr(plan_command, "rollout", planned)


# ----- 1. every size is bounded before any work -----------------------------------------------------------------

SIZES = [
    ("walk too long", [("[walk]\nsteps = 3", "[walk]\nsteps = 100000000")], "walk.steps", str(limits.MAX_STEPS - 1)),
    ("settle too long", [("horizon_steps = 3", "horizon_steps = 3\nsettle = 1e6")], "timing.settle", "60"),
    ("period too short", [("dt = 0.01", "dt = 1e-7")], "timing.dt", "1e-05"),
    ("phase and period tiny", [("dt = 0.01", "dt = 1e-12"), ("double_support = 0.2", "double_support = 1e-12")],
     "timing.double_support", "0.001"),
    ("COG height tiny", [("cog_height = 0.8", "cog_height = 1e-6")], "robot.cog_height", "[0.05, 10]"),
    ("gravity huge", [("cog_height = 0.8", "cog_height = 0.8\ngravity = 1e9")], "robot.gravity", "[0.1, 100]"),
    ("horizon too long", [("horizon_steps = 3", "horizon_steps = 21")], "timing.horizon_steps", "20"),
    ("w T too large", [("horizon_steps = 3", "horizon_steps = 3\nsettle = 6.0")], "timing.settle", "w*T"),
    ("too many ticks", [("[walk]\nsteps = 3", "[walk]\nsteps = 200"), ("dt = 0.01", "dt = 0.0001")], "timing.dt",
     "1000000"),
    ("stride too long", [("step_length = 0.1", "step_length = 2.5")], "walk.step_length", "[-2, 2]"),
]  # fmt: skip
"""(case, edits of BASE, the field the message names, the limit it states)."""


@pytest.mark.parametrize(("case", "edits", "field", "limit"), SIZES, ids=[case for case, *_ in SIZES])
@pytest.mark.usefixtures("no_planning")
def test_a_size_beyond_the_limits_is_one_line_and_exit_2_before_any_work(
    case: str,
    edits: list[tuple[str, str]],
    field: str,
    limit: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "walk.toml").write_text(edited(*edits), encoding="utf-8")
    assert main(["plan", "walk.toml", "--no-figures"]) == 2
    err = one_error_line(capsys)
    assert field in err and limit in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["walk.toml"]


@pytest.mark.parametrize(
    ("dt", "words"),
    [("1e-7", ["--dt", "1e-05"]), ("1e-5", ["--dt", "1000000", "12.7 s"])],  # fig8 walks 12.7 s
)
@pytest.mark.usefixtures("no_planning")
def test_the_dt_option_is_bounded_like_the_file(
    dt: str, words: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["plan", "fig8", "--dt", dt, "--out", str(tmp_path / "o"), "--no-figures"]) == 2
    err = one_error_line(capsys)
    assert all(word in err for word in words), err
    assert not (tmp_path / "o").exists()


@pytest.mark.usefixtures("no_planning")
def test_a_fourier_order_beyond_the_samples_of_a_phase_is_refused_before_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Order 10**9 would allocate its coefficients (per phase, per axis) long before the fit could object.
    args = ["plan", "fig11", "--compensate-angular-momentum", "1000000000", "--out", str(tmp_path / "o")]
    assert main(args) == 2
    assert "ORDER 1000000000 needs 2000000001 samples" in one_error_line(capsys)


# ----- 2. a run replaces its whole set of outputs or changes nothing --------------------------------------------


def old_outputs(folder: Path) -> dict[str, str]:
    """Previous outputs of a `plan --no-figures` run and a file of the user's, in ``folder``."""
    folder.mkdir()
    files = {"trajectory.csv": "old trajectory", "summary.json": '{"old": true}', "notes.txt": "mine"}
    for name, text in files.items():
        (folder / name).write_text(text, encoding="utf-8")
    return files


def contents(folder: Path) -> dict[str, str]:
    return {p.name: p.read_text(encoding="utf-8") for p in folder.iterdir() if p.is_file()}


def no_leftovers(tmp_path: Path, out: Path) -> None:
    hidden = [p for p in [*tmp_path.iterdir(), *out.iterdir()] if p.name.startswith(".")]
    assert hidden == [], hidden


@pytest.mark.usefixtures("no_planning")
def test_a_destination_name_that_is_a_folder_is_refused_before_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "o"
    (out / "summary.json").mkdir(parents=True)
    (out / "trajectory.csv").write_text("old trajectory", encoding="utf-8")
    assert main(["plan", "fig6", "--out", str(out), "--no-figures"]) == 1
    assert "summary.json is a folder" in one_error_line(capsys)
    assert (out / "trajectory.csv").read_text(encoding="utf-8") == "old trajectory"


def test_a_destination_that_turns_into_a_folder_during_the_run_changes_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "o"
    before = old_outputs(out)
    real_rollout = plan_command.rollout

    def rollout_then_block(*args: Any, **kwargs: Any) -> Any:
        (out / "summary.json").unlink()
        (out / "summary.json").mkdir()  # after the check made before the run
        return real_rollout(*args, **kwargs)

    monkeypatch.setattr(plan_command, "rollout", rollout_then_block)
    assert main(["plan", "fig6", "--out", str(out), "--no-figures"]) == 1
    assert "summary.json is a folder" in one_error_line(capsys)
    assert contents(out) == {name: text for name, text in before.items() if name != "summary.json"}
    no_leftovers(tmp_path, out)


def failing_nth_call(real: Callable[..., Any], n: int, failure: Callable[[], None]) -> Callable[..., Any]:
    """``real``, except that its ``n``-th call (1-based) runs ``failure`` first (which may raise)."""
    calls = [0]

    def wrapper(*args: Any) -> Any:
        calls[0] += 1
        if calls[0] == n:
            failure()
        return real(*args)

    return wrapper


def raise_(error: BaseException) -> Callable[[], None]:
    def fail() -> None:
        raise error

    return fail


# Replacing two old files moves 2 aside and 2 new ones in: 4 renames; a failure at any of them must undo the rest.
MOVES = range(1, 5)


@pytest.mark.parametrize("n", MOVES)
def test_a_write_error_while_the_files_move_puts_the_old_ones_back(
    n: int, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "o"
    before = old_outputs(out)
    disk_full = raise_(OSError(28, "No space left on device"))
    monkeypatch.setattr(os, "replace", failing_nth_call(os.replace, n, disk_full))
    assert main(["plan", "fig6", "--out", str(out), "--no-figures", "--quiet"]) == 1
    assert one_error_line(capsys).strip() == f"rtgait: error: cannot write outputs to {out}: No space left on device"
    assert contents(out) == before
    no_leftovers(tmp_path, out)


@pytest.mark.parametrize("n", MOVES)
def test_an_interrupt_while_the_files_move_changes_nothing(
    n: int, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "o"
    before = old_outputs(out)
    monkeypatch.setattr(os, "replace", failing_nth_call(os.replace, n, raise_(KeyboardInterrupt())))
    assert main(["plan", "fig6", "--out", str(out), "--no-figures", "--quiet"]) == 130
    assert one_error_line(capsys).strip() == "rtgait: error: interrupted"
    assert contents(out) == before
    no_leftovers(tmp_path, out)


def ctrl_c() -> None:
    os.kill(os.getpid(), signal.SIGINT)  # a real Ctrl-C, delivered to the main thread (pytest runs tests there)


@pytest.fixture
def terminal_sigint() -> Iterator[None]:
    """SIGINT as a program started from a terminal has it: Python's own handler, installed in the process again
    (a library loaded by an earlier test in this process may have left another disposition), restored after."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


@pytest.mark.usefixtures("terminal_sigint")
@pytest.mark.parametrize("n", MOVES)
def test_a_real_ctrl_c_while_the_files_move_is_held_back_then_undoes_them(
    n: int, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "o"
    before = old_outputs(out)
    monkeypatch.setattr(os, "replace", failing_nth_call(os.replace, n, ctrl_c))
    assert main(["plan", "fig6", "--out", str(out), "--no-figures", "--quiet"]) == 130
    assert contents(out) == before
    no_leftovers(tmp_path, out)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # Python's own handler is back


@pytest.mark.usefixtures("terminal_sigint")
def test_a_ctrl_c_while_a_new_folder_is_moved_in_leaves_no_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    out = tmp_path / "new" / "o"
    monkeypatch.setattr(os, "rename", failing_nth_call(os.rename, 1, ctrl_c))
    assert main(["plan", "fig6", "--out", str(out), "--no-figures", "--quiet"]) == 130
    assert list(tmp_path.iterdir()) == []  # neither the folder, nor the staging one, nor the parent created for it


@pytest.mark.usefixtures("no_planning")
def test_an_out_that_is_a_file_is_refused_before_the_run(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "o").write_text("a file", encoding="utf-8")
    assert main(["plan", "fig6", "--out", str(tmp_path / "o"), "--no-figures"]) == 1
    assert "exists and is not a folder" in one_error_line(capsys)
    assert main(["plan", "fig6", "--out", str(tmp_path / "o" / "sub"), "--no-figures"]) == 1
    assert "is not a folder" in one_error_line(capsys)


@pytest.mark.usefixtures("no_planning")
def test_an_out_below_a_folder_that_is_not_writable_is_refused_before_the_run(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    locked = tmp_path / "locked"
    locked.mkdir()
    # As if chmod 0555 (which does not stop root, who may run this suite).
    monkeypatch.setattr(destination, "writable", lambda path: Path(path) != locked)
    assert main(["plan", "fig6", "--out", str(locked / "a" / "b"), "--no-figures"]) == 1
    assert f"{locked} is not writable" in one_error_line(capsys)
    assert main(["plan", "fig6", "--out", str(locked), "--no-figures"]) == 1
    assert "the folder is not writable" in one_error_line(capsys)
    assert list(locked.iterdir()) == []


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="needs POSIX permissions that bind the user")
def test_a_read_only_parent_folder_is_refused_for_real(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o555)
    try:
        assert main(["plan", "fig6", "--out", str(locked / "o"), "--no-figures"]) == 1
        assert "is not writable" in one_error_line(capsys)
    finally:
        locked.chmod(0o755)


@pytest.mark.usefixtures("no_planning")
def test_an_empty_out_is_bad_input_and_writes_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)  # Path("") is the working folder: that is where it would have written
    for command in ("plan", "simulate"):
        assert main([command, "fig8", "--out", ""]) == 2
        assert "--out" in one_error_line(capsys)
    assert list(tmp_path.iterdir()) == []


def test_write_atomic_never_leaves_a_half_written_file(tmp_path: Path) -> None:
    target = tmp_path / "data.csv"
    target.write_text("old", encoding="utf-8")

    def half_then_fail(path: Path) -> None:
        path.write_text("half", encoding="utf-8")
        raise OSError(28, "No space left on device")

    with pytest.raises(OSError, match="No space"):
        outputs.write_atomic(target, half_then_fail)
    assert [p.name for p in tmp_path.iterdir()] == ["data.csv"] and target.read_text(encoding="utf-8") == "old"
    outputs.write_text_atomic(target, "new")
    assert [p.name for p in tmp_path.iterdir()] == ["data.csv"] and target.read_text(encoding="utf-8") == "new"


def test_there_is_one_atomic_write_helper() -> None:
    # A second copy would drift from this one (it did: three copies, each with its own clean-up rules).
    home = Path(outputs.__file__).parent  # rtgait/outputs: the one place that renames files
    package = home.parent
    renames = re.compile(r"\b(os\.replace|os\.rename|shutil\.move)\(")
    offenders = [
        str(path.relative_to(package))
        for path in sorted(package.rglob("*.py"))
        if home not in path.parents and renames.search(path.read_text(encoding="utf-8"))
    ]
    assert offenders == []


# ----- 4. option values with a minus sign, and argparse's own messages ------------------------------------------


@pytest.mark.parametrize(
    ("argv", "attribute", "value"),
    [
        # --velocity may be repeated (a command from a time on, VX,VY,WZ@T): a list of its values
        (["simulate", "fig8", "--velocity", "-0.1,0,0"], "velocity", ["-0.1,0,0"]),
        (["simulate", "fig8", "--velocity=-0.1,0,0"], "velocity", ["-0.1,0,0"]),
        (["simulate", "fig8", "--vel", "-0.1,0,0"], "velocity", ["-0.1,0,0"]),  # argparse's unique prefixes
        (["simulate", "fig8", "--push", "-1,0.1,50,0", "--push", "2,0.1,-50,0"], "push",
         ["-1,0.1,50,0", "2,0.1,-50,0"]),
        (["plan", "fig8", "--dt", "-1e-3"], "dt", -1e-3),
        (["simulate", "fig8", "--velocity", ".1,-.1,0"], "velocity", [".1,-.1,0"]),
    ],
)  # fmt: skip
def test_option_values_may_start_with_a_minus_sign(argv: list[str], attribute: str, value: object) -> None:
    assert getattr(cli._build_parser().parse_args(argv), attribute) == value


def test_a_negative_value_reaches_the_checks_and_is_refused_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("mujoco")
    assert main(["simulate", "fig8", "--push", "-1,0.1,50,0", "--out", str(tmp_path / "o")]) == 2
    assert "--push start must be a time >= 0 s" in one_error_line(capsys)
    assert main(["plan", "fig8", "--dt", "-1e-3", "--out", str(tmp_path / "o")]) == 2
    assert "--dt must be a number > 0 s" in one_error_line(capsys)
    assert not (tmp_path / "o").exists()


def test_a_name_after_a_value_option_is_not_glued(capsys: pytest.CaptureFixture[str]) -> None:
    # Only number-like values are taken for the option's value: a real option after it keeps its meaning.
    args = cli._build_parser().parse_args(["plan", "fig8", "--out", "o", "--dt", "0.01", "--no-figures"])
    assert (args.out, args.dt, args.no_figures) == (Path("o"), 0.01, True)
    assert main(["plan", "fig8", "--robot", "--no-figures"]) == 2
    assert "--robot: expected one argument" in one_error_line(capsys)


def test_help_and_version_still_exit_0(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--help"]) == 0
    assert "usage: rtgait" in capsys.readouterr().out
    assert main(["simulate", "--help"]) == 0
    assert "--velocity" in capsys.readouterr().out
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.startswith("rtgait ")


def test_a_warning_during_a_command_is_one_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def command(args: object) -> int:
        warnings.warn("velocity command exceeds the step limits:\n  clamped", UserWarning, stacklevel=1)
        return 0

    monkeypatch.setitem(cli._COMMANDS, "scenarios", command)
    assert main(["scenarios"]) == 0
    assert capsys.readouterr().err == "rtgait: warning: velocity command exceeds the step limits: clamped\n"


@pytest.mark.parametrize("command", [["plan", "fig8"], ["simulate", "fig8", "--model", "lipm"]])
def test_an_output_folder_name_the_file_system_refuses_is_one_error_line(
    command: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / ("a" * 300)  # longer than a file name may be (255 bytes on Linux)
    assert main([*command, "--out", str(out), "--no-figures", "--quiet"]) == 1
    assert one_error_line(capsys).strip() == f"rtgait: error: cannot write outputs to {out}: File name too long"
    assert list(tmp_path.iterdir()) == []
