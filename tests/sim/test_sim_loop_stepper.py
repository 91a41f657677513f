"""The closed loop as a stepper (:class:`rtgait.sim.loop.ClosedLoop`): stepped by hand it gives exactly what
``run_sim_loop`` gives; a ring record keeps the last ticks of the whole record, bounded however long the run;
a push given while walking acts for its duration even when the applied forces are cleared between ticks."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")

from rtgait.control.controller import make_controller
from rtgait.core.analysis.rollout import ScheduledChange
from rtgait.core.push import Push
from rtgait.robot.controller_info import robot_info
from rtgait.robot.motion import robot_scenario
from rtgait.sim.loop import ClosedLoop, LoopOptions, SimResult
from rtgait.sim.run_loop import run_sim_loop

QUICK = LoopOptions(start_ramp=0.5, start_hold=0.3, after=0.3)
# Fields that are not the run's outcome: the clock, and the Pinocchio model (an object, the same one each time).
NOT_COMPARED = {"wall_time", "model"}


def controller(talos, talos_sim, shorten, level="adaptive", steps=3):
    """A controller of ``level`` for fig8 cut to ``steps`` steps (its last one lengthened), as simulate makes it."""
    walk = robot_scenario(shorten("fig8", steps, (ScheduledChange(steps, length=0.12),)), talos)
    info = robot_info(talos)
    made = make_controller(level, walk.planner_config(), walk.strides(), walk.sole, info, dt=talos_sim.control_dt)
    return made, walk


def assert_same(a: SimResult, b: SimResult) -> None:
    """Every field of two results equal: arrays element for element (NaN where NaN), the rest by value."""
    for field in dataclasses.fields(SimResult):
        if field.name in NOT_COMPARED:
            continue
        x, y = getattr(a, field.name), getattr(b, field.name)
        if isinstance(x, np.ndarray):
            assert x.shape == y.shape and x.dtype == y.dtype, field.name
            assert np.array_equal(x, y, equal_nan=True), field.name
        else:
            assert repr(x) == repr(y), field.name


def test_the_stepper_driven_by_hand_gives_run_sim_loop_s_result(talos, talos_sim, shorten):
    """A short Talos walk with a footstep change and a push: array for array the same."""
    level, walk = controller(talos, talos_sim, shorten)
    options = dataclasses.replace(QUICK, changes=walk.changes, pushes=(Push(1.2, 0.1, (0.0, 40.0, 0.0)),))
    whole = run_sim_loop(talos_sim, level, options)
    assert not whole.fell and whole.steps_completed == whole.steps_planned >= 3
    assert whole.events and whole.replans > 1, "the walk exercised the adaptive level"

    level, _ = controller(talos, talos_sim, shorten)
    loop = ClosedLoop(talos_sim, level, options)
    assert loop.n_ticks == len(whole.times)
    seen = []
    while not loop.done:
        assert loop.step()
        seen.append(loop.last)
    by_hand = loop.result()
    assert_same(whole, by_hand)
    # The last tick's values are the record's.
    times = np.array([v.t for v in seen])
    assert np.array_equal(times, whole.times)
    assert np.array_equal(np.array([v.zmp_planned for v in seen]), whole.zmp_planned)
    assert np.array_equal(np.array([v.dcm for v in seen]), whole.dcm, equal_nan=True)
    assert np.array_equal(np.array([v.zmp_measured for v in seen]), whole.zmp, equal_nan=True)
    assert np.array_equal(np.array([v.cog_target for v in seen]), whole.cog_planned)
    with pytest.raises(RuntimeError, match="over"):
        loop.step()


def test_a_ring_record_keeps_the_last_ticks_of_the_whole_record(talos, talos_sim, shorten):
    """keep=0.5 s: the result is the last 500 ticks of the whole record (and the replay frames among them)."""
    level, _ = controller(talos, talos_sim, shorten, level="stabilized", steps=2)
    whole = run_sim_loop(talos_sim, level, QUICK)
    level, _ = controller(talos, talos_sim, shorten, level="stabilized", steps=2)
    loop = ClosedLoop(talos_sim, level, QUICK, keep=0.5)
    while not loop.done:
        loop.step()
    ring = loop.result()
    n = round(0.5 / talos_sim.control_dt)
    assert loop.record.capacity == n and len(ring.times) == n < len(whole.times)
    for field in dataclasses.fields(SimResult):
        x = getattr(whole, field.name)
        if isinstance(x, np.ndarray) and x.shape[:1] == whole.times.shape and field.name != "replay_index":
            assert np.array_equal(getattr(ring, field.name), x[-n:], equal_nan=True), field.name
    first = len(whole.times) - n
    kept = whole.replay_index >= first
    assert np.array_equal(ring.replay_index, whole.replay_index[kept] - first)
    assert np.array_equal(ring.replay_q, whole.replay_q[kept])
    assert np.array_equal(ring.replay_soles, whole.replay_soles[kept])
    assert ring.run_start == whole.times[first]
    assert ring.steps_completed == whole.steps_completed and not ring.fell


def test_an_open_ended_walk_by_command_has_bounded_memory(talos, talos_sim):
    """No end, no stop: it walks as long as it is stepped, the record stays at its ring's size."""
    from rtgait.scenario.loading import load_scenario

    walk = robot_scenario(load_scenario("fig8"), talos)
    info = robot_info(talos)
    level = make_controller("adaptive", walk.planner_config(), None, walk.sole, info, dt=talos_sim.control_dt)
    level.planner.set_velocity(0.1, 0.0, 0.0)
    with pytest.raises(ValueError, match=r"needs LoopOptions\.stop_after_steps or duration"):
        ClosedLoop(talos_sim, level, QUICK)
    loop = ClosedLoop(talos_sim, level, QUICK, keep=0.2)
    assert loop.n_ticks is None
    arrays = [loop.record.planned, loop.record.commanded, loop.record.replay_qpos]
    sizes = [a.nbytes for a in arrays]
    for _ in range(round(3.5 / talos_sim.control_dt)):
        assert loop.step()
    assert not loop.done
    assert [a.nbytes for a in arrays] == sizes, "nothing grew"
    result = loop.result()
    assert len(result.times) == round(0.2 / talos_sim.control_dt)
    assert result.times[-1] == pytest.approx(loop.t) and result.walk_end == loop.t
    assert loop.base_position[0] > 0.05, "it walked forward"
    with pytest.raises(ValueError, match="keep"):
        ClosedLoop(talos_sim, level, QUICK, keep=-1.0)


