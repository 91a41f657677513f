"""A re-anchored landing in physics: the loaded foot's IK target does not step; the commanded-motion ZMP measure of
a run that fell ends where the fall began."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")

from rtgait.sim.result import FALL_MARGIN


@pytest.fixture(scope="module")
def blended_walk(short_walk, talos, talos_sim):
    """The shared short walk again with ``ControllerOptions(anchor_blend=0.04)`` (off by default)."""
    from rtgait.control.controller import ControllerOptions
    from rtgait.io.sim_run import simulate

    scenario, _ = short_walk
    return simulate(scenario, talos, sim=talos_sim, controller_options=ControllerOptions(anchor_blend=0.04))


def _largest_loaded_step(result) -> tuple[float, float]:
    """The largest move of a loaded foot's IK target in one tick of the walk: horizontal (m) and in yaw (rad)."""
    log = result.log
    step = np.hypot(*np.diff(log.foot_target[:, :, :2], axis=0).transpose(2, 0, 1))  # (k - 1, 2) (m)
    loaded = log.loaded[1:] & (result.times[1:, None] >= 0.0)  # loaded at the tick it moved to
    assert loaded.sum() > 0.5 * loaded.size
    turn = np.abs(np.diff(log.foot_target[:, :, 3], axis=0))
    return float(step[loaded].max()), float(turn[loaded].max())


def test_a_loaded_foots_ik_target_does_not_step(short_walk, blended_walk):
    # Talos re-anchors every landing on its measured pose, a millimetre or two from the target the servos lagged
    # behind (one step of 1.6 mm in this walk when moved at once, the default). With the blend
    # (ControllerOptions.anchor_blend: 15/8 of such a jump per 40 ticks, under 0.1 mm) and the plan's last
    # millimetres of a swing that touched down on time (0.1 mm per tick), a loaded foot's target never moves by a
    # millimetre in a tick.
    assert sum(e.kind == "touchdown" for e in blended_walk.events) >= 4, "the walk re-anchors its landings"
    step, turn = _largest_loaded_step(blended_walk)
    assert step < 0.5e-3 and turn < 0.5e-3
    assert _largest_loaded_step(short_walk[1])[0] > 1e-3, "at once, the re-anchoring steps the target"


def test_the_commanded_motion_measure_of_a_fall_ends_at_the_tip_over(short_walk):
    # The same walk's record as if it had tipped at 1.2 s and fallen at 2.5 s: the commanded-motion measure stops
    # at the tip-over, the other two 0.5 s before the fall; had it tipped and stood, nothing is cut.
    _, result = short_walk
    fell = dataclasses.replace(result, fell=True, fall_time=2.5, tipped=True, tip_time=1.2)
    walk = (result.support != 0) & np.isfinite(result.zmp[:, 0]) & (result.times >= 0.0)
    assert np.array_equal(fell.single_support_mask, walk & (result.times <= 2.5 - FALL_MARGIN))
    assert np.array_equal(fell.commanded_motion_mask, walk & (result.times < 1.2))
    errors = fell.zmp_errors()
    for name, reference, kept in (
        ("vs_commanded_motion", result.zmp_commanded_motion, walk & (result.times < 1.2)),
        ("vs_plan", result.zmp_planned, walk & (result.times <= 2.0)),
    ):
        kept = kept & np.isfinite(reference[:, 0])
        distance = np.linalg.norm(result.zmp[kept] - reference[kept], axis=1)
        assert errors[name]["rms"] == pytest.approx(np.sqrt(np.mean(distance**2)), rel=1e-12)
        assert errors[name]["max"] == pytest.approx(distance.max(), rel=1e-12)
    stood = dataclasses.replace(result, tipped=True, tip_time=1.2)
    assert np.array_equal(stood.commanded_motion_mask, stood.single_support_mask)
    assert np.array_equal(stood.single_support_mask, walk & (result.times <= result.walk_end))
