"""``rtgait simulate``: the closed loop in MuJoCo as a user runs it, and its bad inputs."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")

from rtgait.cli.main import main
from rtgait.viz.sim_figure import read_zmp_sim_run


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
    assert "the controller on the state estimated from the sensors (noise x1, latency 0 period(s), seed 0)" in printed
    assert "\nestimate    vs the truth: DCM " in printed
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    keys = ("fell", "fall_time", "steps_completed", "distance_walked", "zmp_tracking_error_rms", "real_time_factor")
    assert set(keys) <= set(summary)
    assert summary["fell"] is False and summary["scenario"] == "short"
    assert summary["distance_walked"] == pytest.approx(0.16, abs=0.03)  # two 8 cm steps, then the feet close
    # By default on the state estimated from the simulated sensors, at the description's noise: its errors reported.
    assert summary["state"] == "estimated" and summary["sensors"] == {"noise": 1.0, "latency": 0, "seed": 0}
    assert 0.0 < summary["estimation"]["com_relative_rms"] < 0.005 and summary["estimation"]["landings"] >= 3
    assert "model_error" not in summary
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


# ----- the same checks as `plan`, before any physics ------------------------------------------------------------


@pytest.fixture
def no_physics(monkeypatch: pytest.MonkeyPatch) -> None:
    """Fail the test if a closed loop starts: the input must be refused before."""
    import rtgait.io.sim_run as run
    import rtgait.sim.guided as guided

    def simulated(*args: object, **kwargs: object) -> None:
        raise AssertionError("the simulation started before the input was refused")

    monkeypatch.setattr(run, "run_sim_loop", simulated)
    monkeypatch.setattr(guided, "run_sim_loop", simulated)


def tall_talos(folder: Path) -> Path:
    """Talos's description with a COG 1.2 m high: above anything its legs reach."""
    text = (Path(__file__).parents[2] / "rtgait" / "robots" / "talos.toml").read_text(encoding="utf-8")
    assert "cog_height = 0.84" in text
    path = folder / "tall.toml"
    path.write_text(text.replace("cog_height = 0.84", "cog_height = 1.2"), encoding="utf-8")
    return path


@pytest.mark.parametrize("scenario", ["fig8", "guided"])
@pytest.mark.usefixtures("no_physics")
def test_a_robot_that_cannot_reach_its_cog_height_is_refused_as_by_plan(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], scenario: str
) -> None:
    robot = str(tall_talos(tmp_path))
    out = tmp_path / "never"
    assert main(["plan", scenario, "--robot", robot, "--no-figures", "--out", str(out)]) == 2
    refused_by_plan = capsys.readouterr().err
    assert main(["simulate", scenario, "--robot", robot, "--no-figures", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err == refused_by_plan and "out of reach for talos: COG error" in err and len(err.splitlines()) == 1
    assert not out.exists()


@pytest.mark.usefixtures("no_physics")
def test_a_step_the_robot_cannot_reach_is_refused_before_simulating(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], write_scenario
) -> None:
    scenario = write_scenario(name="giant", connection="quasi-real-time", step_length=0.9)
    out = tmp_path / "never"
    assert main(["simulate", str(scenario), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "step 1 at t=" in err and "out of reach" in err and len(err.splitlines()) == 1
    assert not out.exists()


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        (["--push", "1,0.2,50,0", "--push", "1.1,0.1,-50,0"], "--push 1,0.2,50,0 and --push 1.1,0.1,-50,0 overlap"),
        (["--push", "20,0.1,50,0"], "--push 20,0.1,50,0 starts after the run has ended (at 13.20 s on the walk's"),
    ],
)
def test_pushes_that_would_silently_not_act_are_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], extra: list[str], words: str
) -> None:
    from rtgait.cli import simulate as simulate_command

    monkeypatch.setattr(simulate_command, "load_robot", lambda name: pytest.fail("the robot was loaded"))
    assert main(["simulate", "fig8", "--out", str(tmp_path / "never"), *extra]) == 2
    err = capsys.readouterr().err
    assert err.startswith("rtgait: error:") and words in err and len(err.splitlines()) == 1


