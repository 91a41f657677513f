"""Footholds in 3D in files: ``z``, ``pitch``, ``roll`` per footstep and the ``[terrain]`` table
(:mod:`rtgait.scenario.terrain_table`), placed and checked, with one-line errors naming the field or the step."""

from __future__ import annotations

import math
import sys

import pytest

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised only on Python 3.10
    import tomli as tomllib

from scenario_files import header_text, scenario_text

from rtgait.core.geometry.footsteps import Footstep, Stride, place_step, stride_between
from rtgait.scenario.loading import parse_document
from rtgait.scenario.scenario import ScenarioError

TALOS_SOLE = "[robot.sole]\nfront = 0.105\nback = 0.105\ninner = 0.065\nouter = 0.065\n"


def _load(text: str):
    return parse_document(tomllib.loads(text))


def _walk(terrain: str, steps: int = 8, step_length: float = 0.25) -> str:
    # The Talos sole replaces the HRP-2-like one of the template (it fits a 25 cm tread).
    text = scenario_text(steps=steps, step_length=step_length).replace(
        "[robot.sole]\nfront = 0.13\nback = 0.10\ninner = 0.07\nouter = 0.07\n", TALOS_SOLE
    )
    return text + "[terrain]\n" + terrain


STAIRS = 'type = "stairs"\nriser = 0.15\ntread = 0.25\ncount = 6\nstart = 0.375\n'


def test_stride_carries_rise_and_surface_both_ways():
    stance = Footstep(0.1, -0.1, 0.2, "right", z=0.3)
    landing = place_step(stance, Stride(0.25, 0.19, 0.1, rise=0.15, pitch=-0.1, roll=0.05))
    assert (landing.z, landing.pitch, landing.roll) == pytest.approx((0.45, -0.1, 0.05))
    back = stride_between(stance, landing)
    assert (back.length, back.rise, back.pitch) == pytest.approx((0.25, 0.15, -0.1))


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [("z", math.nan, "footstep z"), ("pitch", 0.6, "footstep pitch"), ("roll", -1.0, "footstep roll")],
)
def test_footstep_refuses_bad_height_or_tilt(field, value, message):
    with pytest.raises(ValueError, match=message):
        Footstep(0.0, 0.0, 0.0, "left", **{field: value})


def test_footstep_plan_takes_z_pitch_roll():
    steps = [
        ("right", 0.2, -0.095, "z = 0.05\npitch = -0.1\n"),
        ("left", 0.4, 0.095, "z = 0.1\nroll = 0.02\n"),
        ("right", 0.4, -0.095, "z = 0.1\n"),
    ]
    text = header_text() + "".join(
        f'\n[[footstep]]\nside = "{side}"\nx = {x}\ny = {y}\n{extra}' for side, x, y, extra in steps
    )
    scenario = _load(text)
    prints = scenario.nominal_footprints()
    assert [f.z for f in prints] == pytest.approx([0.0, 0.0, 0.05, 0.1, 0.1])
    assert (prints[2].pitch, prints[3].roll) == pytest.approx((-0.1, 0.02))
    assert [s.rise for s in scenario.strides()] == pytest.approx([0.05, 0.05, 0.0])


def test_footstep_plan_refuses_a_steep_pitch():
    text = header_text() + '\n[[footstep]]\nside = "right"\nx = 0.2\ny = -0.095\npitch = 0.7\n'
    text += '\n[[footstep]]\nside = "left"\nx = 0.2\ny = 0.095\n'
    with pytest.raises(ScenarioError, match=r"^footstep\[0\]\.pitch must be within"):
        _load(text)


def test_stairs_place_every_foot_on_its_tread():
    scenario = _load(_walk(STAIRS))
    heights = [f.z for f in scenario.nominal_footprints()]
    # Step k lands at x = 0.25 k: on the floor for k = 1, on tread k - 1 for k = 2..7, on the landing after.
    assert heights == pytest.approx([0, 0, 0, 0.15, 0.3, 0.45, 0.6, 0.75, 0.9, 0.9, 0.9])
    assert [s.rise for s in scenario.strides()][:3] == pytest.approx([0.0, 0.15, 0.15])


