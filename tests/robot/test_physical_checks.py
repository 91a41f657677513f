"""A robot's URDF checked for physical sense at load: copies of G1's URDF with a link's mass zero, negative, NaN or
not a number, an inertia no rigid body has, all masses in grams or zero are refused in one line by every command
that loads a robot (exit 2, nothing written, no C++ parser message); Talos and G1 load as before."""

from __future__ import annotations

import functools
import math
import xml.etree.ElementTree as ElementTree
from collections.abc import Callable
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pinocchio")

from rtgait.cli.main import main
from rtgait.robot.description import RobotError, load_robot
from rtgait.robot.description_checks import read_urdf
from rtgait.robot.model import RobotModel
from rtgait.robot.physical_checks import (
    COM_HEIGHT_RANGE,
    TOTAL_MASS_RANGE,
    check_urdf_physics,
    check_whole_body,
)

G1_TEXT = resources.files("rtgait").joinpath("robots", "g1.toml").read_text(encoding="utf-8")
G1_URDF_KEY = 'urdf = "example-robot-data:g1_description/urdf/g1_29dof_rev_1_0.urdf"'
KNEE = "left_knee_link"
INERTIA_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")


@functools.cache
def g1_urdf_text() -> str:
    """G1's URDF as its description finds it (parsed once for the module)."""
    return load_robot("g1").urdf.read_text(encoding="utf-8")


def inertial(root: ElementTree.Element, link: str) -> ElementTree.Element:
    found = root.find(f"link[@name='{link}']/inertial")
    assert found is not None, link
    return found


def set_mass(value: str, link: str = KNEE) -> Callable[[ElementTree.Element], None]:
    def edit(root: ElementTree.Element) -> None:
        inertial(root, link).find("mass").set("value", value)  # type: ignore[union-attr]

    return edit


def set_inertia(matrix: np.ndarray, link: str = KNEE) -> Callable[[ElementTree.Element], None]:
    def edit(root: ElementTree.Element) -> None:
        element = inertial(root, link).find("inertia")
        for key, (i, j) in zip(INERTIA_KEYS, [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)], strict=True):
            element.set(key, repr(float(matrix[i, j])))  # type: ignore[union-attr]

    return edit


def scale_every_inertial(factor: float) -> Callable[[ElementTree.Element], None]:
    def edit(root: ElementTree.Element) -> None:
        for element in root.iter("inertial"):
            mass = element.find("mass")
            mass.set("value", repr(float(mass.get("value")) * factor))  # type: ignore[union-attr, arg-type]
            inertia = element.find("inertia")
            for key in INERTIA_KEYS:
                inertia.set(key, repr(float(inertia.get(key)) * factor))  # type: ignore[union-attr, arg-type]

    return edit


def broken_g1(folder: Path, edit: Callable[[ElementTree.Element], None]) -> Path:
    """G1's description with its URDF copied next to it and edited; returns the description file."""
    root = ElementTree.fromstring(g1_urdf_text())
    edit(root)
    (folder / "g1_broken.urdf").write_bytes(ElementTree.tostring(root))
    assert G1_URDF_KEY in G1_TEXT
    # Meshes resolve against example-robot-data's share folder (the default package_dirs).
    description = folder / "g1_broken.toml"
    description.write_text(G1_TEXT.replace(G1_URDF_KEY, 'urdf = "g1_broken.urdf"'), encoding="utf-8")
    return description


def refusal(capfd: pytest.CaptureFixture[str], args: list[str], out: Path) -> str:
    """Run the command line; it must exit 2 with one error line on the standard error (C++ writes included) and
    write nothing. Returns the line."""
    code = main([*args, "--out", str(out)])
    captured = capfd.readouterr()
    assert code == 2, captured.err
    assert captured.out == ""
    assert captured.err.count("\n") == 1 and captured.err.startswith("rtgait: error: "), captured.err
    assert not out.exists()
    return captured.err.strip()


# ----- each problem, its line ---------------------------------------------------------------------------------------
PREFIX = 'rtgait: error: model.urdf g1_broken.urdf: link "left_knee_link"'
MASS = PREFIX + " has mass {} kg: masses must be positive and finite"
MASSLESS_HINT = " (a massless link has no <inertial>)"


