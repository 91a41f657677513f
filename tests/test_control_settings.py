"""The controller's settings from files: ``[control]`` tables in a robot description, a scenario and ``rtgait
simulate --control FILE``, their precedence, their errors, and that the controller runs with what they say."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from rtgait.cli.control_file import controller_settings, read_control_file
from rtgait.cli.main import main
from rtgait.control.control_table import ControlSettingsError, at_gains, control_options
from rtgait.control.controller import make_controller
from rtgait.control.settings import ControllerOptions, RobotInfo
from rtgait.core.geometry.footsteps import SoleRect, Timing
from rtgait.core.planner.online import PlannerConfig, straight_walk
from rtgait.robot.description import load_robot
from rtgait.scenario.loading import load_scenario
from rtgait.scenario.scenario import ScenarioError

SOLE = SoleRect(front=0.105, back=0.105, inner=0.065, outer=0.065)
CONFIG = PlannerConfig(cog_height=0.84, timing=Timing(0.7, 0.1, start=0.6, end=0.6, settle=0.8), step_width=0.2)
TALOS = Path(__file__).parents[1] / "rtgait" / "robots" / "talos.toml"


def write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path


def test_the_controller_runs_with_the_gains_a_table_sets():
    options = control_options(
        ("scenario probe", (("dcm.k_p", 3.5), ("foot.cop_admittance", 0.004), ("hip_strategy", False))),
    )  # fmt: skip
    controller = make_controller(
        "stabilized", CONFIG, straight_walk(CONFIG, 2, 0.1), SOLE, RobotInfo(90.0, SOLE, 0.84), options=options
    )  # fmt: skip
    assert controller.feedback is not None and controller.feedback.gains.k_p == 3.5
    assert controller.foot is not None and controller.foot.gains.cop_admittance == 0.004
    assert controller.hip is None
    # Every key it does not set keeps the default.
    default = ControllerOptions()
    assert controller.feedback.gains.k_i == default.dcm.k_i and controller.options.late_grace == default.late_grace


def test_no_table_gives_the_defaults_and_foot_false_turns_foot_control_off():
    assert control_options() == ControllerOptions()
    assert control_options(("robot r", ())) == ControllerOptions()
    off = control_options(("robot r", (("foot", False),)))
    assert off.foot is None
    # A later file's foot table turns it on again, with the default gains and its own.
    on = control_options(("robot r", (("foot", False),)), ("scenario s", (("foot.max_tilt", 0.1),)))
    assert on.foot is not None and on.foot.max_tilt == 0.1
    assert on.foot.cop_admittance == ControllerOptions().foot.cop_admittance


def test_a_later_table_wins_key_by_key():
    robot = (("dcm.k_p", 1.0), ("measurement_filter", 0.01), ("foot.cop_admittance", 0.003))
    scenario = (("dcm.k_p", 2.0), ("late_grace", 0.02))
    options = control_options(("robot r", robot), ("scenario s", scenario), ("--control f.toml", (("dcm.k_p", 3),)))
    assert options.dcm.k_p == 3.0 and isinstance(options.dcm.k_p, float)
    assert options.measurement_filter == 0.01 and options.foot.cop_admittance == 0.003 and options.late_grace == 0.02
    assert control_options(("robot r", robot), ("scenario s", scenario)).dcm.k_p == 2.0


@pytest.mark.parametrize(
    ("pairs", "message"),
    [
        ((("kp", 3.0),), "scenario s: unknown key control.kp (allowed in [control]: dcm, foot, "),
        ((("dcm.kp", 3.0),), "scenario s: unknown key control.dcm.kp (allowed in [control.dcm]: k_p, k_i, "),
        ((("dcm.k_p", 50.0),), "scenario s: control.dcm.k_p must be finite and within [0, 20] 1/s, got 50"),
        ((("dcm.k_p", "fast"),), "scenario s: control.dcm.k_p must be a real number in [0, 20] 1/s"),
        ((("foot.cop_admittance", 1.0),), "scenario s: control.foot.cop_admittance must be within [0, 0.1]"),
        ((("foot.max_tilt_rate", True),), "scenario s: control.foot.max_tilt_rate must be within [0, 10]"),
        ((("measurement_filter", -1.0),), "scenario s: control.measurement_filter must be a number within [0, 10] s"),
        ((("measurement_filter", True),), "scenario s: control.measurement_filter must be a number within"),
        ((("max_lean", 0.0),), "scenario s: control.max_lean must be a number within (0, 0.6] rad"),
        ((("replan_dcm_error", 0.0),), "scenario s: control.replan_dcm_error must be a number within [0.0001, 1] m"),
        ((("adapt_timing", 1),), "scenario s: control.adapt_timing must be true or false, got 1"),
        ((("com_reference", "plan"),), "scenario s: control.com_reference must be 'dcm' or 'measured' or 'planned'"),
        ((("dcm", 2.0),), "scenario s: control.dcm must be a table ([control.dcm]), got 2.0"),
        ((("step_adjustment", 1.0),), "scenario s: unknown key control.step_adjustment"),
    ],
)  # fmt: skip
def test_a_bad_key_or_value_is_one_line_naming_it_and_what_is_allowed(pairs, message):
    with pytest.raises(ControlSettingsError) as error:
        control_options(("scenario s", pairs))
    assert str(error.value).startswith(message) and "\n" not in str(error.value)


def test_scenario_and_robot_files_carry_their_control_tables(tmp_path, write_scenario):
    scenario = write_scenario(name="tuned")
    text = scenario.read_text(encoding="utf-8") + "[control]\nlate_grace = 0.02\n[control.dcm]\nk_p = 2.5\n"
    scenario.write_text(text, encoding="utf-8")
    assert load_scenario(scenario).control == (("late_grace", 0.02), ("dcm.k_p", 2.5))
    assert load_scenario("fig8").control == ()
    robot = write(tmp_path, "robot.toml", TALOS.read_text(encoding="utf-8") + "\n[control.foot]\nmax_height = 0.02\n")
    assert load_robot(robot).control == (*load_robot(TALOS).control, ("foot.max_height", 0.02))
    scenario.write_text(text + "[control.foot]\nmax_tilt = [1, 2]\n", encoding="utf-8")
    with pytest.raises(ScenarioError, match=r"^control\.foot\.max_tilt must be a number, true or false, a string"):
        load_scenario(scenario)


def test_precedence_robot_then_scenario_then_the_control_file(tmp_path, write_scenario):
    talos = TALOS.read_text(encoding="utf-8")  # its own [control] table gets one more key
    robot = load_robot(write(tmp_path, "robot.toml", talos.replace(
        "\n[control]\n", "\n[control]\nmeasurement_filter = 0.01\n", 1) + "\n[control.dcm]\nk_p = 1.0\nk_i = 0.5\n"
    ))  # fmt: skip
    own = dict(load_robot(TALOS).control)
    path = write_scenario(name="tuned")
    path.write_text(path.read_text(encoding="utf-8") + "[control.dcm]\nk_p = 2.0\n", encoding="utf-8")
    scenario = load_scenario(path)
    control = write(tmp_path, "gains.toml", "[control.dcm]\nk_p = 3.0\n")

    options, chosen = controller_settings(robot, scenario, None, ())
    assert (options.dcm.k_p, options.dcm.k_i, options.measurement_filter) == (2.0, 0.5, 0.01)
    options, chosen = controller_settings(robot, scenario, str(control), read_control_file(str(control)))
    assert (options.dcm.k_p, options.dcm.k_i, options.measurement_filter) == (3.0, 0.5, 0.01)
    assert chosen == {**own, "measurement_filter": 0.01, "dcm.k_p": 3.0, "dcm.k_i": 0.5}
    options, _ = controller_settings(robot, load_scenario("fig8"), None, ())
    assert options.dcm.k_p == 1.0


def _zmp_command(folder: Path) -> np.ndarray:
    with open(folder / "sim.csv", encoding="utf-8", newline="") as stream:
        rows = list(csv.DictReader(stream))
    return np.array([[float(row["t"]), float(row["zmp_command_x"]), float(row["zmp_command_y"])] for row in rows])


def test_a_control_file_changes_what_the_dcm_law_commands(tmp_path, write_scenario):
    """The pendulum walked with a pushed DCM error: a stiffer k_p from --control commands another ZMP after the push,
    the same one before it (up to the round-off the law multiplies); a file that restates the defaults changes
    nothing."""
    scenario = str(write_scenario(name="short", steps=2, short_ends=True, dt=0.005))
    stiff = write(tmp_path, "stiff.toml", "[control.dcm]\nk_p = 6.0\n")
    same = write(tmp_path, "same.toml", f"[control]\nreplan_dcm_error = 0.025\n[control.dcm]\nk_p = {2.0}\n")
    runs = {}
    for name, extra in (("default", []), ("stiff", ["--control", str(stiff)]), ("same", ["--control", str(same)])):
        out = tmp_path / name
        common = ["--model", "lipm", "--controller", "stabilized", "--push", "1.2,0.1,40,0", "--no-figures"]
        assert main(["simulate", scenario, *common, "--quiet", "--out", str(out), *extra]) == 0
        runs[name] = _zmp_command(out)
    default, stiff_run = runs["default"], runs["stiff"]
    np.testing.assert_array_equal(runs["same"], default)
    before = default[:, 0] < 1.2
    np.testing.assert_allclose(stiff_run[before, 1:], default[before, 1:], rtol=0.0, atol=1e-12)
    assert np.abs(stiff_run[~before, 1:] - default[~before, 1:]).max() > 1e-3  # m


def test_a_bad_control_file_or_table_exits_2_with_one_line(tmp_path, write_scenario, capsys):
    bad = write(tmp_path, "bad.toml", "[control.dcm]\nkp = 3.0\n")
    args = ["simulate", "fig8", "--model", "lipm", "--no-figures", "--out", str(tmp_path / "never")]
    assert main([*args, "--control", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"rtgait: error: --control {bad}: unknown key control.dcm.kp (allowed in [control.dcm]: k_p")
    assert len(err.splitlines()) == 1
    assert main([*args, "--control", str(write(tmp_path, "walk.toml", "[walk]\nsteps = 3\n"))]) == 2
    assert "unknown top-level key walk (allowed here: control)" in capsys.readouterr().err
    path = write_scenario(name="tuned")
    path.write_text(path.read_text(encoding="utf-8") + "[control]\nanchor_blend = 20.0\n", encoding="utf-8")
    args[1] = str(path)
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err == "rtgait: error: scenario tuned: control.anchor_blend must be a number within [0, 10] s, got 20.0\n"
    assert not (tmp_path / "never").exists()


@pytest.mark.parametrize(
    ("name", "levelled"), [("fig8", True), ("stepping-stones", False), ("slope-up", False), ("unseen-step", False)]
)
def test_sole_levelling_is_off_by_default_off_the_flat_floor(name: str, levelled: bool, tmp_path: Path) -> None:
    # The levelling reads a standing sole's tilt as its leg's calibration error: only a level floor under the whole
    # sole makes that true. A [control] table still decides over the default.
    scenario = load_scenario(name)
    options, _ = controller_settings(load_robot("g1"), scenario, None, ())
    assert (options.sole_level > 0.0) is levelled
    control = tmp_path / "level.toml"
    control.write_text("[control]\nsole_level = 0.5\n", encoding="utf-8")
    options, _ = controller_settings(load_robot("g1"), scenario, str(control), read_control_file(str(control)))
    assert options.sole_level == 0.5


def test_a_robot_s_settings_per_gain_set_apply_at_those_gains_only(tmp_path):
    # The table's own keys, then those of the drives' gain set over them; the other set's left out.
    pairs = (("measurement_filter", 0.01), ("gains.stiff.measurement_filter", 0.02), ("gains.robot.dcm.k_p", 4.0))
    common = ("robot probe", [("measurement_filter", 0.01)])
    stiff = ("robot probe [control.gains.stiff]", [("measurement_filter", 0.02)])
    assert at_gains(pairs, "stiff", "robot probe") == [common, stiff]
    robot = ("robot probe [control.gains.robot]", [("dcm.k_p", 4.0)])
    assert at_gains(pairs, "robot", "robot probe") == [common, robot]
    options = control_options(*at_gains(pairs, "robot", "robot probe"))
    assert (options.measurement_filter, options.dcm.k_p) == (0.01, 4.0)
    with pytest.raises(ControlSettingsError, match=r"^robot probe: control\.gains\.soft\.dcm\.k_p is not a setting of"):
        at_gains((("gains.soft.dcm.k_p", 1.0),), "stiff", "robot probe")
    # G1's: its late feet leave rest at the stiff servos (a step of the reference takes them to their torque limits),
    # at once at its own gains; the summary's settings say which.
    g1, fig8 = load_robot("g1"), load_scenario("fig8")
    stiff, chosen = controller_settings(g1, fig8, None, (), "stiff")
    assert stiff.late_descent_acceleration == 9.81 and chosen == {"late_descent_acceleration": 9.81}
    robot, chosen = controller_settings(g1, fig8, None, (), "robot")
    assert robot.late_descent_acceleration == ControllerOptions().late_descent_acceleration == 0.0 and chosen == {}
    # A description's table is checked where it applies: a bad value in the other gain set's is refused there.
    text = (Path(__file__).parents[1] / "rtgait" / "robots" / "g1.toml").read_text(encoding="utf-8")
    bad = load_robot(write(tmp_path, "g1.toml", text + "\n[control.gains.robot]\nlate_descent_speed = -1.0\n"))
    assert controller_settings(bad, fig8, None, (), "stiff")[0].late_descent_speed == 0.3
    message = r"^robot g1 \[control\.gains\.robot\]: control\.late_descent_speed must be a number within"
    with pytest.raises(ControlSettingsError, match=message):
        controller_settings(bad, fig8, None, (), "robot")
