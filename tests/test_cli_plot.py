"""``rtgait plot DIR``: a finished run's figures drawn again from its files, and the folders it refuses."""

from __future__ import annotations

import json
import struct
import sys
import xml.etree.ElementTree as ElementTree
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from matplotlib.figure import Figure
from matplotlib.image import imread
from scenario_files import scenario_text

from rtgait.cli.main import main
from rtgait.core.analysis.rollout import rollout
from rtgait.core.planner.online import OnlinePlanner
from rtgait.io.pendulum_run import simulate_pendulum, write_pendulum_outputs
from rtgait.io.plan_files import write_plan_outputs
from rtgait.scenario.loading import load_scenario
from rtgait.viz.figures import DRAW
from rtgait.viz.pendulum import PendulumRun, draw_pendulum, read_pendulum_run
from rtgait.viz.run_data import FigureInfo, PlanRun, read_plan_run

PLAN_FIGURES = ("zmp_cog.png", "zmp_deviation.png", "top_view.png", "zmp_margin.png")
PUSH = (5.0, 0.1, 250.0, 0.0)  # 25 N s forward at the start of step 5's double support


def _quiet_main(argv: list[str]) -> int:
    saved = sys.stdout
    try:
        with open(Path(argv[argv.index("--out") + 1]).parent / "stdout.txt", "w", encoding="utf-8") as stream:
            sys.stdout = stream  # module fixtures cannot use capsys
            return main(argv)
    finally:
        sys.stdout = saved


@pytest.fixture(scope="module")
def plan_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``rtgait plan fig8`` with its figures."""
    out = tmp_path_factory.mktemp("plan") / "fig8"
    assert _quiet_main(["plan", "fig8", "--out", str(out)]) == 0
    return out


@pytest.fixture(scope="module")
def lipm_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``rtgait simulate fig8 --model lipm`` with a push, with its figure."""
    out = tmp_path_factory.mktemp("lipm") / "fig8-sim"
    push = ",".join(f"{v:g}" for v in PUSH)
    assert _quiet_main(["simulate", "fig8", "--model", "lipm", "--push", push, "--out", str(out)]) == 0
    return out