@pytest.mark.parametrize(
    ("edit", "line"),
    [
        (set_mass("0"), MASS.format("0") + MASSLESS_HINT),
        (set_mass("-50"), MASS.format("-50") + MASSLESS_HINT),
        (set_mass("nan"), MASS.format("nan")),  # urdfdom would print four lines and drop the link's inertia
        (set_mass("inf"), MASS.format("inf")),
        (set_mass("2,5"), PREFIX + ' <mass value>: "2,5" is not a number'),
    ],
    ids=["zero", "negative", "nan", "inf", "comma"],
)
def test_a_bad_link_mass_is_one_line_naming_the_link_and_the_value(tmp_path, capfd, edit, line):
    robot = broken_g1(tmp_path, edit)
    assert refusal(capfd, ["plan", "fig11", "--robot", str(robot), "--no-figures"], tmp_path / "out") == line


@pytest.mark.parametrize(
    ("moments", "words"),
    [
        ((-0.002, 0.011, 0.011), "none may be negative"),  # not positive semi-definite
        ((0.001, 0.002, 0.011), "I1 + I2 >= I3"),  # positive definite, but no rigid body has it
    ],
    ids=["not-positive", "triangle"],
)
def test_an_inertia_no_rigid_body_has_is_refused(tmp_path, capfd, moments, words):
    # The principal moments given, turned away from the link's axes (a rotation about (1, 2, 3) by 0.7 rad).
    axis = np.array([1.0, 2.0, 3.0]) / math.sqrt(14.0)
    cross = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    rotation = np.eye(3) + math.sin(0.7) * cross + (1.0 - math.cos(0.7)) * cross @ cross
    robot = broken_g1(tmp_path, set_inertia(rotation @ np.diag(moments) @ rotation.T))
    line = refusal(capfd, ["plan", "fig11", "--robot", str(robot), "--no-figures"], tmp_path / "out")
    assert f'link "{KNEE}" has an inertia with principal moments' in line and words in line
    for moment in moments:  # the moments named are the ones given, whatever the axes
        assert f"{moment:.4g}" in line


@pytest.mark.parametrize("factor", [1000.0, 0.0], ids=["grams", "massless"])  # massless: every mass and inertia 0
def test_an_implausible_total_mass_is_refused(tmp_path, capfd, factor):
    robot = broken_g1(tmp_path, scale_every_inertial(factor))
    line = refusal(capfd, ["plan", "fig11", "--robot", str(robot), "--no-figures"], tmp_path / "out")
    low, high = TOTAL_MASS_RANGE
    total = factor * sum(float(m.get("value")) for m in ElementTree.fromstring(g1_urdf_text()).iter("mass"))
    assert line.startswith(f"rtgait: error: robot g1: total mass {total:.6g} kg is outside the plausible range")
    assert f"[{low:g}, {high:g}] kg" in line


def test_a_urdf_error_of_pinocchio_s_parser_is_one_line(tmp_path, capfd):
    """What the XML checks do not look at, urdfdom reports (to the C++ standard error): caught, one line."""

    def no_knee_limit(root: ElementTree.Element) -> None:
        joint = root.find("joint[@name='left_knee_joint']")
        joint.remove(joint.find("limit"))  # type: ignore[union-attr, arg-type]

    robot = broken_g1(tmp_path, no_knee_limit)
    line = refusal(capfd, ["plan", "fig11", "--robot", str(robot), "--no-figures"], tmp_path / "out")
    assert "Pinocchio cannot build it" in line and "left_knee_joint" in line and "limits" in line


# ----- every command that loads a robot -----------------------------------------------------------------------------
@pytest.mark.parametrize(
    "command",
    [
        ["plan", "fig11"],
        ["simulate", "fig11", "--model", "lipm"],  # the pendulum takes the robot's mass
        ["simulate", "fig11"],
    ],
    ids=["plan", "simulate-lipm", "simulate-mujoco"],
)
def test_every_command_refuses_the_robot(tmp_path, capfd, command):
    robot = broken_g1(tmp_path, set_mass("-50"))
    assert (
        refusal(capfd, [*command, "--robot", str(robot), "--quiet"], tmp_path / "out")
        == MASS.format("-50") + MASSLESS_HINT
    )


