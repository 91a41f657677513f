"""``rtgait simulate``: the closed loop in MuJoCo as a user runs it, and its bad inputs."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")

from rtgait.cli import main


def test_simulate_writes_csv_summary_and_figure(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], write_scenario
) -> None:
    # Two 8 cm steps and the closing one at fig8's timing, with short start and end phases.
    scenario = write_scenario(
        name="short", connection="quasi-real-time", single_support=0.7, double_support=0.1, dt=0.005,
        steps=2, step_length=0.08, short_ends=True,
    )  # fmt: skip
    out = tmp_path / "sim"
    assert main(["simulate", str(scenario), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "walked 3 of 3 steps without falling" in printed
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    keys = ("fell", "fall_time", "steps_completed", "distance_walked", "zmp_tracking_error_rms", "real_time_factor")
    assert set(keys) <= set(summary)
    assert summary["fell"] is False and summary["scenario"] == "short"
    assert summary["distance_walked"] == pytest.approx(0.16, abs=0.03)  # two 8 cm steps, then the feet close
    with open(out / "sim.csv", encoding="utf-8") as stream:
        header = next(csv.reader(stream))
    assert header[:5] == ["t", "zmp_x", "zmp_y", "zmp_planned_x", "zmp_planned_y"]
    assert (out / "zmp_sim.png").stat().st_size > 10_000


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        (["--velocity", "0.1,nan,0"], "--velocity"),
        (["--velocity", "0.1,0"], "--velocity"),
        (["--push", "1.0,0.1,50"], "--push"),
        (["--robot", "atlas"], "talos"),
    ],
)
def test_bad_simulate_input_exits_2_with_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: list[str], words: str
) -> None:
    out = tmp_path / "never"
    assert main(["simulate", "fig8", "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert err.startswith("rtgait: error:") and len(err.strip().splitlines()) == 1 and words in err
    assert not out.exists()


def test_unknown_scenario(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["simulate", "fig99", "--out", str(tmp_path / "x")]) == 2
    assert "fig4" in capsys.readouterr().err
