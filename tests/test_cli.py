"""The ``rtgait`` command line, run in-process: outputs, the paper's verdicts, errors and atomic writing."""

from __future__ import annotations

import csv
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rtgait.cli import plan as plan_command
from rtgait.cli.main import main
from rtgait.io.plan_files import plan_files
from rtgait.scenario.loading import load_scenario

HEAD_LINE = (
    "t,cog_x,cog_y,cog_z,cog_vx,cog_vy,cog_ax,cog_ay,zmp_x,zmp_y,lfoot_x,lfoot_y,lfoot_z,lfoot_yaw,"
    "rfoot_x,rfoot_y,rfoot_z,rfoot_yaw,support"
)
"""The documented first columns of trajectory.csv, in order."""
SUMMARY_KEYS = {
    "scenario", "connection", "cog_height", "gravity", "dt", "replans", "zmp_margin_min", "zmp_outside",
    "zmp_margin_min_time", "zmp_margin_min_position", "steps", "duration", "plans", "planning_time_us", "changes",
    "files",
}  # fmt: skip
FIGURES = ("zmp_cog.png", "zmp_deviation.png", "top_view.png", "zmp_margin.png")

VALID = """\
name = "probe"
connection = "real-time"

[robot]
cog_height = 0.8

[robot.sole]
front = 0.13
back = 0.10
inner = 0.07
outer = 0.07

[timing]
single_support = 0.8
double_support = 0.2
dt = 0.01
horizon_steps = 3

[walk]
steps = 3
step_length = 0.1
step_width = 0.19
step_height = 0.05

[[walk.change]]
step = 2
length = 0.12
"""


def read_csv(path: Path) -> tuple[list[str], list[list[str]]]:
    with open(path, newline="", encoding="utf-8") as stream:
        rows = list(csv.reader(stream))
    return rows[0], rows[1:]


@pytest.fixture(scope="module")
def fig4_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """One full ``plan fig4`` with figures, shared by the tests that read its outputs (figures take ~2 s)."""
    out = tmp_path_factory.mktemp("fig4") / "result"
    capture = tmp_path_factory.mktemp("stdout") / "stdout.txt"
    saved = sys.stdout
    with open(capture, "w", encoding="utf-8") as stream:
        sys.stdout = stream  # capsys is function-scoped; a module fixture captures by hand
        try:
            code = main(["plan", "fig4", "--out", str(out)])
        finally:
            sys.stdout = saved
    assert code == 0
    return out, capture.read_text(encoding="utf-8")


# ----- outputs --------------------------------------------------------------------------------------------------


def test_plan_writes_the_csv_with_the_documented_header_and_one_row_per_tick(fig4_run: tuple[Path, str]) -> None:
    out, _ = fig4_run
    first_line = (out / "trajectory.csv").read_text(encoding="utf-8").split("\n", 1)[0]
    assert first_line.startswith(HEAD_LINE + ",")
    header, rows = read_csv(out / "trajectory.csv")
    assert set(header[len(HEAD_LINE.split(",")) :]) >= {"zmp_ref_x", "zmp_ref_y", "zmp_margin", "phase"}
    scenario = load_scenario("fig4")
    assert len(rows) == math.floor(scenario.duration / scenario.dt + 1e-9) + 1
    assert all(len(row) == len(header) for row in rows)
    t = np.array([float(row[0]) for row in rows])
    assert t[0] == 0.0 and np.allclose(np.diff(t), scenario.dt, atol=1e-9)
    assert {row[header.index("support")] for row in rows} == {"double", "left", "right"}
    cog_z = np.array([float(row[header.index("cog_z")]) for row in rows])
    assert np.all(cog_z == 0.8)  # constant-height model


def test_csv_margin_column_agrees_with_the_summary(fig4_run: tuple[Path, str]) -> None:
    out, _ = fig4_run
    header, rows = read_csv(out / "trajectory.csv")
    margin = np.array([float(row[header.index("zmp_margin")]) for row in rows])
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    worst = int(np.argmin(margin))
    assert margin[worst] == pytest.approx(summary["zmp_margin_min"], abs=1e-9)
    assert float(rows[worst][0]) == pytest.approx(summary["zmp_margin_min_time"])
    zmp = [float(rows[worst][header.index(name)]) for name in ("zmp_x", "zmp_y")]
    assert zmp == pytest.approx(summary["zmp_margin_min_position"], abs=1e-9)


