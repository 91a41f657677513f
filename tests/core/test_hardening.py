"""Every input bounded, every refusal clean, what is committed stays committed.

Each test reproduces a way the planner broke before it was hardened (issue 7), then looks at the class of
problem around it.
"""

from __future__ import annotations

import contextlib
import math
import time
import tracemalloc
import warnings

import pytest

from rtgait.core import limits
from rtgait.core.analysis.rollout import rollout
from rtgait.core.geometry.footsteps import Footstep, SoleRect, Stride, Timing
from rtgait.core.planner.online import (
    CommandClampedWarning,
    OnlinePlanner,
    PlannerConfig,
    StepChangeTooLateError,
    StopCancelledWarning,
    straight_walk,
)

SOLE = SoleRect(0.13, 0.10, 0.07, 0.07)


def _snapshot(planner: OnlinePlanner) -> tuple:
    """What a refused call must leave unchanged."""
    walk = planner.walk
    return (
        tuple(planner.footprints()),
        walk.n_steps,
        walk.command,
        walk.finite,
        len(planner.change_log),
        planner.end_time,
    )


# ----- 1. committed stays committed ------------------------------------------------------------------------------
def test_sampling_an_earlier_time_does_not_reopen_a_committed_step():
    cfg = PlannerConfig(timing=Timing(0.8, 0.2), connection="real-time")
    q = OnlinePlanner(cfg, straight_walk(cfg, 6, 0.1))
    q.start(0.0)
    swinging = q.sample(q.phase_start(3) + 0.4)
    q.sample(q.phase_start(3) - 0.05)  # one earlier sample: allowed, but it decides nothing
    before = _snapshot(q)
    with pytest.raises(StepChangeTooLateError):
        q.change_step(2, length=0.4)
    assert _snapshot(q) == before
    again = q.sample(swinging.t)
    assert again.values.tolist() == swinging.values.tolist(), "the swing foot must not move"


@pytest.mark.parametrize("mode", ["real-time", "quasi-real-time"])
def test_first_open_step_never_goes_back(mode):
    cfg = PlannerConfig(timing=Timing(0.7, 0.1), connection=mode)
    p = OnlinePlanner(cfg, straight_walk(cfg, 5, 0.1))
    p.start(0.0)
    latest = 1
    for t in (0.5, 2.3, 1.1, 0.0 + p.phase_start(1), 3.0, 2.0):
        with contextlib.suppress(ValueError):  # before the plan being executed: refused, nothing changes
            p.sample(t)
        assert p.first_open_step() >= latest
        latest = p.first_open_step()


# ----- 2. sizes and times bounded ----------------------------------------------------------------------------------
def test_huge_walks_are_refused_before_any_work():
    cfg = PlannerConfig()
    began = time.process_time()
    with pytest.raises(ValueError, match=str(limits.MAX_STEPS - 1)):
        straight_walk(cfg, 100_000_000, 0.1)
    with pytest.raises(ValueError, match="at most"):
        OnlinePlanner(cfg, [Stride(0.1, 0.19)] * (limits.MAX_STEPS + 1))
    p = OnlinePlanner(cfg, straight_walk(cfg, 3, 0.1))
    p.start(0.0)
    p.sample(0.0)
    with pytest.raises(ValueError, match="at most"):
        p.set_strides([Stride(0.1, 0.19)] * (limits.MAX_STEPS + 1))
    assert time.process_time() - began < 0.5


@pytest.mark.parametrize(
    "kwargs",
    [
        {"settle": 1e6},
        {"double_support": 1e-12},
        {"single_support": 1e-4},
        {"start": math.inf},
        {"end": float("nan")},
    ],
)
def test_timing_out_of_range_is_refused_naming_the_field(kwargs):
    base = {"single_support": 0.8, "double_support": 0.2}
    name = next(iter(kwargs))
    with pytest.raises(ValueError, match=f"timing {name}"):
        Timing(**{**base, **kwargs})


def test_phase_too_long_for_the_pendulum_is_refused_with_the_range():
    # 10 s is a valid duration, but w T = 35 at 0.8 m: the closed form would lose its precision.
    with pytest.raises(ValueError, match=r"timing settle must be at most 5\.\d+ s"):
        PlannerConfig(timing=Timing(0.8, 0.2, settle=10.0))


def test_rollout_with_too_many_ticks_is_refused_before_any_work():
    cfg = PlannerConfig()
    p = OnlinePlanner(cfg, straight_walk(cfg, 20, 0.1))
    began = time.process_time()
    with pytest.raises(ValueError, match="dt"):
        rollout(p, 1e-7, SOLE)
    with pytest.raises(ValueError, match="ticks"):
        rollout(p, 2e-5, SOLE)  # 24.8 s at 20 us: over a million ticks
    assert time.process_time() - began < 0.1
    assert not p.started


def test_sample_at_infinity_or_far_ahead_returns_at_once():
    cfg = PlannerConfig()
    p = OnlinePlanner(cfg, None)
    p.start(0.0)
    p.set_velocity(0.1)
    with pytest.raises(ValueError, match="finite"):
        p.sample(float("inf"))
    began = time.process_time()
    with pytest.raises(ValueError, match="at least once per step"):
        p.sample(1e4)
    # Walking the plan out to 1e4 s step by step costs about 1.8 s of CPU; a refusal is microseconds. The process's
    # CPU time, not the wall clock, so that other processes on a loaded machine do not count.
    assert time.process_time() - began < 0.2
    p.sample(0.5)  # the planner is still usable
    finite = OnlinePlanner(cfg, straight_walk(cfg, 200, 0.05))
    finite.start(0.0)
    with pytest.raises(ValueError, match="at least once per step"):
        finite.sample(finite.end_time)


