"""Hand-guided walking: the admittance from hand force to walking command, and a planner led by the hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.core.geometry.footsteps import Timing
from rtgait.core.laws.guidance import Admittance, HandGuide
from rtgait.core.planner.online import SAMPLE_FIELDS, OnlinePlanner, PlannerConfig

CONFIG = PlannerConfig(timing=Timing(0.7, 0.1), connection="quasi-real-time")  # the paper's experiment


def test_admittance_deadband_gain_and_saturation():
    admittance = Admittance(linear_damping=50.0, force_deadband=5.0, max_forward=0.2)
    assert admittance.command(4.0, 0.0, 0.0, 0.0).vx == 0.0  # inside the deadband
    assert admittance.command(10.0, 0.0, 0.0, 0.0).vx == pytest.approx(5.0 / 50.0)
    assert admittance.command(-10.0, 0.0, 0.0, 0.0).vx == pytest.approx(-5.0 / 50.0)
    assert admittance.command(100.0, 0.0, 0.0, 0.0).vx == pytest.approx(0.2)


def test_admittance_reads_the_pull_in_the_robots_frame():
    """A pull toward world +y is straight ahead for a robot heading +90 degrees."""
    command = Admittance().command(0.0, 15.0, 0.0, math.pi / 2)
    assert command.vx > 0.0 and abs(command.vy) < 1e-12
    left = Admittance().command(15.0, 0.0, 0.0, math.pi / 2)  # world +x is to the robot's right
    assert left.vy < 0.0 and abs(left.vx) < 1e-12


def test_bad_admittance_inputs():
    with pytest.raises(ValueError, match="linear_damping"):
        Admittance(linear_damping=0.0)
    with pytest.raises(ValueError, match="force_x"):
        Admittance().command(float("nan"), 0.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="quasi-real-time"):
        HandGuide(OnlinePlanner(PlannerConfig(timing=Timing(0.7, 0.1)), None))


def lead(pull, seconds: float, dt: float = 0.005):
    """Walk a planner by the hand; ``pull(t) -> (fx, fy, tz)``. Returns the planner, each sampled value by name (one
    array over the ticks each) and the decision times."""
    planner = OnlinePlanner(CONFIG, None)
    guide = HandGuide(planner)
    planner.start(0.0)
    rows, decisions = [], []
    for k in range(int(seconds / dt)):
        t = k * dt
        heading = 0.5 * (rows[-1].lfoot_yaw + rows[-1].rfoot_yaw) if rows else 0.0  # mean yaw of the feet
        if guide.update(t, *pull(t), heading):
            decisions.append(t)
        values, _, _ = planner.sample_values(t)
        rows.append(values)
    return planner, dict(zip(SAMPLE_FIELDS, np.array(rows).T, strict=True)), decisions


def test_a_steady_pull_walks_the_robot_forward_at_the_commanded_speed():
    planner, run, _ = lead(lambda t: (17.0, 0.0, 0.0), 12.0)  # (17 - 5) / 60 = 0.2 m/s
    cog_x = run["cog_x"]
    speed = (cog_x[-1] - cog_x[len(cog_x) // 2]) / 6.0
    assert speed == pytest.approx(0.2, abs=0.02)
    for axis in "xy":  # still a pendulum-consistent plan throughout: p = c - c'' / w^2
        residual = run[f"zmp_{axis}"] - (run[f"cog_{axis}"] - run[f"cog_a{axis}"] / planner.w**2)
        assert np.abs(residual).max() < 1e-9
        assert np.abs(np.diff(run[f"cog_{axis}"])).max() < 0.2 * 0.005 * 3  # no jumps when the command changes


def test_turn_release_and_decisions_come_one_double_support_before_lift_off():
    def pull(t):
        if t < 4.0:
            return 17.0, 0.0, 0.0
        if t < 8.0:
            return 17.0, 0.0, 4.0  # keep pulling and twist: turn left
        return 0.0, 0.0, 0.0  # let go: stepping in place

    planner, run, decisions = lead(pull, 14.0)
    yaw = 0.5 * (run["lfoot_yaw"] + run["rfoot_yaw"])
    assert yaw[int(8.0 / 0.005)] > yaw[int(4.0 / 0.005)] + 0.3
    late = np.column_stack([run["cog_x"], run["cog_y"]])[int(11.0 / 0.005) :]
    heading = np.array([np.cos(yaw[-1]), np.sin(yaw[-1])])
    assert np.ptp(late @ heading) < 0.05  # released: the robot no longer advances (it still sways across its heading)
    for t in decisions:
        # Each decision is made just before a quasi-real-time deadline (the start of the double support before
        # the step's lift-off): at most one double-support duration earlier.
        starts = [planner.phase_start(2 * k) for k in range(40)]
        assert any(0.0 <= start - t <= CONFIG.timing.double_support + 1e-9 for start in starts), t