def test_summary_has_the_documented_keys_and_the_papers_verdict(fig4_run: tuple[Path, str]) -> None:
    out, _ = fig4_run
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert set(summary) >= SUMMARY_KEYS
    assert summary["scenario"] == "fig4" and summary["connection"] == "real-time"
    assert (summary["cog_height"], summary["gravity"], summary["dt"]) == (0.8, 9.81, 0.005)
    assert summary["zmp_outside"] is True and summary["zmp_margin_min"] < -0.05
    assert 5.8 <= summary["zmp_margin_min_time"] <= 6.0
    # Twelve plans: the first at the start, then one per double support of steps 1..10 and the final one.
    assert summary["plans"] == 12 and summary["replans"] == 11
    assert summary["changes"] == [
        {"step": 5, "decided_at": pytest.approx(5.0), "length": 0.15, "width": None, "yaw": None, "through": 10}
    ]
    assert summary["planning_time_us"]["replan_median"] > 0.0
    assert sorted(summary["files"]) == sorted(["trajectory.csv", "summary.json", *FIGURES])


def test_figures_are_written_as_non_empty_pngs(fig4_run: tuple[Path, str]) -> None:
    out, _ = fig4_run
    for name in FIGURES:
        data = (out / name).read_bytes()
        assert data.startswith(b"\x89PNG\r\n\x1a\n"), name
        assert len(data) > 10_000, name  # a blank canvas compresses to a few kB


def test_printed_summary_gives_the_verdict_where_when_and_the_outputs(fig4_run: tuple[Path, str]) -> None:
    out, printed = fig4_run
    assert "fig4" in printed and "real-time" in printed
    assert "OUTSIDE" in printed
    assert "µs" in printed and "11 connected replans" in printed
    assert str(out) in printed
    assert len(printed.splitlines()) <= 12


def test_no_leftovers_beside_the_output_folder(fig4_run: tuple[Path, str]) -> None:
    out, _ = fig4_run
    assert [p.name for p in out.parent.iterdir()] == [out.name]


def test_the_files_checked_before_the_run_are_the_files_written(fig4_run: tuple[Path, str], tmp_path: Path) -> None:
    # The destination is checked for these names before the run: a name missing there would be checked too late.
    out, _ = fig4_run
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["files"] == plan_files(figures=True, robot=False, html=False)
    assert main(["plan", "fig6", "--out", str(tmp_path / "o"), "--no-figures", "--quiet"]) == 0
    summary = json.loads((tmp_path / "o" / "summary.json").read_text(encoding="utf-8"))
    assert summary["files"] == plan_files(figures=False, robot=False, html=False)


@pytest.mark.parametrize("name", ["fig6", "fig7", "fig8"])
def test_paper_walks_that_keep_balance_are_reported_inside(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["plan", name, "--out", str(tmp_path / name), "--no-figures"]) == 0
    summary = json.loads((tmp_path / name / "summary.json").read_text(encoding="utf-8"))
    assert summary["zmp_outside"] is False and summary["zmp_margin_min"] > 0.0
    assert "inside the support polygon" in capsys.readouterr().out
    assert sorted(p.name for p in (tmp_path / name).iterdir()) == ["summary.json", "trajectory.csv"]


def test_dt_option_sets_the_control_period(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["plan", "fig8", "--out", str(tmp_path), "--dt", "0.02", "--no-figures", "--quiet"]) == 0
    assert capsys.readouterr() == ("", "")
    _, rows = read_csv(tmp_path / "trajectory.csv")
    assert len(rows) == math.floor(load_scenario("fig8").duration / 0.02 + 1e-9) + 1
    assert json.loads((tmp_path / "summary.json").read_text(encoding="utf-8"))["dt"] == 0.02


