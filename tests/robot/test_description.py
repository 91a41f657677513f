"""Robot description files: the built-ins, the documented example, and every kind of bad input."""

from __future__ import annotations

import math
import re
import shutil
import xml.etree.ElementTree as ElementTree
from importlib import resources
from pathlib import Path

import pytest

pytest.importorskip("pinocchio")

from rtgait.robot.data import data_file
from rtgait.robot.description import RobotError, builtin_robots, load_robot
from rtgait.robot.model import RobotModel

TALOS_TEXT = resources.files("rtgait").joinpath("robots", "talos.toml").read_text(encoding="utf-8")
DOCS = Path(__file__).resolve().parents[2] / "docs" / "robots.md"


def write(tmp_path: Path, text: str, name: str = "robot.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def edited(old: str, new: str) -> str:
    """The Talos description with one piece of text replaced (which must be there)."""
    assert old in TALOS_TEXT, old
    return TALOS_TEXT.replace(old, new, 1)


def test_builtins_are_listed_and_load():
    robots = builtin_robots()
    assert set(robots) >= {"talos", "g1"}
    assert all(robots.values()), "every built-in robot has a one-line description"
    talos = load_robot()  # the default robot
    assert talos.name == "talos"
    assert talos.urdf == data_file("talos_data/robots/talos_reduced.urdf")
    assert talos.left_sole_frame == "left_sole_link" and talos.right_sole_frame == "right_sole_link"
    assert len(talos.moving_joints) == 14
    assert talos.sole_offset == (0.0, 0.0, 0.0)
    g1 = load_robot("g1")
    assert g1.sole_offset == (0.0, 0.0, -0.035)
    assert g1.package_dirs and all(folder.is_dir() for folder in g1.package_dirs)


def test_talos_posture_is_the_srdf_half_sitting():
    # Independent truth: the half_sitting group state of the SRDF shipped with the URDF.
    root = ElementTree.parse(data_file("talos_data/srdf/talos.srdf")).getroot()
    state = next(s for s in root.iter("group_state") if s.get("name") == "half_sitting")
    srdf = {j.get("name"): float(j.get("value")) for j in state.iter("joint") if j.get("name") != "root_joint"}
    talos = load_robot("talos")
    for joint, angle in srdf.items():
        assert talos.posture_angle(joint) == pytest.approx(angle, abs=1e-12), joint


def test_file_with_relative_paths_resolves_against_its_folder(tmp_path):
    (tmp_path / "urdf").mkdir()
    shutil.copy(data_file("talos_data/robots/talos_reduced.urdf"), tmp_path / "urdf" / "mine.urdf")
    (tmp_path / "meshes").mkdir()
    text = edited(
        'urdf = "example-robot-data:talos_data/robots/talos_reduced.urdf"',
        'urdf = "urdf/mine.urdf"\npackage_dirs = ["meshes"]',
    )
    text = text.replace("[posture]", "[gains]\nkp = 800.0\nkd = { leg_left_4_joint = 8.0 }\n\n[posture]")
    description = load_robot(write(tmp_path, text))
    assert description.urdf == (tmp_path / "urdf" / "mine.urdf").resolve()
    assert description.package_dirs == (tmp_path / "meshes",)
    assert description.gains("leg_left_4_joint") == (800.0, 8.0)
    assert description.gains("leg_left_3_joint") is None  # no kd for it
    robot = RobotModel.load(description)
    assert robot.mass == pytest.approx(90.27, abs=0.01)


def test_documented_second_robot_example_works(tmp_path):
    # docs/robots.md walks through a description of a second robot; the TOML shown there must work as is.
    blocks = re.findall(r"```toml\n(.*?)```", DOCS.read_text(encoding="utf-8"), flags=re.S)
    assert blocks, "docs/robots.md shows a TOML example"
    description = load_robot(write(tmp_path, blocks[0], "example.toml"))
    robot = RobotModel.load(description)
    assert robot.step_width > 0.1
    assert 0.0 < description.cog_height < robot.cog_half_sitting[2]


BAD = [
    # (what, TOML text or None for a special case, words the one-line message must contain)
    ("invalid TOML", "name = ", "invalid TOML"),
    ("unknown top-level key", 'colour = "red"\n' + TALOS_TEXT, "unknown top-level key colour"),
    ("unknown nested key", edited("cog_height = 0.84", "cog_heigth = 0.84"), "walking.cog_heigth"),
    ("missing key", edited('torso_frame = "torso_2_link"', ""), "missing required key walking.torso_frame"),
    ("bad name", edited('name = "talos"', 'name = "my robot"'), "name must be"),
    ("missing URDF file", edited("example-robot-data:talos_data/robots/talos_reduced.urdf", "no/where.urdf"),
     "model.urdf 'no/where.urdf': no such file"),
    ("missing example-robot-data file", edited("robots/talos_reduced.urdf\"", "robots/talos_nope.urdf\""),
     "example-robot-data has no file robots/talos_data/robots/talos_nope.urdf"),
    ("missing package dir", edited("[feet]", 'package_dirs = ["no_such_folder"]\n\n[feet]'),
     "model.package_dirs: no such folder"),
    ("sole frame not in URDF", edited('left_sole_frame = "left_sole_link"', 'left_sole_frame = "left_foot"'),
     "feet.left_sole_frame: the URDF talos_reduced.urdf has no link or joint named 'left_foot'"),
    ("same frame twice", edited('right_sole_frame = "right_sole_link"', 'right_sole_frame = "left_sole_link"'),
     "must be different frames"),
    ("bad sole offset", edited("[feet.sole]", "sole_offset = [0.0, -0.1]\n\n[feet.sole]"), "feet.sole_offset"),
    ("negative sole side", edited("front = 0.105", "front = -0.105"), "feet.sole.front must be a number >= 0 m"),
    ("missing sole side", edited("outer = 0.065", ""), "missing required key feet.sole.outer"),
    ("non-positive COG height", edited("cog_height = 0.84", "cog_height = 0"), "walking.cog_height must be"),
    ("boolean COG height", edited("cog_height = 0.84", "cog_height = true"), "walking.cog_height must be"),
    ("toe release past the swing", edited("cog_height = 0.84", "cog_height = 0.84\ntoe_release = 1.5"),
     "walking.toe_release must be a share of the swing in (0, 1], got 1.5"),
    ("zero toe release", edited("cog_height = 0.84", "cog_height = 0.84\ntoe_release = 0"),
     "walking.toe_release must be a number > 0"),
    ("negative descent bend", edited("descent_bend = 0.035", "descent_bend = -0.01"),
     "walking.descent_bend must be a number >= 0"),
    ("moving joint not in URDF", edited('"torso_1_joint", "torso_2_joint",', '"torso_1_joint", "torso_3_joint",'),
     "walking.moving_joints: the URDF talos_reduced.urdf has no joint named torso_3_joint"),
    ("moving joint listed twice", edited('"torso_1_joint", "torso_2_joint",', '"torso_1_joint", "torso_1_joint",'),
     "walking.moving_joints lists torso_1_joint more than once"),
    ("fixed joint as moving", edited('"torso_2_joint",', '"torso_2_joint", "leg_left_sole_fix_joint",'),
     "leg_left_sole_fix_joint is a fixed joint"),
    ("empty moving joints", re.sub(r"moving_joints = \[.*?\]", "moving_joints = []", TALOS_TEXT, flags=re.S),
     "walking.moving_joints must be a non-empty list"),
    ("torso frame not in URDF", edited('torso_frame = "torso_2_link"', 'torso_frame = "chest"'),
     "walking.torso_frame: the URDF talos_reduced.urdf has no link or joint named 'chest'"),
    ("posture joint not in URDF", edited("torso_1_joint = 0.0", "waist_joint = 0.0"),
     "posture.waist_joint: the URDF has no movable joint named 'waist_joint'"),
    ("posture outside limits", edited("leg_left_4_joint = 0.859395", "leg_left_4_joint = -0.5"),
     "posture.leg_left_4_joint = -0.5 is outside the URDF limits [0.0, 2.618]"),
    ("posture not a number", edited("leg_left_4_joint = 0.859395", 'leg_left_4_joint = "bent"'),
     "posture.leg_left_4_joint must be a finite number"),
    ("negative gain", TALOS_TEXT + "\n[gains]\nkp = -1.0\nkd = 1.0\n", "gains.kp must be a number >= 0"),
    ("gain for an unknown joint", TALOS_TEXT + "\n[gains]\nkp = 1.0\nkd = { elbow = 1.0 }\n", "gains.kd.elbow"),
    ("unknown stepping key", edited("max_length = 0.29", "max_lenght = 0.29"), "stepping.max_lenght"),
    ("negative step length", edited("max_length = 0.29", "max_length = -0.29"), "stepping.max_length must be"),
    ("step length as text", edited("max_length = 0.29", 'max_length = "far"'), "stepping.max_length must be"),
    ("boolean swing speed", edited("max_swing_speed = 1.0", "max_swing_speed = true"), "stepping.max_swing_speed"),
    ("too short a single support", edited("min_single_support = 0.5", "min_single_support = 0.01"),
     "stepping.min_single_support must be"),
    ("stride box inside out", edited("max_width = 0.40", "max_width = 0.1"), "stepping.min_width (0.15) must be <"),
    ("soles overlapping", edited("min_width = 0.15", "min_width = 0.1"),
     "stepping.min_width (0.1 m) must be at least 2 x feet.sole.inner (0.13 m)"),
    ("stepping not a table", edited("[stepping]", "stepping = 1\n[stepping_]"), "stepping"),
    ("sensor frame not in URDF", edited('frame = "imu_link"', 'frame = "imu_nowhere"'),
     "sensors.imu.frame: the URDF has no link or joint named 'imu_nowhere'"),
    ("unknown sensor key", edited("yaw_drift = 1e-4", "yaw_drfit = 1e-4"), "sensors.imu.yaw_drfit"),
    ("unknown yaw source", edited('yaw_source = "imu"', 'yaw_source = "compass"'),
     "sensors.imu.yaw_source must be one of feet, imu, got 'compass'"),
    ("negative sensor noise", edited("force_noise = 0.5", "force_noise = -0.5"),
     "sensors.feet.force_noise must be a number >= 0 N"),
    ("fractional latency", edited("latency = 0", "latency = 0.5"), "sensors.latency must be a whole number"),
    ("joint torques not a flag", edited("latency = 0", "joint_torques = 1"), "sensors.joint_torques must be"),
    ("bad sensor offset", edited('frame = "imu_link"', 'frame = "imu_link"\noffset = [0.1]'), "sensors.imu.offset"),
    ("one foot sensor frame twice", edited('right_frame = "leg_right_6_link"', 'right_frame = "leg_left_6_link"'),
     "sensors.feet.left_frame and sensors.feet.right_frame must be different frames"),
    ("foot sensor frame missing", edited('right_frame = "leg_right_6_link"', ""),
     "missing required key sensors.feet.right_frame"),
]  # fmt: skip


@pytest.mark.parametrize(("what", "text", "words"), BAD, ids=[case[0] for case in BAD])
def test_bad_description_raises_one_line_naming_the_field(tmp_path, what, text, words):
    with pytest.raises(RobotError) as caught:
        load_robot(write(tmp_path, text))
    message = str(caught.value)
    assert "\n" not in message
    assert words in message, f"{what}: {message}"


def test_unknown_robot_lists_the_known_ones():
    with pytest.raises(RobotError, match=r"unknown robot 'asimo': built-in robots are .*g1.*talos"):
        load_robot("asimo")


def test_unreadable_file(tmp_path):
    with pytest.raises(RobotError, match=r"cannot read robot file .*missing\.toml"):
        load_robot(tmp_path / "missing.toml")


def test_a_file_that_is_not_a_urdf(tmp_path):
    not_urdf = write(tmp_path, "<html></html>", "page.urdf")
    text = edited("example-robot-data:talos_data/robots/talos_reduced.urdf", not_urdf.name)
    with pytest.raises(RobotError, match="is not a URDF"):
        load_robot(write(tmp_path, text))


def test_posture_with_soles_off_the_ground_is_refused(tmp_path):
    # One knee bent much more than the other: the feet cannot both be flat on the ground.
    text = edited("leg_left_4_joint = 0.859395", "leg_left_4_joint = 1.5")
    with pytest.raises(RobotError, match="soles are not flat on the ground"):
        RobotModel.load(load_robot(write(tmp_path, text)))


def test_swapped_feet_are_refused(tmp_path):
    text = edited('left_sole_frame = "left_sole_link"', 'left_sole_frame = "right_sole_link"')
    text = text.replace('right_sole_frame = "right_sole_link"', 'right_sole_frame = "left_sole_link"')
    with pytest.raises(RobotError, match="left sole frame is not to the left"):
        RobotModel.load(load_robot(write(tmp_path, text)))


def test_description_values_are_finite():
    for name in builtin_robots():
        description = load_robot(name)
        assert all(math.isfinite(v) for v in description.posture.values())
        assert description.cog_height > 0.0


def test_step_limits_come_from_the_stepping_table():
    talos, g1 = load_robot("talos"), load_robot("g1")
    assert talos.stepping is not None and g1.stepping is not None
    assert (talos.stepping.max_length, talos.stepping.min_width, talos.stepping.max_width) == (0.29, 0.15, 0.40)
    assert g1.stepping.max_swing_speed == 1.5 and g1.stepping.min_single_support == 0.35
    # The no-crossing limit leaves the soles apart on both robots.
    for robot in (talos, g1):
        assert robot.stepping.min_width > 2.0 * robot.sole.inner
    adjust = talos.stepping.adjustment(talos.sole, adapt_timing=True)
    assert adjust.sole == talos.sole and adjust.limits.max_length == 0.29 and adjust.limits.min_single_support == 0.5
    assert adjust.adapt_timing


def test_a_partial_stepping_table_takes_the_defaults_and_none_gives_none(tmp_path):
    start = TALOS_TEXT.index("[stepping]")
    without = TALOS_TEXT[:start]
    assert load_robot(write(tmp_path, without)).stepping is None
    table = "[stepping]\nmax_length = 0.2\nmin_width = 0.16\n"
    partial = load_robot(write(tmp_path, without + table, "partial.toml")).stepping
    assert partial.max_length == 0.2 and partial.max_width == 0.45 and partial.min_time_to_touchdown == 0.2
    # The core's default no-crossing limit (0.12 m) is too narrow for Talos's soles: said in one line.
    with pytest.raises(RobotError, match=r"stepping\.min_width"):
        load_robot(write(tmp_path, without + "[stepping]\nmax_length = 0.2\n", "narrow.toml"))