def test_a_run_longer_than_the_tick_limit_is_refused_before_anything_loads(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], write_scenario
) -> None:
    from rtgait.cli import simulate as simulate_command

    monkeypatch.setattr(simulate_command, "load_robot", lambda name: pytest.fail("the robot was loaded"))
    # 1000 steps of 1 s: planned every 10 ms, 100 thousand samples; simulated every 1 ms, too many. The run lasts
    # the walk (1004.8 s), the 1.5 s start transition and 0.5 s after.
    scenario = write_scenario(name="long", steps=1000)
    assert main(["simulate", str(scenario), "--out", str(tmp_path / "never")]) == 2
    err = capsys.readouterr().err
    assert "1006.8 s" in err and "physics step dt 0.001 s" in err and "1006801 ticks, at most 1000000" in err, err
    guided = scenario.read_text(encoding="utf-8").replace("real-time", "quasi-real-time")
    guided += "[guide]\nspeed = 0.001\n"  # the person walks 3.1 m at 1 mm/s: almost an hour
    scenario.write_text(guided, encoding="utf-8")
    assert main(["simulate", str(scenario), "--out", str(tmp_path / "never")]) == 2
    assert "ticks, at most 1000000" in capsys.readouterr().err


def test_an_out_that_is_a_file_is_refused_before_simulating(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from rtgait.cli import simulate as simulate_command

    monkeypatch.setattr(simulate_command, "load_robot", lambda name: pytest.fail("the robot was loaded"))
    out = tmp_path / "o"
    out.write_text("a file", encoding="utf-8")
    assert main(["simulate", "fig8", "--out", str(out)]) == 1
    assert capsys.readouterr().err == f"rtgait: error: cannot write outputs to {out}: it exists and is not a folder\n"


# ----- nothing outside --out, MuJoCo's warnings, negative commands ----------------------------------------------


def test_mujoco_warnings_are_collected_instead_of_written_to_the_working_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import mujoco
    import numpy as np

    from rtgait.io.sim_run import mujoco_messages

    monkeypatch.chdir(tmp_path)
    model = mujoco.MjModel.from_xml_string("<mujoco><worldbody><body><freejoint/><geom size='0.1'/></body>"
                                           "</worldbody></mujoco>")  # fmt: skip
    data = mujoco.MjData(model)
    data.qpos[0] = np.nan  # MuJoCo warns of a bad position, then resets the state
    previous = mujoco.get_mju_user_warning()
    with mujoco_messages() as messages:
        assert mujoco.get_mju_user_warning() is not None
        mujoco.mj_step(model, data)
    assert mujoco.get_mju_user_warning() is previous
    assert len(messages) == 1 and "QPOS" in messages[0]
    assert list(tmp_path.iterdir()) == []  # no MUJOCO_LOG.TXT


def test_simulate_writes_nothing_outside_out_and_reports_mujocos_warnings(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], write_scenario
) -> None:
    scenario = write_scenario(name="short", connection="quasi-real-time", single_support=0.7, double_support=0.1,
                              dt=0.005, steps=1, step_length=0.08, short_ends=True)  # fmt: skip
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    # A 10^12 N shove makes the physics blow up at once: MuJoCo warns (and the robot falls), in a tenth of a second.
    # Such a push is refused as beyond physical sense (test_bad_input_is_one_line_and_no_output): not here, where
    # it is the way to make MuJoCo warn.
    import rtgait.core.push

    monkeypatch.setattr(rtgait.core.push, "PUSH_SPEED_LIMIT", float("inf"))
    args = ["simulate", str(scenario), "--out", "out", "--push", "0.1,0.01,1e12,0", "--no-figures"]
    assert main(args) == 0
    assert "warnings    MuJoCo: Nan, Inf or huge value in QACC" in capsys.readouterr().out
    assert [p.name for p in work.iterdir()] == ["out"]
    assert sorted(p.name for p in (work / "out").iterdir()) == ["sim.csv", "sim.parquet", "summary.json"]
    summary = json.loads((work / "out" / "summary.json").read_text(encoding="utf-8"))
    assert summary["fell"] is True and any("unstable" in text for text in summary["mujoco_warnings"])


