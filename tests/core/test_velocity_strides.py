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
from rtgait.core.walk.velocity_command import StepLimits, VelocityCommand, clamp_command, command_reach

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


def pair_demands(prints) -> list[tuple[float, float, float]]:
    """The strides' demands per pair of consecutive steps, from the footprints alone: forward step (m), sideways
    displacement (the difference of the two widths, m) and the turn of the pair (rad)."""
    strides = [stride_between(a, b) for a, b in itertools.pairwise(prints[1:])]
    return [(max(abs(s.length), abs(t.length)), abs(s.width - t.width), abs(s.turn) + abs(t.turn))
            for s, t in itertools.pairwise(strides)]  # fmt: skip


def test_every_command_the_planner_accepts_makes_strides_within_the_limits_ellipsoid():
    """Over a grid of commands up to three times the limits on every axis, diagonals included: the strides ask shares
    of the three limits whose squares add up to at most 1, and a command inside the ellipsoid is walked as asked."""
    limits = (0.25, 0.18, 1.0)  # G1's: forward step m, sideways per pair m, turn per pair rad
    config = PlannerConfig(timing=TIMING, step_width=0.237, max_step_length=limits[0], max_step_lateral=limits[1],
                           max_step_turn=limits[2], min_step_width=0.15)  # fmt: skip
    top = (limits[0] / PERIOD, limits[1] / (2 * PERIOD), limits[2] / (2 * PERIOD))  # each axis's largest command
    grid = (-3.0, -1.0, -0.6, 0.0, 0.5, 0.9, 3.0)
    for a, b, c in itertools.product(grid, grid, (-1.0, 0.0, 0.4, 2.0)):
        command = (a * top[0], b * top[1], c * top[2])
        inside = a * a + b * b + c * c <= 1.0
        planner = OnlinePlanner(config, None)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", CommandClampedWarning)
            planner.set_velocity(*command)
        assert bool(caught) is not inside, command
        for length, lateral, turn in pair_demands(planner.footprints(8)):
            share = (length / limits[0]) ** 2 + (lateral / limits[1]) ** 2 + (turn / limits[2]) ** 2
            assert share <= 1.0 + 1e-9, (command, share)
            if inside:  # walked as asked: v T forward, 2 v T sideways and 2 w T of turn per pair of steps
                assert (length, lateral, turn) == pytest.approx(
                    (abs(command[0]) * PERIOD, 2 * abs(command[1]) * PERIOD, 2 * abs(command[2]) * PERIOD), abs=1e-12
                )


def test_a_diagonal_command_beyond_the_limits_keeps_its_direction_and_the_warning_names_it():
    """The issue's diagonal, 0.2 m/s forward and 0.08 m/s sideways at fig7's 2.3 s steps with G1's limits there
    (0.2 m, 0.07 m): each alone is beyond its limit; it is scaled onto the ellipsoid, not cut per axis to its corner
    (0.2 m forward and 0.07 m sideways at once, beyond what either limit alone asks)."""
    period = 2.3
    config = PlannerConfig(timing=Timing(0.8, 1.5), step_width=0.237, max_step_length=0.2, max_step_lateral=0.07,
                           max_step_turn=1.0, min_step_width=0.15)  # fmt: skip
    planner = OnlinePlanner(config, None)
    share = math.hypot(0.2 * period / 0.2, 2 * 0.08 * period / 0.07)
    vx, vy = 0.2 / share, 0.08 / share
    with pytest.warns(CommandClampedWarning, match=rf"clamped to \({vx:.4g} m/s, {vy:.4g} m/s, 0 rad/s\)"):
        planner.set_velocity(0.2, 0.08, 0.0)
    for length, lateral, turn in pair_demands(planner.footprints(8)):
        assert (length, lateral, turn) == pytest.approx((vx * period, 2 * vy * period, 0.0), abs=1e-12)
        assert lateral / length == pytest.approx(2 * 0.08 / 0.2)  # the direction asked
        assert (length / 0.2) ** 2 + (lateral / 0.07) ** 2 == pytest.approx(1.0)  # on the ellipsoid


SWAY_TABLE = {
    "max_step_length": 0.25, "max_step_lateral": 0.18, "max_step_turn": 1.0, "min_step_width": 0.15, "max_sway": 0.6,
    "more_sway": [{"max_sway": 0.72, "max_step_lateral": 0.15},
                  {"max_sway": 1.0, "max_step_length": 0.2, "max_step_lateral": 0.07}],
}  # fmt: skip


@pytest.mark.parametrize(
    ("timing", "expected"),
    [(Timing(0.7, 0.1), (0.25, 0.18)), (Timing(0.8, 0.2), (0.25, 0.15)), (Timing(0.8, 1.5), (0.2, 0.07)),
     (Timing(1.5, 0.2), (0.2, 0.07)), (Timing(0.3, 0.05), (0.25, 0.18))],
)  # fmt: skip
def test_a_walk_takes_the_limits_of_its_timing_s_sway(timing, expected):
    """At a COG height of 0.64 m the sways are 0.598 (0.7 + 0.1 s), 0.719 (0.8 + 0.2 s), 0.952 (0.8 + 1.5 s),
    0.927 (1.5 + 0.2 s) and 0.195 (0.3 + 0.05 s) (tests/core/test_cog_sway.py checks them against the planner): each
    takes the first table that holds up to its sway; what an entry leaves out is the one before it."""
    limits = VelocityLimits.from_table(SWAY_TABLE)
    config = limits.apply(PlannerConfig(cog_height=0.64, timing=timing, step_width=0.237))
    assert (config.max_step_length, config.max_step_lateral) == expected
    assert (config.max_step_turn, config.min_step_width) == (1.0, 0.15)


@pytest.mark.parametrize(
    ("change", "message"),
    [({"max_sway": 1.5}, r"^velocity\.max_sway must be within \(0, 1\]"),
     ({"max_sway": None}, r"^velocity\.max_sway is needed with more_sway"),
     ({"more_sway": [{"max_step_lateral": 0.1}]}, r"^velocity\.more_sway\[0\]: missing key 'max_sway'"),
     ({"more_sway": [{"max_sway": 0.5}]}, r"^velocity\.more_sway\[0\]\.max_sway must be more than the one before it"),
     ({"more_sway": [{"max_sway": 0.9, "max_step_lateral": -1.0}]}, r"^velocity\.more_sway\[0\]\.max_step_lateral"),
     ({"more_sway": [{"max_sway": 0.9, "more_sway": []}]}, r"^velocity\.more_sway\[0\]: unknown key 'more_sway'"),
     ({"more_sway": {"max_sway": 0.9}}, r"^velocity\.more_sway must be a list of tables")],
)  # fmt: skip
def test_a_bad_sway_table_names_the_key(change, message):
    table = {**SWAY_TABLE, **change}
    table = {key: value for key, value in table.items() if value is not None}
    with pytest.raises(ValueError, match=message):
        VelocityLimits.from_table(table)


def test_a_command_near_the_float_range_is_scaled_onto_the_ellipsoid_keeping_its_direction():
    limits = StepLimits(0.3, 0.2, 0.6)
    clamped = clamp_command(VelocityCommand(1e308, -1e308, 0.0), limits, 0.8)
    assert command_reach(clamped, limits, 0.8) == pytest.approx(1.0)
    assert clamped.vx > 0.0 > clamped.vy and clamped.wz == 0.0
    # the direction kept: vx / vy is the command's -1
    assert clamped.vx / clamped.vy == pytest.approx(-1.0)
