"""``rtgait simulate --model lipm``: the closed loop on the point-mass pendulum from the command line."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rtgait.cli.main import main


def _run(tmp_path: Path, *options: str) -> tuple[int, dict]:
    out = tmp_path / "out"
    code = main(["simulate", "fig8", "--model", "lipm", "--out", str(out), "--quiet", *options])
    summary = json.loads((out / "summary.json").read_text()) if (out / "summary.json").exists() else {}
    return code, summary


def test_a_push_the_adaptive_controller_recovers_topples_the_open_loop(tmp_path: Path) -> None:
    push = ("--push", "5.0,0.1,250,0", "--no-figures")  # 25 N s forward at the start of a double support
    code, adaptive = _run(tmp_path / "a", *push)
    assert code == 0 and not adaptive["fell"] and adaptive["ended_at_rest"]
    assert adaptive["controller"] == "adaptive" and adaptive["model"] == "lipm" and adaptive["mass"] == 57.0
    assert adaptive["pushes"][0]["impulse_norm"] == pytest.approx(25.0)
    code, open_loop = _run(tmp_path / "b", *push, "--controller", "open-loop")
    assert code == 0 and open_loop["fell"] and 5.0 < open_loop["fall_time"] < 7.0
    assert open_loop["steps_completed"] < open_loop["steps_planned"]


def test_outputs_and_figure(tmp_path: Path) -> None:
    code, summary = _run(tmp_path, "--controller", "stabilized", "--mass", "40")
    assert code == 0 and summary["mass"] == 40.0
    assert summary["files"] == ["sim.csv", "summary.json", "pendulum.png"]
    header = (tmp_path / "out" / "sim.csv").read_text().splitlines()[0].split(",")
    assert header[0] == "t" and "dcm_x" in header and "zmp_real_x" in header
    assert (tmp_path / "out" / "pendulum.png").stat().st_size > 10_000


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (("--controller", "sometimes"), "invalid choice"),
        (("--mass", "nan"), "--mass must be within"),
        (("--mass", "5000"), "--mass must be within"),
        (("--control-dt", "0.5"), "--control-dt"),
        (("--push", "1,0.1,1e9,0"), "--push"),
        (("--push", "nan,0.1,10,0"), "--push"),
        (("--velocity", "0.1,0,0"), "--velocity"),
        (("--html",), "--html"),
    ],
)
def test_bad_input_is_one_line_and_writes_nothing(tmp_path: Path, capsys, options, message) -> None:
    out = tmp_path / "out"
    code = main(["simulate", "fig8", "--model", "lipm", "--out", str(out), *options])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and message in err
    assert not out.exists()


def test_the_mujoco_model_takes_the_controller_levels_too(tmp_path: Path, capsys) -> None:
    # Accepted for MuJoCo as well (tests/sim/test_sim_cli.py walks them); here the run stops at the unknown robot.
    code = main(["simulate", "fig8", "--controller", "stabilized", "--robot", "atlas", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2 and "--controller" not in err and "atlas" in err
