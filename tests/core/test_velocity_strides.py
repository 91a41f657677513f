"""Strides of walks by velocity command: within the step limits a command is walked as asked (no clamping), the
strides respect the limits, and the footprints move the body by the command's displacement.

The truth is geometry: over a step period ``T`` a command ``(vx, vy, wz)`` must carry the feet ``vx T`` forward per
step, ``2 vy T`` sideways and ``2 wz T`` in heading per pair of steps; the feet never cross.
"""

from __future__ import annotations

import itertools
import math
import warnings

import pytest

from rtgait.core.geometry.footsteps import Timing, stride_between, wrap_angle
from rtgait.core.planner.config import PlannerConfig, VelocityLimits
from rtgait.core.planner.online import CommandClampedWarning, OnlinePlanner

TIMING = Timing(0.7, 0.1)  # T = 0.8 s, the paper's fig8
PERIOD = 0.8


def command_footprints(config: PlannerConfig, vx: float, vy: float, wz: float, steps: int = 12):
    """The footprints ``F[0..steps + 1]`` of a walk by this command, no warning allowed."""
    planner = OnlinePlanner(config, None)
    with warnings.catch_warnings():
        warnings.simplefilter("error", CommandClampedWarning)
        planner.set_velocity(vx, vy, wz)
    return planner.footprints(steps + 1)


def test_the_issue_s_commands_are_not_clamped_within_wider_limits():
    """0.1 m/s sideways and 0.3 rad/s turning with 0.8 s steps need 0.16 m and 0.48 rad per pair of steps."""
    config = PlannerConfig(
        timing=TIMING, step_width=0.17, max_step_lateral=0.25, max_step_turn=0.6, min_step_width=0.15
    )
    for command in ((0.0, 0.1, 0.0), (0.0, 0.0, 0.3), (0.3, 0.0, 0.0), (-0.1, 0.0, 0.0)):
        command_footprints(config, *command)  # raises if clamped
    with pytest.warns(CommandClampedWarning, match="lateral 0.1 m and turn 0.4 rad per pair of steps"):
        OnlinePlanner(PlannerConfig(timing=TIMING), None).set_velocity(0.0, 0.1, 0.0)  # the defaults clamp it


@pytest.mark.parametrize("vy", [0.1, -0.1, 0.04])
def test_a_sideways_walk_spreads_its_widths_around_the_stance(vy):
    """The step toward the motion lands 2 vy T wider than the next one; the widths lie evenly around the stance,
    the narrow one never below min_step_width; the feet advance 2 vy T per pair of steps and never cross."""
    width, narrowest = 0.17, 0.15
    config = PlannerConfig(timing=TIMING, step_width=width, max_step_lateral=0.25, min_step_width=narrowest)
    prints = command_footprints(config, 0.0, vy, 0.0)
    shift = 2.0 * abs(vy) * PERIOD
    narrow = max(width - 0.5 * shift, narrowest)
    toward = "left" if vy > 0 else "right"
    for stance, landing in itertools.pairwise(prints[1:]):
        stride = stride_between(stance, landing)
        expected = narrow + shift if landing.side == toward else narrow
        assert stride.width == pytest.approx(expected, abs=1e-12)
        assert narrowest - 1e-12 <= stride.width <= narrowest + config.max_step_lateral + 1e-12
        assert stride.length == pytest.approx(0.0, abs=1e-12) and stride.turn == pytest.approx(0.0, abs=1e-12)
    # Once both feet have stepped, every footprint lies 2 vy T beside the previous one of the same foot: the body
    # moves vy per second (the standing feet are the stance itself, neither wide nor narrow).
    for before, after in zip(prints[2:], prints[4:], strict=False):
        assert after.y - before.y == pytest.approx(2.0 * vy * PERIOD, abs=1e-12)


def test_without_min_step_width_the_feet_only_open():
    """The default (min_step_width None) never narrows the stance: the narrow step lands at step_width."""
    config = PlannerConfig(timing=TIMING, step_width=0.19, max_step_lateral=0.16)
    widths = {
        round(stride_between(a, b).width, 12) for a, b in itertools.pairwise(command_footprints(config, 0, 0.1, 0)[1:])
    }
    assert widths == {0.19, round(0.19 + 0.16, 12)}


@pytest.mark.parametrize("wz", [0.3, -0.3])
def test_every_step_turns_half_of_a_pair_s_turn(wz):
    """Each step turns wz T (the feet alternately toe out and in by wz T), never more than max_step_turn / 2; the
    heading after n steps is n wz T."""
    config = PlannerConfig(timing=TIMING, step_width=0.17, max_step_turn=0.6)
    prints = command_footprints(config, 0.0, 0.0, wz)
    for stance, landing in itertools.pairwise(prints[1:]):
        turn = wrap_angle(landing.yaw - stance.yaw)
        assert turn == pytest.approx(wz * PERIOD, abs=1e-12)
        assert abs(turn) <= 0.5 * config.max_step_turn + 1e-12
    assert wrap_angle(prints[-1].yaw - wz * PERIOD * (len(prints) - 2)) == pytest.approx(0.0, abs=1e-9)


def test_a_command_beyond_the_limits_is_clamped_to_them():
    config = PlannerConfig(timing=TIMING, step_width=0.17, max_step_lateral=0.2, max_step_turn=0.5, min_step_width=0.15)
    planner = OnlinePlanner(config, None)
    with pytest.warns(CommandClampedWarning):
        planner.set_velocity(1.0, 0.5, 1.0)
    prints = planner.footprints(9)
    for stance, landing in itertools.pairwise(prints[1:]):
        stride = stride_between(stance, landing)
        assert abs(stride.length) <= config.max_step_length + 1e-12
        assert 0.15 - 1e-12 <= stride.width <= 0.15 + 0.2 + 1e-12
        assert abs(stride.turn) <= 0.25 + 1e-12


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [("min_step_width", 0.2, "min_step_width must be None or within"), ("min_step_width", 0.0, "min_step_width"),
     ("min_step_width", math.nan, "min_step_width"), ("max_step_turn", 1.6, "max_step_turn"),
     ("max_step_lateral", -0.1, "max_step_lateral")],
)  # fmt: skip
def test_bad_limits_are_refused_naming_the_field(field, value, message):
    with pytest.raises(ValueError, match=message):
        PlannerConfig(step_width=0.19, **{field: value})


@pytest.mark.parametrize(
    ("table", "message"),
    [({"max_step_turn": 2.0}, r"^velocity\.max_step_turn must be within"),
     ({"max_step_lateral": 0.0}, r"^velocity\.max_step_lateral must be within"),
     ({"min_step_width": -1.0}, r"^velocity\.min_step_width must be within"),
     ({"max_step_length": "far"}, r"^velocity\.max_step_length must be a number"),
     ({"max_turn": 0.5}, r"^velocity: unknown key 'max_turn'")],
)  # fmt: skip
def test_a_bad_velocity_table_names_the_key(table, message):
    with pytest.raises(ValueError, match=message):
        VelocityLimits.from_table(table)


def test_velocity_limits_replace_the_config_s_and_check_against_its_stance():
    limits = VelocityLimits(max_step_lateral=0.25, min_step_width=0.15)
    config = limits.apply(PlannerConfig(step_width=0.17))
    assert (config.max_step_lateral, config.min_step_width, config.max_step_turn) == (0.25, 0.15, 0.4)
    with pytest.raises(ValueError, match=r"^velocity\.min_step_width must be None or within \(0, step_width = 0.14\]"):
        limits.apply(PlannerConfig(step_width=0.14))