def test_a_negative_velocity_command_walks_backward(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], write_scenario
) -> None:
    scenario = write_scenario(name="back", connection="quasi-real-time", single_support=0.7, double_support=0.1,
                              dt=0.005, steps=2, step_length=0.08, short_ends=True)  # fmt: skip
    out = tmp_path / "sim"
    assert main(["simulate", str(scenario), "--velocity", "-0.1,0,0", "--out", str(out), "--no-figures"]) == 0
    printed = capsys.readouterr().out
    assert "walked 3 of 3 steps without falling" in printed
    assert "the controller on the state estimated from the sensors (noise x1, latency 0 period(s), seed 0)" in printed
    assert "\nestimate    vs the truth: DCM " in printed
    # It says it is a velocity walk, with its command: in the printed summary, and in the title the log keeps for
    # the figure and the replay (rtgait plot draws the figure from it).
    title = "velocity walk 0.1 m/s backward (back's timing, quasi-real-time)"
    assert printed.startswith(f"scenario    {title}\n")
    assert read_zmp_sim_run(out).title == title
    with open(out / "sim.csv", encoding="utf-8") as stream:
        rows = list(csv.DictReader(stream))
    # 0.1 m/s over 0.8 s steps: two 8 cm steps backward, then the feet close.
    assert float(rows[-1]["base_x"]) - float(rows[0]["base_x"]) == pytest.approx(-0.16, abs=0.04)
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["mujoco_warnings"] == []
    assert summary["velocity"] == [{"t": 0.0, "vx": -0.1, "vy": 0.0, "wz": 0.0}]


