"""A known external force: the controller leans against it so that the measured ZMP stays where it is planned.

Independent truths: the statics of a pulled robot (a horizontal force ``F`` at height ``h`` moves the centre of
pressure by at least ``h F / (m g)``, measured in MuJoCo on a robot that does not lean) and the pendulum equation
(the ZMP the lean's own motion makes, ``-delta'' / w^2``, from finite differences of the lean).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.control.external_force import ExternalForce, lean
from rtgait.robot.controller_info import robot_info

G = 9.81


def test_the_lean_balances_the_moment_of_the_force():
    # m g (c - p) + h F = 0 at rest with p = 0: c = -h F / (m g).
    assert lean((30.0, -12.0), 0.8, 90.0, G) == pytest.approx((-0.8 * 30.0 / (90.0 * G), 0.8 * 12.0 / (90.0 * G)))


def test_the_lean_follows_a_step_of_the_force_slowly_enough_for_the_pendulum():
    mass, w, dt = 90.0, 3.42, 0.001
    external = ExternalForce(mass, w, dt, G)
    assert external.time_constant == pytest.approx(2.0 / w)
    target = lean((40.0, 0.0), 0.75, mass, G)[0]
    offsets, rates = [], []
    for _ in range(6000):  # 10 time constants
        external.set((40.0, 0.0), 0.75)
        offsets.append(external.offset[0])
        rates.append(external.rate[0])
    offsets, rates = np.array(offsets), np.array(rates)
    # First order with T = 2 / w: 63 % of the way after T.
    k = round(external.time_constant / dt)
    assert offsets[k - 1] == pytest.approx((1.0 - math.exp(-1.0)) * target, rel=2e-3)
    assert offsets[-1] == pytest.approx(target, rel=1e-3)
    # The rate is the lean's derivative (central differences), and the ZMP the lean's motion makes stays within a
    # quarter of the lean (the module's bound for T = 2 / w), up to the sampling.
    assert rates[1:-1] == pytest.approx((offsets[2:] - offsets[:-2]) / (2.0 * dt), rel=2e-3, abs=1e-6)
    zmp_of_motion = -np.gradient(rates, dt)[2:] / w**2
    assert np.abs(zmp_of_motion).max() <= 0.25 * abs(target) * 1.01
    with pytest.raises(ValueError, match="finite"):
        external.set((math.nan, 0.0), 0.75)
    with pytest.raises(ValueError, match="mass"):
        ExternalForce(0.0, w, dt)


# ----- in physics ---------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def pulled(talos, talos_sim, shorten):
    """Four steps of fig8 on Talos pulled forward at the pelvis from the walk's start: by 15 N with the controller
    not told of it, by 30 N told (a steady 30 N pull topples the robot that does not lean). Not told, its DCM bias
    filter is off: it would take the steady pull for a bias of the COM (rtgait.estimation.dcm_bias) and lean against
    part of it."""
    pytest.importorskip("mujoco")
    from rtgait.control.controller import ControllerOptions, make_controller
    from rtgait.robot.motion import robot_scenario
    from rtgait.sim.loop import LoopOptions
    from rtgait.sim.run_loop import run_sim_loop

    walk = robot_scenario(shorten("fig8", 4), talos)
    base = talos_sim.base_body
    runs = {}
    for told, force in ((False, (15.0, 0.0)), (True, (30.0, 0.0))):
        options = ControllerOptions() if told else ControllerOptions(dcm_bias=False)
        level = make_controller(
            "adaptive", walk.planner_config(), walk.strides(), walk.sole, robot_info(talos), dt=talos_sim.control_dt,
            options=options,
        )  # fmt: skip
        heights = []

        def pull(t, data, level=level, told=told, force=force, heights=heights):
            data.xfrc_applied[base, 0:3] = (*force, 0.0)
            height = float(data.xipos[base][2])  # MuJoCo applies xfrc_applied at the body's centre of mass
            heights.append(height)
            if told:
                level.set_external_force(force, height)

        result = run_sim_loop(talos_sim, level, LoopOptions(on_tick=pull))
        runs[told] = (result, float(np.mean(heights)) * force[0] / (talos.mass * G))  # the pull's ZMP shift (m)
    return runs


def _mean_error(result) -> np.ndarray:
    mask = result.single_support_mask & np.isfinite(result.zmp[:, 0])
    return (result.zmp[mask] - result.zmp_planned[mask]).mean(axis=0)


def test_a_robot_that_does_not_lean_stands_off_its_plan_by_the_pull_s_moment(pulled):
    result, shift = pulled[False]
    assert not result.fell
    # At least the pull's moment moves the ZMP ahead of the plan (15 mm): the statics; the feedback law, seeing the
    # DCM pulled ahead of the plan's, moves it farther the same way (27 mm in all).
    error = _mean_error(result)[0]
    assert 0.8 * shift < error < 3.0 * shift


def test_a_robot_that_leans_against_the_pull_keeps_its_zmp_on_the_plan(pulled):
    result, shift = pulled[True]
    assert not result.fell and result.ended_at_rest
    assert abs(_mean_error(result)[0]) < 0.3 * shift
    # It leaned back: at rest, its COM target behind the planned ZMP by about the lean.
    assert result.cog_planned[-1, 0] - result.zmp_planned[-1, 0] == pytest.approx(-shift, rel=0.35)