def test_default_output_folder_is_out_slash_name(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    path = tmp_path / "walk.toml"
    path.write_text(VALID, encoding="utf-8")
    assert main(["plan", "walk.toml", "--no-figures", "--quiet"]) == 0
    assert (tmp_path / "out" / "probe" / "trajectory.csv").is_file()


def test_rerun_replaces_outputs_and_keeps_other_files(tmp_path: Path) -> None:
    keep = tmp_path / "notes.txt"
    keep.write_text("mine", encoding="utf-8")
    (tmp_path / "trajectory.csv").write_text("stale", encoding="utf-8")
    assert main(["plan", "fig6", "--out", str(tmp_path), "--no-figures", "--quiet"]) == 0
    assert keep.read_text(encoding="utf-8") == "mine"
    assert (tmp_path / "trajectory.csv").read_text(encoding="utf-8").startswith("t,cog_x")
    assert sorted(p.name for p in tmp_path.parent.iterdir() if p.name.startswith(f".{tmp_path.name}")) == []


def test_failed_write_leaves_nothing_behind(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import rtgait.viz.figures as figures

    def broken(*args: object) -> list[Path]:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(figures, "render_all", broken)
    out = tmp_path / "result"
    assert main(["plan", "fig6", "--out", str(out)]) == 1
    assert list(tmp_path.iterdir()) == []  # neither the folder nor the staging folder
    assert capsys.readouterr().err.strip() == f"rtgait: error: cannot write outputs to {out}: No space left on device"


def test_progress_is_shown_only_on_a_terminal(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(plan_command, "PROGRESS_MIN_TICKS", 0)
    assert main(["plan", "fig6", "--out", str(tmp_path / "a"), "--no-figures"]) == 0
    assert capsys.readouterr().err == ""  # captured stderr is not a terminal
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    assert main(["plan", "fig6", "--out", str(tmp_path / "b"), "--no-figures"]) == 0
    err = capsys.readouterr().err
    assert "rtgait: planning fig6" in err and "%" in err and "ticks/s" in err  # tqdm's bar, with its rate
    assert main(["plan", "fig6", "--out", str(tmp_path / "c"), "--no-figures", "--quiet"]) == 0
    assert capsys.readouterr().err == ""


def test_format_option_writes_valid_svg_and_pdf_figures(tmp_path: Path) -> None:
    import xml.etree.ElementTree as ElementTree

    out = tmp_path / "svg"
    assert main(["plan", "fig6", "--out", str(out), "--format", "svg", "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["files"] == plan_files(figures=True, robot=False, html=False, fmt="svg")
    assert sorted(p.name for p in out.iterdir()) == sorted(summary["files"])
    for name in FIGURES:
        svg = out / name.replace(".png", ".svg")
        assert ElementTree.parse(svg).getroot().tag == "{http://www.w3.org/2000/svg}svg", name
    out = tmp_path / "pdf"
    argv = ["simulate", "fig8", "--model", "lipm", "--out", str(out), "--format", "pdf", "--quiet"]
    assert main(argv) == 0
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["files"] == ["sim.csv", "summary.json", "pendulum.pdf"]
    data = (out / "pendulum.pdf").read_bytes()
    assert data.startswith(b"%PDF-") and data.rstrip().endswith(b"%%EOF")


def test_format_is_refused_where_it_would_be_ignored(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # The MuJoCo run writes zmp_sim in any of the formats (tests/sim/test_sim_cli.py); an unknown one is refused.
    assert main(["plan", "fig6", "--format", "jpg"]) == 2
    assert "invalid choice: 'jpg'" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_progress_printer_is_a_tqdm_bar_fed_with_the_fraction_done() -> None:
    import io

    from rtgait.cli.common import progress_printer

    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

    stream = Terminal()
    progress = progress_printer(stream, "rtgait: simulating probe")
    for fraction in (0.0, 0.5, 1.0):
        progress(fraction)
    text = stream.getvalue()
    assert "rtgait: simulating probe" in text and "%" in text and "<" in text  # the share done and the time left
    assert text.endswith("\r")  # closed at 1.0: the bar erased itself, the next line starts clean
    log = io.StringIO()  # not a terminal: a log file or a pipe gets nothing
    progress_printer(log, "rtgait: planning probe", total=10)(1.0)
    assert log.getvalue() == ""


# ----- listing and entry points ---------------------------------------------------------------------------------


def test_scenarios_lists_every_builtin_with_its_description(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["scenarios"]) == 0
    lines = capsys.readouterr().out.splitlines()
    names = [line.split()[0] for line in lines]
    assert names == [
        "fig4", "fig6", "fig7", "fig8", "fig8-real-time", "fig11", "guided", "obstacle", "sidestep", "slope-down",
        "slope-down-g1", "slope-up", "slope-up-g1", "stairs-down", "stairs-down-185", "stairs-down-g1", "stairs-up",
        "stairs-up-185", "stairs-up-g1", "stepping-stones", "turn", "unseen-step", "unseen-step-g1",
    ]  # fmt: skip
    assert all(len(line.split(maxsplit=1)) == 2 for line in lines)


def test_python_dash_m_runs_the_same_command() -> None:
    done = subprocess.run(
        [sys.executable, "-m", "rtgait", "scenarios"], capture_output=True, text=True, timeout=60, check=False
    )
    assert done.returncode == 0
    assert done.stdout.splitlines()[0].startswith("fig4")


# ----- bad input ------------------------------------------------------------------------------------------------

BAD_FILES = [
    ("missing key", ("step_height = 0.05\n", ""), "walk.step_height"),
    ("negative duration", ("double_support = 0.2", "double_support = -0.2"), "timing.double_support"),
    ("zero duration", ("single_support = 0.8", "single_support = 0.0"), "timing.single_support"),
    ("nan", ("cog_height = 0.8", "cog_height = nan"), "robot.cog_height"),
    ("inf", ("step_length = 0.1", "step_length = -inf"), "walk.step_length"),
    ("step that does not exist", ("step = 2", "step = 4"), "walk.change[0].step"),
    ("connection mode", ('connection = "real-time"', 'connection = "realtime"'), "connection"),
    ("invalid TOML", ("[walk]", "[walk"), "invalid TOML"),
    ("unknown key", ("step_width = 0.19", "step_widht = 0.19"), "walk.step_widht"),
    ("dt longer than a phase", ("dt = 0.01", "dt = 0.3"), "timing.dt"),
    ("dt below the limit", ("dt = 0.01", "dt = 1e-6"), "timing.dt must be within [1e-05, 60] s"),
    (
        "two changes of one step",
        ("length = 0.12\n", "length = 0.12\n\n[[walk.change]]\nstep = 2\nwidth = 0.2\n"),
        "walk.change[0] and walk.change[1] both change step 2",
    ),
]


def assert_rejected(
    code: int, capsys: pytest.CaptureFixture[str], expected: str, folder: Path, allowed: set[str]
) -> None:
    """Exit code 2, a single ``rtgait: error:`` line naming ``expected``, and nothing written in ``folder``."""
    err = capsys.readouterr().err
    assert code == 2
    assert len(err.splitlines()) == 1, err
    assert err.startswith("rtgait: error: ") and expected in err, err
    assert {p.name for p in folder.iterdir()} == allowed


@pytest.mark.parametrize(("case", "edit", "expected"), BAD_FILES, ids=[case for case, _, _ in BAD_FILES])
def test_bad_scenario_file_exits_2_with_one_line_and_writes_nothing(
    case: str,
    edit: tuple[str, str],
    expected: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert edit[0] in VALID, case
    monkeypatch.chdir(tmp_path)  # the default output folder would be created here
    (tmp_path / "walk.toml").write_text(VALID.replace(*edit, 1), encoding="utf-8")
    assert_rejected(main(["plan", "walk.toml"]), capsys, expected, tmp_path, {"walk.toml"})
    assert_rejected(main(["plan", "walk.toml", "--out", "res"]), capsys, expected, tmp_path, {"walk.toml"})


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["plan", "fig5"], "unknown scenario 'fig5'"),
        (["plan", "missing.toml"], "cannot read scenario file missing.toml"),
        (["plan", "fig4", "--dt", "-0.01"], "--dt must be a number > 0 s"),
        (["plan", "fig4", "--dt", "nan"], "--dt must be a number > 0 s"),
        (["plan", "fig4", "--dt", "0.5"], "--dt must not exceed the shortest phase"),
        (["plan", "fig4", "--dt", "1e-7"], "--dt must be at least 1e-05 s"),
        (["plan", "fig4", "--dt", "-1e-3"], "--dt must be a number > 0 s"),  # not taken for an option
    ],
)
def test_bad_arguments_exit_2_with_one_line_and_write_nothing(
    argv: list[str], expected: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    assert_rejected(main(argv), capsys, expected, tmp_path, set())


def test_unreadable_scenario_file_is_bad_input(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "folder.toml").mkdir()  # reading a folder fails even for root, unlike chmod 000
    assert_rejected(main(["plan", "folder.toml"]), capsys, "cannot read scenario file folder.toml", tmp_path,
                    {"folder.toml"})  # fmt: skip


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        ([], "choose a command"),
        (["plan"], "the following arguments are required: SCENARIO"),
        (["plan", "fig4", "--dt", "fast"], "--dt: invalid float value: 'fast'"),
        (["plan", "fig4", "--bogus"], "unrecognized arguments: --bogus"),
        (["plan", "fig4", "--out"], "--out: expected one argument"),
        (["walk"], "invalid choice: 'walk'"),
        (["simulate", "fig8", "--robot"], "--robot: expected one argument"),
    ],
)
def test_usage_errors_exit_2_with_one_line(argv: list[str], expected: str, capsys: pytest.CaptureFixture[str]) -> None:
    # argparse's own errors too: one line naming the problem and where help is, no usage block.
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("rtgait: error: ") and len(err.splitlines()) == 1, err
    assert expected in err and "--help" in err and "usage:" not in err


def test_help_exits_0(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["plan", "--help"]) == 0
    assert "--no-figures" in capsys.readouterr().out
