"""The support height before a step down (rtgait.core.geometry.support_height): a stance whose swing lands on a lower
stair tread holds the VRP half a riser lower, so the COG comes down during that single support, and the full ZMP
equation errs by exactly the term the method predicts (docs/method.md eq. 4); every other stance is unchanged."""

from __future__ import annotations

import numpy as np
import pytest

from rtgait.core.analysis.height_error import zmp_error
from rtgait.core.analysis.rollout import rollout
from rtgait.core.geometry.footsteps import Footstep
from rtgait.core.geometry.support_height import DESCENT_SHARE, stance_support_height
from rtgait.core.planner.online import OnlinePlanner
from rtgait.scenario.loading import load_scenario


def _foot(z: float, pitch: float = 0.0, x: float = 0.0) -> Footstep:
    return Footstep(x, 0.0, 0.0, "left", z, pitch, 0.0)


def test_only_a_stair_down_lowers_the_stance() -> None:
    assert stance_support_height(_foot(0.3), _foot(0.15)) == pytest.approx(0.3 - DESCENT_SHARE * 0.15)
    assert DESCENT_SHARE == 0.5  # the riser split evenly between the legs
    assert stance_support_height(_foot(0.3), _foot(0.45)) == 0.3  # a step up
    assert stance_support_height(_foot(0.3), _foot(0.3)) == 0.3  # level
    assert stance_support_height(_foot(0.3), _foot(0.295)) == 0.3  # below MIN_RISE: walked as on the flat
    assert stance_support_height(_foot(0.3, -0.17), _foot(0.25, -0.17)) == 0.3  # a ramp's footholds
    assert stance_support_height(_foot(0.3), None) == 0.3  # the next foothold not known yet


def _walk(name: str):
    scenario = load_scenario(name)
    planner = OnlinePlanner(scenario.planner_config(), scenario.strides())
    return scenario, planner, rollout(planner, scenario.dt, scenario.sole, scenario.changes)


def test_down_the_stairs_the_cog_obeys_the_pendulum_about_the_lowered_support_height() -> None:
    scenario, planner, result = _walk("stairs-down")
    w2 = planner.w**2
    cz, az = result.column("cog_z"), result.column("cog_az")
    prints = result.footprints
    single = np.flatnonzero(result.support != "double")
    expected = []
    for k in single:
        q = int(result.phase[k])  # single support 2i - 1: stance F[i], its swing lands on F[i + 1]
        stance, landing = prints[(q + 1) // 2], prints[(q + 1) // 2 + 1]
        drop = min(0.0, landing.z - stance.z)
        expected.append(stance.z + (0.5 * drop if drop <= -0.01 else 0.0))
    # c_z - c_z'' / w^2 = h + zc with h from the footholds alone (an independent truth).
    np.testing.assert_allclose(cz[single] - az[single] / w2, np.array(expected) + scenario.cog_height, atol=1e-9)
    lowered = np.array(expected) < np.array([prints[(int(result.phase[k]) + 1) // 2].z for k in single]) - 1e-9
    assert lowered.sum() > 0.5 * len(single)  # most single supports are on a tread before a step down
    # It still ends at rest zc above the bottom.
    assert cz[-1] == pytest.approx(scenario.cog_height - 0.9, abs=1e-6)


def test_the_full_zmp_error_of_a_lowered_stance_is_the_method_s_term() -> None:
    scenario, _, result = _walk("stairs-down")
    error = zmp_error(result, scenario.terrain.terrain, scenario.gravity)
    acc = np.hypot(result.column("cog_ax"), result.column("cog_ay"))
    predicted = 0.5 * 0.15 * acc / (scenario.gravity + result.column("cog_az"))  # |p_z - h| |c''_xy| / (c_z'' + g)
    prints = result.footprints
    for k in np.flatnonzero(result.support != "double"):
        q = int(result.phase[k])
        stance, landing = prints[(q + 1) // 2], prints[(q + 1) // 2 + 1]
        if landing.z < stance.z - 0.01:
            assert error[k] == pytest.approx(predicted[k], abs=1e-6)
        else:
            assert error[k] < 1e-9  # no step down after it (the last tread): the VRP on the stance's surface
    assert 0.005 < error.max() < 0.012  # millimetres, inside the 65 mm ZMP margin: no compensation needed


def test_stairs_up_are_unchanged() -> None:
    # Up the stairs no stance is followed by a step down: the support height is the stance's height throughout.
    scenario, planner, result = _walk("stairs-up")
    single = result.support != "double"
    stance_z = np.array([result.contacts[int(q)][0].z for q in result.phase[single]])
    cz, az = result.column("cog_z"), result.column("cog_az")
    np.testing.assert_allclose((cz - az / planner.w**2)[single], stance_z + scenario.cog_height, atol=1e-9)


def test_a_stance_at_the_horizon_s_end_is_lowered_whatever_the_walk_has_made_so_far() -> None:
    # The footprints are made lazily; the last stance of a plan must still see where its swing lands. A run whose
    # footprints were all made first (as the walking stack does) plans the same COG height to the last bit.
    scenario = load_scenario("stairs-down")
    runs = []
    for made_first in (False, True):
        planner = OnlinePlanner(scenario.planner_config(), scenario.strides())
        if made_first:
            planner.walk.footprints()
        runs.append(rollout(planner, scenario.dt, scenario.sole, scenario.changes).column("cog_z"))
    np.testing.assert_array_equal(runs[0], runs[1])