def test_slope_gives_height_and_pitch():
    slope = 'type = "slope"\nangle = 0.1\nlength = 2.0\nstart = 0.5\n'
    prints = _load(_walk(slope, steps=6, step_length=0.2)).nominal_footprints()
    on_ramp = prints[5]  # x = 0.8
    assert on_ramp.z == pytest.approx(math.tan(0.1) * 0.3)
    assert on_ramp.pitch == pytest.approx(-0.1)  # rising ahead: toes up, a negative right-hand pitch


def test_place_footsteps_false_keeps_the_plan_flat():
    step = 'type = "step"\nheight = 0.03\nx = 0.7\nplace_footsteps = false\n'
    scenario = _load(_walk(step, steps=5, step_length=0.2))
    assert all(f.z == 0.0 for f in scenario.nominal_footprints())
    assert scenario.terrain is not None and scenario.terrain.terrain.height(0.8, 0.0) == pytest.approx(0.03)


@pytest.mark.parametrize(
    ("terrain", "steps", "length", "message"),
    [
        (
            'type = "stairs"\nriser = 0.15\ntread = 0.25\ncount = 6\nstart = 0.3\n',
            8,
            0.25,
            r"step 1 at x = 0\.25 m lands across an edge",
        ),
        (
            'type = "stairs"\nriser = 0.25\ntread = 0.25\ncount = 2\nstart = 0.375\n',
            4,
            0.25,
            r"step 2 goes 0\.25 m up: beyond the robot's reach",
        ),
        (
            'type = "stones"\nlength = 0.2\nwidth = 0.15\ngap = 0.1\ncount = 3\nstart = 0.35\n',
            4,
            0.3,
            r"step 2 lands off the surface at x = 0\.6 m",
        ),
        (
            'type = "stairs"\nriser = 0.15\ntread = 0.25\ncount = 6\ndirection = "sideways"\n',
            4,
            0.25,
            r"^terrain\.direction must be 'up' or 'down'",
        ),
        ('type = "stairs"\nriser = 0.6\ntread = 0.25\ncount = 6\n', 4, 0.25, r"^terrain\.riser must be within"),
        ('type = "slope"\nangle = 0.1\n', 4, 0.25, r"^missing required key terrain\.length"),
        ('type = "volcano"\n', 4, 0.25, r"^terrain\.type must be one of"),
        ('type = "step"\nheight = 0.03\nx = 0.7\nwidth = 1\n', 4, 0.25, r"^unknown key terrain\.width"),
        ('type = "step"\nheight = 0.03\nx = -0.5\n', 4, 0.25, r"standing foot F\[0\] must stand on level ground"),
    ],
)
def test_terrain_errors_are_one_line(terrain, steps, length, message):
    with pytest.raises(ScenarioError, match=message) as error:
        _load(_walk(terrain, steps=steps, step_length=length))
    assert "\n" not in str(error.value)


def test_a_swing_too_low_for_the_stairs_is_refused_naming_the_step():
    text = _walk(STAIRS).replace("step_height = 0.05", "step_height = 0.01")
    with pytest.raises(ScenarioError, match=r"^terrain: step 1's swing passes 0\.0\d+ m over the terrain mid-swing"):
        _load(text)


def test_swing_over_the_nose_keeps_its_clearance():
    from rtgait.core.geometry.swing_terrain import swing_gaps

    scenario = _load(_walk(STAIRS))
    prints, terrain = scenario.nominal_footprints(), scenario.terrain.terrain
    for step in range(1, len(prints) - 1):
        s, gap = swing_gaps(terrain, prints[step - 1], prints[step + 1], scenario.step_height, scenario.sole)
        assert gap.min() > -1e-9  # never into a tread or a riser
        if prints[step - 1].z != prints[step + 1].z:  # over a nose: the full step height above the upper tread
            assert gap[(s >= 0.35) & (s <= 0.65)].min() == pytest.approx(scenario.step_height, abs=1e-9)