def test_play_refuses_the_robot(tmp_path, capfd, monkeypatch):
    pytest.importorskip("mujoco")
    import rtgait.viz.live_view as live_view

    monkeypatch.setattr(live_view, "check_display", lambda: None)  # the robot is loaded before a window opens
    robot = broken_g1(tmp_path, set_mass("-50"))
    code = main(["play", "fig11", "--robot", str(robot), "--quiet"])
    captured = capfd.readouterr()
    assert code == 2 and captured.err.strip() == MASS.format("-50") + MASSLESS_HINT


# ----- what passes --------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["talos", "g1"])
def test_the_builtin_robots_load_unchanged_and_quietly(capfd, name):
    description = load_robot(name)
    robot = RobotModel.load(description)
    captured = capfd.readouterr()
    assert captured.err == "" and captured.out == ""
    # Independent: the masses written in the URDF, summed.
    masses = [float(m.get("value")) for m in read_urdf(description.urdf).iter("mass")]  # type: ignore[arg-type]
    assert robot.mass == pytest.approx(sum(masses), rel=1e-12)
    assert TOTAL_MASS_RANGE[0] < robot.mass < TOTAL_MASS_RANGE[1]
    assert COM_HEIGHT_RANGE[0] < robot.cog_half_sitting[2] < COM_HEIGHT_RANGE[1]


def urdf_with_inertia(tmp_path: Path, mass: float, matrix: np.ndarray) -> Path:
    path = tmp_path / "one.urdf"
    values = " ".join(f'{key}="{matrix[i, j]:.6g}"' for key, (i, j) in
                      zip(INERTIA_KEYS, [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)], strict=True))  # fmt: skip
    path.write_text(
        f'<robot name="one"><link name="body"><inertial><mass value="{mass}"/><inertia {values}/></inertial></link>'
        '<link name="frame"/></robot>',
        encoding="utf-8",
    )
    return path


def test_limit_cases_of_a_rigid_body_pass_once_written_with_six_digits(tmp_path):
    """A thin plate (I1 + I2 = I3), a thin rod (I1 = 0) and a point mass (I = 0), turned and written with six
    significant digits, are rigid bodies: accepted. A plate 1 % too light for its largest moment is not."""
    mass, side = 2.0, 0.3
    rotation = np.linalg.qr(np.array([[1.0, 2.0, 0.5], [-0.3, 1.0, 2.0], [0.7, -1.2, 1.0]]))[0]
    plate = mass * side**2 / 12.0 * np.array([1.0, 1.0, 2.0])
    rod = mass * side**2 / 12.0 * np.array([0.0, 1.0, 1.0])
    for moments in (plate, rod, np.zeros(3)):
        path = urdf_with_inertia(tmp_path, mass, rotation @ np.diag(moments) @ rotation.T)
        check_urdf_physics(read_urdf(path), path)
    path = urdf_with_inertia(tmp_path, mass, rotation @ np.diag(plate * [0.99, 0.99, 1.0]) @ rotation.T)
    with pytest.raises(RobotError, match=r"I1 \+ I2 >= I3"):
        check_urdf_physics(read_urdf(path), path)


@pytest.mark.parametrize(
    ("mass", "height", "words"),
    [
        (0.5, 0.6, "total mass 0.5 kg"),
        (600.0, 0.6, "total mass 600 kg"),
        (math.nan, 0.6, "total mass nan kg"),
        (30.0, 0.05, "the COM is 0.05 m above the soles"),
        (30.0, 2.5, "the COM is 2.5 m above the soles"),
        (30.0, math.nan, "the COM is nan m above the soles"),
    ],
)
def test_whole_body_ranges(mass, height, words):
    with pytest.raises(RobotError, match="outside the plausible range") as error:
        check_whole_body("probe", mass, height)
    assert words in str(error.value) and "\n" not in str(error.value)
    check_whole_body("probe", TOTAL_MASS_RANGE[0], COM_HEIGHT_RANGE[1])  # the ends are plausible