def test_horizon_bounded():
    with pytest.raises(ValueError, match="horizon_steps"):
        PlannerConfig(horizon_steps=limits.MAX_HORIZON_STEPS + 1)
    PlannerConfig(horizon_steps=limits.MAX_HORIZON_STEPS)


# ----- 3. physical ranges -----------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"cog_height": 1e-6}, "cog_height"),
        ({"cog_height": 1e3}, "cog_height"),
        ({"gravity": 1e9}, "gravity"),
        ({"gravity": 1e-3}, "gravity"),
        ({"step_width": 5.0}, "step_width"),
        ({"max_step_turn": 2.0}, "max_step_turn"),
        ({"step_height": -0.1}, "step_height"),
    ],
)
def test_physical_ranges_are_checked_where_they_enter(kwargs, field):
    with pytest.raises(ValueError, match=rf"{field} must be within [\[(]"):
        PlannerConfig(**kwargs)


def test_absurd_strides_are_refused():
    with pytest.raises(ValueError, match="at most"):
        Stride(50.0, 0.19)


# ----- 4. set_footsteps once everything is committed ---------------------------------------------------------------
def test_set_footsteps_when_every_step_is_committed_is_too_late():
    config = PlannerConfig(timing=Timing(0.8, 0.2), connection="quasi-real-time")
    p = OnlinePlanner(config, straight_walk(config, steps=1, step_length=0.1))
    p.start(0.0)
    p.sample(p.phase_start(4))
    prints = p.footprints()
    before = _snapshot(p)
    with pytest.raises(StepChangeTooLateError):
        p.set_footsteps([*prints[2:], prints[-1]])
    assert _snapshot(p) == before


def test_set_footsteps_with_every_given_step_committed_is_too_late():
    config = PlannerConfig(timing=Timing(0.8, 0.2), connection="real-time")
    p = OnlinePlanner(config, straight_walk(config, steps=6, step_length=0.1))
    p.start(0.0)
    p.sample(p.phase_start(7))  # steps 1..4 committed in real-time mode
    prints = p.footprints()
    before = _snapshot(p)
    with pytest.raises(StepChangeTooLateError, match="committed"):
        p.set_footsteps(prints[2:5])  # steps 1..3 only
    assert _snapshot(p) == before


# ----- 8. the walk ends at rest ------------------------------------------------------------------------------------
@pytest.mark.parametrize("settle", [0.1, 0.3, 2.0])
def test_walk_ends_at_rest_whatever_the_settle_time(settle):
    cfg = PlannerConfig(timing=Timing(0.8, 0.2, settle=settle))
    p = OnlinePlanner(cfg, straight_walk(cfg, 4, 0.15))
    result = rollout(p, 0.005, SOLE)
    end = p.sample(p.end_time)
    assert abs(end.cog_vel[:2]).max() < 1e-9
    assert abs(end.cog_acc[:2]).max() < 1e-9
    last = p.footprints()[-2:]
    assert end.cog[:2] == pytest.approx([0.5 * (last[0].x + last[1].x), 0.5 * (last[0].y + last[1].y)], abs=1e-9)
    after = p.sample(p.end_time + 5.0)
    assert after.values == pytest.approx(end.values, abs=1e-9), "after the end the planner holds the state at rest"
    assert result.zmp_margin_min > 0.0


# ----- 9. memory stays flat ----------------------------------------------------------------------------------------
def test_endless_walk_keeps_bounded_history():
    cfg = PlannerConfig(timing=Timing(0.3, 0.1, start=0.3), history_steps=16)
    p = OnlinePlanner(cfg, None)
    p.start(0.0)
    p.set_velocity(0.2, 0.0, 0.1)
    dt = 0.01
    t = 0.0

    def walk_for(seconds: float) -> None:
        nonlocal t
        end = t + seconds
        while t < end:
            p.sample(t)
            t += dt

    walk_for(20.0)  # warm up: caches, the first history
    tracemalloc.start()
    walk_for(1.0)
    first, _ = tracemalloc.get_traced_memory()
    walk_for(60.0)  # 150 more steps
    second, _ = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert len(p.footprints()) <= 2 * 16 + 8
    assert len(p.plans) <= 16 and len(p.change_log) <= 16
    assert second - first < 20_000, f"memory grew by {second - first} bytes over 150 steps"


# ----- 10. surprises are said ----------------------------------------------------------------------------------------
def test_clamped_velocity_command_warns():
    cfg = PlannerConfig(max_step_length=0.3)
    p = OnlinePlanner(cfg, None)
    p.start(0.0)
    with pytest.warns(CommandClampedWarning, match="clamped"):
        p.set_velocity(2.0)  # 2 m/s over a 1 s step period: 2 m per step
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        p.set_velocity(0.2)  # within the limits: silent


def test_velocity_after_stop_warns_and_walks_on():
    cfg = PlannerConfig()
    p = OnlinePlanner(cfg, None)
    p.start(0.0)
    p.set_velocity(0.2)
    p.sample(0.5)
    p.stop()
    assert p.n_steps is not None
    with pytest.warns(StopCancelledWarning):
        p.set_velocity(0.2)
    assert p.n_steps is None


def test_rejected_start_changes_nothing():
    cfg = PlannerConfig()
    p = OnlinePlanner(cfg, straight_walk(cfg, 3, 0.1))
    before = tuple(p.footprints())
    with pytest.raises(ValueError, match="cog"):
        p.start(0.0, feet=(Footstep(1, 1, 0, "left"), Footstep(1, 0.8, 0, "right")), cog=(math.nan, 0.0))
    assert tuple(p.footprints()) == before
    assert not p.started