def test_a_live_push_acts_for_its_duration_even_if_the_forces_are_cleared(talos, talos_sim, shorten):
    """MuJoCo's passive viewer zeroes xfrc_applied at every sync: the push is written every tick it lasts."""
    level, _ = controller(talos, talos_sim, shorten, level="stabilized", steps=2)
    applied = []
    base = talos_sim.base_body
    options = dataclasses.replace(QUICK, on_tick=lambda t, data: applied.append(data.xfrc_applied[base, 1]))
    loop = ClosedLoop(talos_sim, level, options, keep=0.0)
    while loop.t < 1.0:
        loop.step()
    push = loop.push((0.0, 30.0, 0.0), duration=0.1)
    assert push.start == pytest.approx(loop.t + talos_sim.control_dt)
    assert loop.push_acting == (0.0, 30.0, 0.0)
    before = len(applied)
    while loop.t < 1.5:
        loop.step()
        loop.data.xfrc_applied[:] = 0.0  # as the viewer's sync does
    pushed = np.array(applied[before:])
    assert np.count_nonzero(pushed == 30.0) == round(0.1 / talos_sim.control_dt)
    assert np.count_nonzero(pushed) == np.count_nonzero(pushed == 30.0)
    assert loop.push_acting is None
    assert loop.result().pushes[-1] == push
    with pytest.raises(ValueError, match="no such body"):
        loop.push((1.0, 0.0, 0.0), body="no_such_body")
    with pytest.raises(ValueError, match="exceeds"):
        loop.push((1e7, 0.0, 0.0))
    assert math.isfinite(loop.result().wall_time)


def test_the_measurement_reads_the_contacts_the_last_tick_read_of_the_same_state(talos, talos_sim, shorten):
    """With one physics step a control period, the controller's measurement reuses the contacts and sites the last
    tick's record read after its step, and the subtree velocities its complete log computed: nothing between the two
    may change them (a push acting included)."""
    import mujoco

    from rtgait.sim.step_snapshot import read_snapshot

    assert talos_sim.substeps == 1
    level, walk = controller(talos, talos_sim, shorten, steps=2)
    options = dataclasses.replace(QUICK, changes=walk.changes, pushes=(Push(0.9, 0.1, (0.0, 40.0, 0.0)),))
    loop = ClosedLoop(talos_sim, level, options)
    checked = 0
    while loop.step():
        if loop.done:
            break
        assert loop.robot.last_contacts is not None
        kept, sums = loop.robot.last_contacts
        assert read_snapshot(loop.data) == kept
        assert loop.robot.reader.contacts.read(loop.data, kept) == sums
        velocities = loop.data.subtree_linvel.copy()
        mujoco.mj_subtreeVel(talos_sim.model, loop.data)
        assert np.array_equal(loop.data.subtree_linvel, velocities)
        checked += 1
    assert checked == loop.k - 1 and kept.addresses, "ticks checked, with contacts"
