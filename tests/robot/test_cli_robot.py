"""``rtgait plan SCENARIO --robot ...``: joint trajectories, the multibody check, the Appendix A compensation and
clean failures, as a user runs them."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

from rtgait.cli.main import main  # noqa: E402
from rtgait.robot.data import data_file  # noqa: E402

TALOS_URDF = "talos_data/robots/talos_reduced.urdf"


def run(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main(args)
    captured = capsys.readouterr()
    return code, captured.out, captured.err


@pytest.fixture(scope="module")
def fig11_compensated(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The paper's Fig. 11 case on Talos with compensation (run once for the module)."""
    out = tmp_path_factory.mktemp("fig11") / "out"
    args = ["plan", "fig11", "--robot", "talos", "--compensate-angular-momentum", "--out", str(out), "--quiet"]
    assert main(args) == 0
    return out


def test_joints_csv_has_the_base_and_every_urdf_joint(fig11_compensated: Path) -> None:
    with open(fig11_compensated / "joints.csv", encoding="utf-8") as stream:
        rows = list(csv.reader(stream))
    header, data = rows[0], np.array(rows[1:], dtype=float)
    urdf_model = pin.buildModelFromUrdf(str(data_file(TALOS_URDF)))  # independent: straight from the URDF
    joints = [name for name in urdf_model.names[1:]]
    assert header == ["t", "base_x", "base_y", "base_z", "base_qx", "base_qy", "base_qz", "base_qw", *joints]
    with open(fig11_compensated / "trajectory.csv", encoding="utf-8") as stream:
        ticks = sum(1 for _ in stream) - 1
    assert len(data) == ticks
    assert np.allclose(np.linalg.norm(data[:, 4:8], axis=1), 1.0)  # the base orientation is a unit quaternion
    lower = urdf_model.lowerPositionLimit
    upper = urdf_model.upperPositionLimit
    assert np.all(data[:, 8:] >= lower - 1e-9) and np.all(data[:, 8:] <= upper + 1e-9)


def test_joint_trajectory_puts_the_soles_where_the_plan_says(fig11_compensated: Path) -> None:
    """Forward kinematics of the written joints.csv (full URDF model) against the written trajectory.csv."""
    model = pin.buildModelFromUrdf(str(data_file(TALOS_URDF)), pin.JointModelFreeFlyer())
    data = model.createData()
    joints = np.loadtxt(fig11_compensated / "joints.csv", delimiter=",", skiprows=1)
    with open(fig11_compensated / "trajectory.csv", encoding="utf-8") as stream:
        reader = csv.DictReader(stream)
        planned = [row for row in reader]
    left = model.getFrameId("left_sole_link")
    for k in range(0, len(joints), 97):
        pin.framesForwardKinematics(model, data, joints[k, 1:])
        position = data.oMf[left].translation
        expected = [float(planned[k][name]) for name in ("lfoot_x", "lfoot_y", "lfoot_z")]
        assert np.allclose(position, expected, atol=1e-4), k


def test_summary_reports_ik_and_multibody_errors_and_the_compensation_helps(fig11_compensated: Path) -> None:
    summary = json.loads((fig11_compensated / "summary.json").read_text(encoding="utf-8"))
    assert summary["robot"] == "talos"
    assert summary["ik_cog_error_max"] < 1e-4 and summary["ik_foot_error_max"] < 1e-4
    assert set(summary["multibody_zmp_error_max"]) == {"x", "y"}
    compensation = summary["angular_momentum_compensation"]
    assert compensation["order"] == 3
    before, after = compensation["before"], compensation["after"]
    assert after["multibody_zmp_error_max"] == summary["multibody_zmp_error_max"]
    # The paper's Fig. 11 result: the angular momentum's ZMP error shrinks with the Fourier compensation.
    for axis in "xy":
        assert after["multibody_zmp_error_rms"][axis] < 0.5 * before["multibody_zmp_error_rms"][axis]
    assert (fig11_compensated / "multibody_zmp.png").stat().st_size > 10_000


def test_second_robot_from_its_description(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(["plan", "fig11", "--robot", "g1", "--no-figures", "--dt", "0.01", "--out", str(tmp_path / "g")],
                       capsys)  # fmt: skip
    assert code == 0
    assert "robot       g1" in out
    assert json.loads((tmp_path / "g" / "summary.json").read_text())["robot"] == "g1"


def test_html_replay_defaults_to_talos(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, _, _ = run(["plan", "fig11", "--html", "--no-figures", "--dt", "0.01", "--out", str(tmp_path / "h")], capsys)
    assert code == 0
    page = (tmp_path / "h" / "replay.html").read_text(encoding="utf-8")
    assert "<html" in page.lower() and len(page) > 100_000


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        (["--robot", "atlas"], "talos"),  # unknown robot: the message lists the known ones
        (["--robot", "talos", "--compensate-angular-momentum", "-1"], "ORDER"),
    ],
)
def test_bad_robot_input_exits_2_with_one_line_and_no_output(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: list[str], words: str
) -> None:
    out = tmp_path / "never"
    code, _, err = run(["plan", "fig11", "--out", str(out), *extra], capsys)
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and err.startswith("rtgait: error:") and words in err
    assert not out.exists()


def test_description_naming_a_missing_frame(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text = (Path(__file__).parents[2] / "rtgait" / "robots" / "talos.toml").read_text(encoding="utf-8")
    text = text.replace('"left_sole_link"', '"left_toe_link"')
    description = tmp_path / "broken.toml"
    description.write_text(text, encoding="utf-8")
    out = tmp_path / "never"
    code, _, err = run(["plan", "fig11", "--robot", str(description), "--out", str(out)], capsys)
    assert code == 2 and "left_toe_link" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_unreachable_step_exits_2_and_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], write_scenario
) -> None:
    scenario = write_scenario(name="giant", connection="quasi-real-time", step_length=0.9)
    out = tmp_path / "never"
    code, _, err = run(["plan", str(scenario), "--robot", "talos", "--out", str(out)], capsys)
    assert code == 2
    assert "out of reach" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()
