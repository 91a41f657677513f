"""A walk onto terrain in physics (CI-fast): Talos walks six steps up the 10 degree ramp of ``slope-up`` (and down
``slope-down``'s) on the estimated state, its soles turned to the ramp, and ends at rest on it, its COG risen (gone
down) with the footholds."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")

from rtgait.io.sim_run import simulate


def test_talos_walks_up_the_ramp_and_stands_on_it(talos, shorten) -> None:
    scenario = shorten("slope-up", 6)  # the ramp from x = 0.5 m: steps 3 to 6 land on it, the closing step too
    result = simulate(scenario, talos)
    assert result.state == "estimated"
    assert not result.fell and result.steps_completed == 7
    assert result.ended_at_rest, "at rest with both soles flat on the ramp"
    assert result.tip_time is None, "no loaded sole turned off the surface under it"
    last = result.footprints[-1]
    # About x = 1.2 m, 0.7 m up the ramp, at the ramp's height under it (re-anchored where it landed).
    assert last.x == pytest.approx(1.2, abs=0.01)
    assert last.z == pytest.approx(math.tan(math.radians(10.0)) * (last.x - 0.5), abs=1e-3)
    assert last.pitch == pytest.approx(-math.radians(10.0))
    # The COG rose with the footholds: within 1 cm of their height gain (its height above them is the nominal one).
    start = int(np.searchsorted(result.times, 0.0))  # the walk's start, after the transition from half-sitting
    rise = result.cog[-1, 2] - result.cog[start, 2]
    assert rise == pytest.approx(last.z, abs=0.01)
    # The soles lie on the ramp: tilted by its 10 degrees (within the 0.02 rad of ended_at_rest).
    np.testing.assert_allclose(result.sole_tilt[-1], math.radians(10.0), atol=0.02)


def test_talos_meets_the_unseen_step_short_of_its_foothold_and_walks_onto_it(talos, shorten) -> None:
    # The plan walks flat; the 3 cm step at x = 0.7 m is only in the scene. The swing onto it (step 4, planned at
    # x = 0.8 m) touches it early, short of its foothold: the foot skims on to the foothold at the height it met
    # (rtgait.control.landings) instead of standing on the edge.
    scenario = shorten("unseen-step", 6)
    result = simulate(scenario, talos)
    assert result.state == "estimated"
    skims = [event for event in result.events if event.kind == "touchdown-skimmed"]
    assert skims, "the step met short of a foothold"
    assert all(0.0 < float(event.detail.split()[0]) <= 0.05 for event in skims)  # m above the foothold
    assert not result.fell and result.steps_completed == 7
    assert result.ended_at_rest and result.tip_time is None


def test_talos_climbs_stairs_and_ends_at_rest_on_a_tread(talos, shorten) -> None:
    # 15 cm risers: each landing is up to 0.15 m above the stance sole, far beyond the landing gate's 35 mm for an
    # unplanned step; the planned rise under the feet lets it land (rtgait.core.geometry.ground_height).
    scenario = shorten("stairs-up", 5)
    result = simulate(scenario, talos)
    assert result.state == "estimated"
    assert not result.fell and result.steps_completed == result.steps_planned
    assert result.ended_at_rest
    last = result.footprints[-1]
    assert last.z >= 0.3 - 1e-9, "at least two treads up"
    start = int(np.searchsorted(result.times, 0.0))
    assert result.cog[-1, 2] - result.cog[start, 2] == pytest.approx(last.z, abs=0.01)


def test_talos_walks_down_the_ramp_and_stands_on_it(talos, shorten) -> None:
    # Steps 3 to 6 land down the ramp from x = 0.5 m, the closing step too. A late landing's ground taken as its
    # measured height over the plan (the foothold's own depth) sank every stance target into the ramp, and the
    # estimator took the whipped late foot for a landing 16 mm above the ramp: the foot tipped at 5.4 s.
    scenario = shorten("slope-down", 6)
    result = simulate(scenario, talos)
    assert result.state == "estimated"
    assert not result.fell and result.steps_completed == 7
    assert result.ended_at_rest and result.tip_time is None
    last = result.footprints[-1]
    assert last.x == pytest.approx(1.2, abs=0.01)  # 0.7 m down the ramp, at the ramp's height under it
    assert last.z == pytest.approx(-math.tan(math.radians(10.0)) * (last.x - 0.5), abs=1e-3)
    start = int(np.searchsorted(result.times, 0.0))
    assert result.cog[-1, 2] - result.cog[start, 2] == pytest.approx(last.z, abs=0.01)
    np.testing.assert_allclose(result.sole_tilt[-1], math.radians(10.0), atol=0.02)
