"""The multibody ZMP of the commanded motion in a walk that re-anchors its landings: no spike where the controller
moves a target at once, the finite-difference ZMP wherever the commanded motion is smooth, and the re-anchored
swings left out."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")

from rtgait.robot.dynamics import multibody_check
from rtgait.sim.commanded_motion import reanchoring_mask, retarget_ticks


@pytest.fixture(scope="module")
def measured(short_walk):
    """The shared short walk: its result, the ticks of its retargeting, the new measure and the finite-difference
    multibody ZMP of its commanded motion across everything (with the same off-the-ground rule)."""
    _, result = short_walk
    ticks = retarget_ticks(result.times, result.events, result.control_dt)
    times = result.run_start + np.arange(len(result.times)) * result.control_dt
    check = multibody_check(result.model, times, result.commanded_q)
    across = np.array(check.zmp)
    weight = result.mass * result.gravity
    across[~(np.abs(check.vertical_force - weight) < 0.9 * weight)] = np.nan
    return result, ticks, result.zmp_commanded_motion, across


def test_a_reanchoring_makes_no_spike(measured):
    # The late landings re-anchor a foot the servos had a few millimetres from its target, and the replans that
    # follow move the COM target: across those ticks the second differences put the ZMP metres from the measured
    # one (4.5 m and 10.8 m in this walk). Differentiated on either side of the jump, it is no further than at the
    # ticks around (0.2 to 0.9 m: double support, the late foot coming down), and in the single supports that the
    # error measures take it stays within decimetres.
    result, ticks, zmp, across = measured
    late = [_tick(result, e.t) for e in result.events if e.kind == "landing" and e.detail == "late"]
    assert len(late) == 2 and set(late) <= set(ticks), "precondition: two late landings, each a retargeting"
    distance = np.hypot(*(result.zmp - zmp).T)
    spiked = np.hypot(*(result.zmp - across).T)
    for k in late:
        assert spiked[k - 1 : k + 1].max() > 3.0, "precondition: a jump at the landing"
        assert distance[k - 1 : k + 1].max() < 1.5 * distance[[k - 2, k + 1]].max(), result.times[k]
    walk = result.times >= 0.0
    assert np.nanmax(distance[walk & result.commanded_motion_mask]) < 0.5


def test_it_is_the_finite_difference_zmp_where_the_motion_is_smooth(measured):
    # Away from the retargeting ticks (the one before each, where the difference would span the jump, and the tick
    # itself) and the re-anchored swings, the measure is the finite-difference multibody ZMP to the bit.
    result, ticks, zmp, across = measured
    near = np.zeros(len(result.times), dtype=bool)
    for k in ticks:
        near[k - 1 : k + 1] = True
    smooth = ~near & ~result.reanchored_swings
    assert smooth.mean() > 0.97
    np.testing.assert_array_equal(zmp[smooth], across[smooth])
    assert np.isnan(zmp[result.reanchored_swings]).all()


def test_the_reanchored_swings_run_from_a_touchdown_to_the_double_support(measured):
    result, _, _, _ = measured
    swings = result.reanchored_swings
    starts = np.flatnonzero(np.diff(swings.astype(int)) == 1) + 1
    ends = np.flatnonzero(np.diff(swings.astype(int)) == -1)
    early_or_on_time = [e for e in result.events if e.kind == "touchdown" and result.support[_tick(result, e.t)] != 0]
    assert len(starts) == len(ends) == len(early_or_on_time) == 3
    for start, end, event in zip(starts, ends, early_or_on_time, strict=True):
        assert result.times[start] == pytest.approx(event.t)
        assert result.support[end] == 0 and (result.support[start:end] != 0).all()  # through the first double tick
    errors = result.zmp_errors()["vs_commanded_motion"]
    assert errors["reanchored_ticks"] == int((swings & result.commanded_motion_mask).sum()) > 0
    assert errors["ticks"] == int((result.commanded_motion_mask & np.isfinite(result.zmp_commanded_motion[:, 0])).sum())
    # A touch-down of a foot the plan has standing re-anchors a loaded foot: a jump at one tick, not a swing.
    standing = np.zeros((len(result.times), 2), dtype=bool)
    assert not reanchoring_mask(result.times, standing, result.events, result.control_dt).any()


def _tick(result, t: float) -> int:
    return int(np.searchsorted(result.times, t - 0.5 * result.control_dt))