def _png_size(path: Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data.startswith(b"\x89PNG\r\n\x1a\n")
    return struct.unpack(">II", data[16:24])  # the IHDR chunk: width, height


def _drawn(figure: Figure) -> list[tuple[str, np.ndarray, tuple[float, float], tuple[float, float]]]:
    """Every line, patch (soles, polygons, shadings) and filled band of every panel, with the panel's limits: what a
    figure shows, as numbers."""
    out = []
    for ax in figure.axes:
        shapes = [(line.get_label(), np.asarray(line.get_xydata(), dtype=float)) for line in ax.get_lines()]
        shapes += [(str(patch.get_label()), patch.get_patch_transform().transform(patch.get_path().vertices))
                   for patch in ax.patches]  # fmt: skip
        shapes += [(str(band.get_label()), np.concatenate([path.vertices for path in band.get_paths()]))
                   for band in ax.collections if band.get_paths()]  # fmt: skip
        out += [(label, data, ax.get_xlim(), ax.get_ylim()) for label, data in shapes]
    return out


def _assert_same_drawing(a: Figure, b: Figure, atol: float) -> None:
    first, second = _drawn(a), _drawn(b)
    assert len(first) == len(second) and first
    for (label_a, data_a, xlim_a, ylim_a), (label_b, data_b, xlim_b, ylim_b) in zip(first, second, strict=True):
        assert label_a == label_b
        np.testing.assert_allclose(data_a, data_b, atol=atol, rtol=0)  # NaN where NaN: the same breaks in the lines
        assert xlim_a == pytest.approx(xlim_b, abs=atol) and ylim_a == pytest.approx(ylim_b, abs=atol)
    texts = [[t.get_text() for t in f.texts] + [ax.get_title(loc="right") for ax in f.axes] for f in (a, b)]
    assert texts[0] == texts[1]


# ----- the same figures ----------------------------------------------------------------------------------------


def test_plan_figures_drawn_from_the_files_are_those_of_the_run(tmp_path: Path) -> None:
    scenario = load_scenario("fig8")
    result = rollout(OnlinePlanner(scenario.planner_config(), scenario.strides()), scenario.dt, scenario.sole,
                     scenario.changes)  # fmt: skip
    write_plan_outputs(result, scenario, tmp_path, figures=False)
    from_files, info_files, _ = read_plan_run(tmp_path)
    in_memory = PlanRun.from_rollout(result)
    info = FigureInfo(f"{scenario.name} ({scenario.connection})", scenario.sole, scenario.nominal_footprints())
    assert info_files == FigureInfo(info.title, info.sole, info_files.nominal_footprints)
    assert list(info_files.nominal_footprints) == list(info.nominal_footprints)
    assert from_files.free_segments == in_memory.free_segments and from_files.changes == in_memory.changes
    for draw in DRAW.values():
        # The CSV keeps 10 significant digits: 1e-6 is a micrometre on the axes in m, a nanometre on those in mm.
        _assert_same_drawing(draw(in_memory, info), draw(from_files, info_files), atol=1e-6)


def test_pendulum_figure_drawn_from_the_files_is_that_of_the_run(tmp_path: Path) -> None:
    scenario = load_scenario("fig8")
    result = simulate_pendulum(scenario, "adaptive", [PUSH])
    write_pendulum_outputs(result, tmp_path, {"scenario": scenario.name, "connection": scenario.connection})
    from_files, _ = read_pendulum_run(tmp_path)
    in_memory = PendulumRun.from_result(result, f"{scenario.name} ({scenario.connection})")
    assert from_files.step_adjustments == in_memory.step_adjustments and from_files.pushes == in_memory.pushes
    _assert_same_drawing(draw_pendulum(in_memory), draw_pendulum(from_files), atol=1e-6)


def test_plot_remakes_a_plan_runs_figures(plan_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    summary_before = (plan_run / "summary.json").read_bytes()
    out = tmp_path / "again"
    assert main(["plot", str(plan_run), "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == sorted(PLAN_FIGURES)
    for name in PLAN_FIGURES:
        assert _png_size(out / name) == _png_size(plan_run / name), name
        # The same numbers through the same code: at most a few anti-aliased pixels differ.
        assert np.abs(imread(out / name) - imread(plan_run / name)).mean() < 1e-3, name
    assert "zmp_cog.png" in capsys.readouterr().out
    assert (plan_run / "summary.json").read_bytes() == summary_before


def test_plot_remakes_a_lipm_runs_figure_in_another_format(lipm_run: Path) -> None:
    summary_before = (lipm_run / "summary.json").read_bytes()
    assert main(["plot", str(lipm_run), "--format", "svg", "--quiet"]) == 0
    root = ElementTree.parse(lipm_run / "pendulum.svg").getroot()
    assert root.tag == "{http://www.w3.org/2000/svg}svg"
    assert (lipm_run / "summary.json").read_bytes() == summary_before  # plot writes figures only
    assert main(["plot", str(lipm_run), "--out", str(lipm_run.parent / "png"), "--quiet"]) == 0
    again, first = lipm_run.parent / "png" / "pendulum.png", lipm_run / "pendulum.png"
    assert _png_size(again) == _png_size(first) and np.abs(imread(again) - imread(first)).mean() < 1e-3


# ----- MuJoCo simulations --------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def mujoco_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``rtgait simulate`` in MuJoCo: one step of 0.08 m with short ends, 5 N s pushed at 1 s, with its figure."""
    pytest.importorskip("mujoco")
    pytest.importorskip("pinocchio")
    pytest.importorskip("pyarrow")
    folder = tmp_path_factory.mktemp("mujoco")
    scenario = folder / "short.toml"
    scenario.write_text(scenario_text(name="short", connection="quasi-real-time", single_support=0.7,
                                      double_support=0.1, dt=0.005, steps=1, step_length=0.08, short_ends=True),
                        encoding="utf-8")  # fmt: skip
    out = folder / "short-sim"
    assert _quiet_main(["simulate", str(scenario), "--push", "1.0,0.1,50,0", "--out", str(out)]) == 0
    return out


def test_plot_remakes_a_mujoco_runs_zmp_sim(
    mujoco_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    summary_before = (mujoco_run / "summary.json").read_bytes()
    assert json.loads(summary_before)["files"] == ["sim.csv", "sim.parquet", "summary.json", "zmp_sim.png"]
    out = tmp_path / "again"
    assert main(["plot", str(mujoco_run), "--out", str(out)]) == 0
    assert [p.name for p in out.iterdir()] == ["zmp_sim.png"]
    again, first = out / "zmp_sim.png", mujoco_run / "zmp_sim.png"
    assert _png_size(again) == _png_size(first)
    assert np.abs(imread(again) - imread(first)).mean() < 1e-3  # the same numbers through the same code
    captured = capsys.readouterr()
    assert "zmp_sim.png" in captured.out and "MuJoCo simulation" in captured.out and not captured.err
    assert (mujoco_run / "summary.json").read_bytes() == summary_before
    assert main(["plot", str(mujoco_run), "--out", str(out), "--format", "pdf", "--quiet"]) == 0
    assert (out / "zmp_sim.pdf").read_bytes().startswith(b"%PDF")


def test_plot_without_sim_parquet_draws_zmp_sim_from_sim_csv_and_says_so(
    mujoco_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "csv-only"
    folder.mkdir()
    for name in ("sim.csv", "summary.json"):
        (folder / name).write_bytes((mujoco_run / name).read_bytes())
    assert main(["plot", str(folder), "--quiet", "--format", "svg"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("rtgait: warning:") and "sim.csv" in err[0] and "sole" in err[0], err
    root = ElementTree.parse(folder / "zmp_sim.svg").getroot()
    assert root.tag == "{http://www.w3.org/2000/svg}svg"


# ----- folders it refuses --------------------------------------------------------------------------------------


def _mujoco_run(folder: Path) -> None:
    """The files of a MuJoCo simulation as an old rtgait wrote them (header and a row, too few summary keys)."""
    header = ("t,zmp_x,zmp_y,zmp_planned_x,zmp_planned_y,base_x,base_y,base_z,base_qx,base_qy,base_qz,base_qw,"
              "cog_x,cog_y,cog_z,left_contact,right_contact")  # fmt: skip
    (folder / "sim.csv").write_text(header + "\n" + ",".join(["0"] * 17) + "\n", encoding="utf-8")
    summary = {"scenario": "fig8", "robot": "talos", "fell": False, "walk_start": 1.5, "files": ["sim.csv"]}
    (folder / "summary.json").write_text(json.dumps(summary), encoding="utf-8")


def _old_plan_run(folder: Path, plan_run: Path) -> None:
    """A plan run whose summary predates the keys the figures need."""
    summary = json.loads((plan_run / "summary.json").read_text(encoding="utf-8"))
    del summary["free_segments"]
    (folder / "summary.json").write_text(json.dumps(summary), encoding="utf-8")
    (folder / "trajectory.csv").write_bytes((plan_run / "trajectory.csv").read_bytes())


BAD_FOLDERS = {
    "missing folder": (None, "does not exist"),
    "empty folder": (lambda f, _: None, "summary.json is missing"),
    "no csv": (lambda f, p: (f / "summary.json").write_bytes((p / "summary.json").read_bytes()), "trajectory.csv"),
    "bad json": (lambda f, _: (f / "summary.json").write_text("{", encoding="utf-8"), "cannot read"),
    "old MuJoCo run": (lambda f, _: _mujoco_run(f), "MuJoCo simulation"),
    "broken sim.parquet": (lambda f, _: (_mujoco_run(f), (f / "sim.parquet").write_bytes(b"PAR1 no")), "sim.parquet"),
    "old summary": (_old_plan_run, "free_segments"),
    "truncated csv": (lambda f, p: (_old_plan_run(f, p), (f / "summary.json").write_bytes(
        (p / "summary.json").read_bytes()), (f / "trajectory.csv").write_text("t,cog_x\n0,0\n")), "no column"),
}  # fmt: skip


@pytest.mark.parametrize("case", list(BAD_FOLDERS))
def test_a_folder_without_a_drawable_run_is_one_error_line_and_exit_2(
    case: str, plan_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    make, expected = BAD_FOLDERS[case]
    folder = tmp_path / "run"
    if make is not None:
        folder.mkdir()
        make(folder, plan_run)
    before = sorted(p.name for p in folder.iterdir()) if folder.exists() else None
    assert main(["plot", str(folder)]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and err.startswith("rtgait: error: ") and expected in err, err
    assert (sorted(p.name for p in folder.iterdir()) if folder.exists() else None) == before  # nothing written


def test_plot_usage_errors(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["plot"]) == 2
    assert main(["plot", "somewhere", "--format", "bmp"]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 2 and "DIR" in lines[0] and "invalid choice: 'bmp'" in lines[1]