# ----- the controller levels and the periods ----------------------------------------------------------------------


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        (["--controller", "stiff"], "invalid choice: 'stiff'"),
        (["--stabilizer"], "--stabilizer was removed"),
        (["--physics-dt", "0.002", "--control-dt", "0.001"], "longer than the control period"),
        (["--physics-dt", "0.002"], "longer than the control period"),  # Talos's own period is 1 ms
        (["--physics-dt", "0.0007", "--control-dt", "0.002"], "must divide the control period"),
        (["--control-dt", "nan"], "--control-dt must be within"),
        (["--push", "1,0.1,nan,0"], "--push needs 4 finite"),
        (["--push", "1,0.1,1e9,0"], "exceeds"),  # 10^8 N s: a unit error, not a push
        (["--mass", "50"], "--mass is for --model lipm"),
        (["--state", "guessed"], "invalid choice: 'guessed'"),
        (["--sensor-noise", "-1"], "--sensor-noise must be a finite factor >= 0"),
        (["--sensor-noise", "inf"], "--sensor-noise must be a finite factor >= 0"),
        (["--sensor-seed", "-1"], "--sensor-seed must be an integer >= 0"),
        (["--latency", "-1"], "--latency must be a whole number of control periods in [0, 1000]"),
        (["--latency", "1001"], "--latency must be a whole number of control periods in [0, 1000]"),
        (["--latency", "1.5"], "invalid int value"),
        (["--model-error", "-2"], "--model-error must be an integer seed >= 0"),
        (["--model-error", "one"], "invalid int value"),
        (["--model", "lipm", "--state", "truth"], "--state is for --model mujoco"),
        (["--model", "lipm", "--sensor-noise", "0"], "--sensor-noise is for --model mujoco"),
        (["--model", "lipm", "--motor-model"], "--motor-model (the drives' motors) is for --model mujoco"),
    ],
)
@pytest.mark.usefixtures("no_physics")
def test_bad_controller_periods_and_pushes_are_one_line_and_no_output(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: list[str], words: str
) -> None:
    out = tmp_path / "never"
    assert main(["simulate", "fig8", "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert err.startswith("rtgait: error:") and len(err.strip().splitlines()) == 1 and words in err, err
    assert not out.exists()


def test_zmp_sim_in_any_format_on_the_walks_clock_with_its_error_measures(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], write_scenario
) -> None:
    from xml.etree import ElementTree

    scenario = write_scenario(name="short", connection="quasi-real-time", single_support=0.7, double_support=0.1,
                              dt=0.005, steps=1, step_length=0.08, short_ends=True)  # fmt: skip
    out = tmp_path / "svg"
    argv = ["simulate", str(scenario), "--out", str(out), "--format", "svg", "--controller", "stabilized"]
    assert main([*argv, "--push", "1.0,0.1,50,0"]) == 0
    printed = capsys.readouterr().out
    assert "stabilized" in printed and "from the robot description" in printed and "5.0 N s at 1.00 s" in printed
    assert printed.startswith("scenario    short (quasi-real-time)\nrobot       talos in MuJoCo, stabilized")
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["files"] == ["sim.csv", "sim.parquet", "summary.json", "zmp_sim.svg"]
    assert ElementTree.parse(out / "zmp_sim.svg").getroot().tag == "{http://www.w3.org/2000/svg}svg"
    # The walk's clock: the start transition at negative times, the push where --push said, on that clock.
    assert summary["run_start"] == pytest.approx(-1.5) and summary["pushes"][0]["start"] == 1.0
    assert summary["pushes"][0]["impulse"] == pytest.approx([5.0, 0.0, 0.0])
    assert summary["controller"] == "stabilized" and summary["walk"]["step_width"] == pytest.approx(0.17, abs=1e-3)
    for key in ("missed_landings", "step_adjustments", "foot_slip_max", "fall_cause", "steps_planned"):
        assert key in summary
    # Each ZMP error measure printed as its median, 95th percentile and RMS, as summary.json has them (mm).
    motion = "vs the multibody ZMP of the commanded motion"
    for label, name in (("vs the plan", "vs_plan"), (motion, "vs_commanded_motion")):
        stats = summary["zmp_error"][name]
        mm = {key: f"{stats[key] * 1e3:.1f} mm" for key in ("median", "p95", "rms")}
        assert f"{label}: median {mm['median']}, 95th percentile {mm['p95']}, RMS {mm['rms']}" in printed
        assert stats["median"] <= stats["p95"] <= stats["max"] and stats["ticks"] > 100
    with open(out / "sim.csv", encoding="utf-8") as stream:
        rows = list(csv.DictReader(stream))
    assert float(rows[0]["t"]) == pytest.approx(-1.5) and min(abs(float(r["t"])) for r in rows) < 1e-9


class _LoopStartedError(Exception):
    """The closed loop was about to start: the test has what it came for."""


def test_the_control_tables_reach_the_walking_controller(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, write_scenario
) -> None:
    """robot < scenario < --control, key by key, into the controller the MuJoCo loop runs."""
    import rtgait.io.sim_run as run

    started = []

    def start(sim: object, controller: object, *args: object, **kwargs: object) -> None:
        started.append(controller)
        raise _LoopStartedError

    monkeypatch.setattr(run, "run_sim_loop", start)
    talos = (Path(__file__).parents[2] / "rtgait" / "robots" / "talos.toml").read_text(encoding="utf-8")
    robot = tmp_path / "robot.toml"
    talos = talos.replace("\n[control]\n", "\n[control]\nlate_grace = 0.02\n", 1)  # into its own table
    robot.write_text(talos + "\n[control.dcm]\nk_p = 1.0\nk_i = 0.5\n", "utf-8")
    scenario = write_scenario(name="tuned", connection="quasi-real-time", single_support=0.7, double_support=0.1,
                              steps=2, step_length=0.08, short_ends=True)  # fmt: skip
    scenario.write_text(scenario.read_text("utf-8") + "[control.dcm]\nk_p = 2.5\n[control.foot]\nmax_height = 0.02\n")
    control = tmp_path / "gains.toml"
    control.write_text("[control.dcm]\nk_p = 4.0\n", "utf-8")
    args = ["simulate", str(scenario), "--robot", str(robot), "--no-figures", "--out", str(tmp_path / "out")]
    for extra, k_p in (([], 2.5), (["--control", str(control)], 4.0)):
        with pytest.raises(_LoopStartedError):
            main([*args, *extra])
        controller = started.pop()
        assert controller.feedback.gains.k_p == k_p and controller.feedback.gains.k_i == 0.5
        assert controller.foot.gains.max_height == 0.02 and controller.options.late_grace == 0.02
    # The library's simulate() applies the robot's and the scenario's tables too (a sweep's worker calls it).
    from rtgait.scenario.loading import load_scenario

    with pytest.raises(_LoopStartedError):
        run.simulate(load_scenario(scenario), str(robot))
    assert started.pop().feedback.gains.k_p == 2.5


@pytest.mark.parametrize(
    ("extra", "state", "sensors", "seed"),
    [
        (["--state", "truth"], "truth", {"noise": 1.0, "latency": 0, "seed": 0}, None),
        (["--sensor-noise", "2", "--sensor-seed", "4", "--latency", "1", "--model-error", "3"], "estimated",
         {"noise": 2.0, "latency": 1, "seed": 4}, 3),
    ],
)  # fmt: skip
def test_the_state_sensors_and_model_error_reach_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], write_scenario, extra, state, sensors, seed
) -> None:
    scenario = write_scenario(name="one", connection="quasi-real-time", single_support=0.7, double_support=0.1,
                              dt=0.005, steps=1, step_length=0.05, short_ends=True)  # fmt: skip
    out = tmp_path / "sim"
    assert main(["simulate", str(scenario), "--out", str(out), "--no-figures", "--quiet", *extra]) == 0
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["fell"] is False
    assert summary["state"] == state and summary["sensors"] == sensors
    assert (summary["estimation"] is None) == (state == "truth")
    assert (summary.get("model_error") or {}).get("seed") == seed
    assert (out / "model_error.json").exists() == (seed is not None)
