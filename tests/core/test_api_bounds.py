"""The closed-loop API against whatever a sensor says: every argument bounded, a refused call changes nothing.

Two parts. Focused cases, one per way the planner broke when a user fuzzed it: a landing 1e9 m away, a
COM at 1e300 m, a landing turned 2.5 rad, a flat support polygon (Qhull's "initial simplex is flat"), the IndexError of
a timing-adapted emergency stop, a refused landing that had already retargeted the walk; and each entry point's
bounds. Then random call streams at 1 kHz (numpy Generator, fixed seeds) mixing every closed-loop call with NaN,
infinities, huge finite values and plausible ones, on twin planners: planner A gets every call, planner B only those
A accepted, and their samples must agree at every tick (bit for bit), so a refused call provably left no trace in
what the planner will do. Checked too: only the documented errors, A's observable state unchanged by each refusal,
no NaN in any sample, no call slow enough to be a hang.
"""

from __future__ import annotations

import contextlib
import math
import signal
import time
import warnings

import numpy as np
import pytest

from rtgait.core import InputOutOfBoundsError as ReExported
from rtgait.core.geometry.footsteps import Footstep, SoleRect, Stride, Timing
from rtgait.core.geometry.support import signed_margin, support_polygon
from rtgait.core.input_bounds import (
    COM_REACH_HEIGHTS,
    COM_SPEED_FROUDE,
    LANDING_TOLERANCE,
    MAX_POSITION,
    InputOutOfBoundsError,
)
from rtgait.core.laws.stepping import StepAdjustment
from rtgait.core.planner.online import (
    CommandClampedWarning,
    OnlinePlanner,
    PlannerConfig,
    StepChangeTooLateError,
    StopCancelledWarning,
    straight_walk,
)

SOLE = SoleRect(0.13, 0.10, 0.07, 0.07)
DT = 0.001
DOCUMENTED = (InputOutOfBoundsError, StepChangeTooLateError)
WARNINGS = (CommandClampedWarning, StopCancelledWarning)


def _observable(planner: OnlinePlanner) -> tuple:
    """What a refused call must leave as it was: the walk (footprints up to a few steps ahead, timeline, command,
    what is reached), the plans made (their records, but for the wall time), the changes and step adjustments logged,
    the latest time sampled and the next replan."""
    walk = planner.walk
    upto = planner.first_open_step() + 4
    if walk.n_steps is not None:
        upto = min(upto, walk.n_steps + 1)
    timeline = planner.timeline
    return (
        tuple(walk.footprints(upto)), walk.base, walk.n_steps, walk.command, walk.finite, walk.stopping,
        walk.latest_phase, timeline.step_timings, tuple(timeline.start_time(q) for q in range(upto * 2)),
        tuple(record._replace(compute_time=0.0) for record in planner.plans), planner.replan_count,
        tuple(planner.change_log), tuple(planner.step_adjustments), planner.step_adjustment_count,
        planner.latest_time, planner.next_replan_phase, planner.t0,
    )  # fmt: skip


def _walked(config: PlannerConfig, t_end: float, steps: int = 8, observe: bool = False) -> tuple[OnlinePlanner, float]:
    planner = OnlinePlanner(config, straight_walk(config, steps, 0.1))
    planner.start(0.0)
    t = 0.0
    while t < t_end:
        s = planner.sample(t)
        if observe:
            planner.observe(t, s.cog[:2], s.cog_vel[:2])
        t = round(t + DT, 9)
    return planner, t


def _refused(planner: OnlinePlanner, call, match: str) -> None:
    """``call`` raises the bounds error with ``match`` in its message and leaves the planner as it was."""
    before = _observable(planner)
    with pytest.raises(InputOutOfBoundsError, match=match):
        call()
    assert _observable(planner) == before, "a refused call changed the planner"


# ----- the cases found by fuzzing ------------------------------------------------------------------------------------
def test_the_error_is_a_value_error_exported_with_the_planner():
    assert issubclass(InputOutOfBoundsError, ValueError) and ReExported is InputOutOfBoundsError


def test_a_landing_a_billion_metres_away_is_refused():
    planner, _ = _walked(PlannerConfig(), 1.3)
    twin, _ = _walked(PlannerConfig(), 1.3)
    _refused(planner, lambda: planner.touchdown(1.31, "left", 1e9, 0.095, 0.0), r"touchdown \(x, y\).*1e\+06 m")
    # Finite and within MAX_POSITION, but 1.5 m beyond the stance foot: outside the landing box.
    _refused(planner, lambda: planner.touchdown(1.31, "right", 1.5, -0.095, 0.0), "along the stance foot")
    assert planner.sample(1.32).values.tolist() == twin.sample(1.32).values.tolist()


def test_a_com_at_1e300_is_refused_and_the_replan_after_it_is_unaffected():
    config = PlannerConfig(feedback="measured")
    planner, t = _walked(config, 1.3)
    twin, _ = _walked(config, 1.3)
    _refused(planner, lambda: planner.observe(t, (1e300, 0.0), (0.0, 0.0)), "cog .* must be within")
    _refused(planner, lambda: planner.observe(t, (0.0, 0.0), (50.0, 0.0)), "cog_vel .* at most")
    _refused(planner, lambda: planner.observe(math.nan, (0.0, 0.0), (0.0, 0.0)), "finite")
    planner.replan_now(t)
    twin.replan_now(t)
    assert planner.sample(t + 0.1).values.tolist() == twin.sample(t + 0.1).values.tolist()
    assert abs(planner.sample(t + 0.1).cog[0]) < 1.0


def test_the_com_bounds_follow_the_configuration_and_take_a_push():
    config = PlannerConfig(feedback="measured", cog_height=0.8)
    planner, t = _walked(config, 1.3)
    s = planner.sample(t)
    speed = COM_SPEED_FROUDE * math.sqrt(config.gravity * config.cog_height)
    planner.observe(t, s.cog[:2], (0.99 * speed, 0.0))  # a violent push, still a push
    _refused(planner, lambda: planner.observe(t, s.cog[:2], (1.01 * speed, 0.0)), "cog_vel")
    stance = planner.walk.footprint(1)  # single support of step 1 on F[1]
    reach = COM_REACH_HEIGHTS * config.cog_height
    planner.observe(t, (stance.x + 0.99 * reach, stance.y), s.cog_vel[:2])
    _refused(planner, lambda: planner.observe(t, (stance.x + 1.01 * reach, stance.y), s.cog_vel[:2]), "cog")


def test_a_landing_turned_a_quarter_turn_or_more_is_refused_however_it_is_wrapped():
    planner, t = _walked(PlannerConfig(), 1.3)
    stance = planner.walk.footprint(1)  # the swing foot lands on F[2] from F[1]
    landing = planner.walk.footprint(2)
    for yaw in (2.5, -2.0, 2.5 + 2.0 * math.pi * 1e4):
        _refused(planner, lambda yaw=yaw: planner.touchdown(t, landing.side, landing.x, landing.y, yaw), "turns")
    assert planner.walk.footprint(1) == stance
    # An unwrapped heading is a heading: 1000 turns and 0.1 rad is accepted, but not 1e9 rad (0.577 rad once
    # wrapped, yet beyond MAX_YAW), nor 1e300 rad, whose turn from the stance foot is lost in round-off.
    for yaw in (1e9, -1e300):
        _refused(planner, lambda yaw=yaw: planner.touchdown(t, landing.side, landing.x, landing.y, yaw), "yaw must be")
    planner.touchdown(t, landing.side, landing.x, landing.y, 2000.0 * math.pi + 0.1)
    assert np.all(np.isfinite(planner.sample(t + 0.1).values))
    assert planner.walk.footprint(3).yaw == pytest.approx(0.1, abs=1e-9), "the next footprint turns from 0.1 rad"


def test_a_refused_landing_leaves_no_replan_behind():
    """At the landing instant the touchdown first samples it (a double support begins: its plan is made) and only
    then knows which footprint landed; refused, that plan and the phase reached are undone."""
    config = PlannerConfig(timing=Timing(0.8, 0.2))
    planner, _ = _walked(config, 1.79)
    twin, _ = _walked(config, 1.79)
    landing_time = planner.phase_start(2)
    assert planner.next_replan_phase == 2 and planner.latest_time < landing_time
    landing = planner.walk.footprint(2)
    _refused(planner, lambda: planner.touchdown(landing_time, landing.side, landing.x, landing.y, 2.5), "turns")
    assert planner.next_replan_phase == 2, "the double support's plan must not have been made"
    for u in (landing_time, landing_time + 0.4, landing_time + 1.0):
        assert planner.sample(u).values.tolist() == twin.sample(u).values.tolist()


def test_a_flat_support_is_a_segment_or_a_point_not_an_error():
    far = 1e17  # a sole's 0.2 m is below the resolution of a coordinate this large (16 m)
    feet = [Footstep(far, 0.1, 0.0, "left"), Footstep(far, -0.1, 0.0, "right")]
    segment = support_polygon(feet, SOLE)
    assert segment.shape == (2, 2) and np.all(segment[:, 0] == far)
    assert sorted(segment[:, 1]) == pytest.approx([-0.17, 0.17])
    assert signed_margin([far, 0.0], segment)[0] == 0.0
    assert signed_margin([far, 1.17], segment)[0] == pytest.approx(-1.0)
    point = support_polygon([Footstep(far, far, 0.0, "left"), Footstep(far, far, 0.0, "right")], SOLE)
    assert point.shape == (1, 2)
    assert signed_margin([far, far], point)[0] == 0.0
    assert signed_margin([far + 32.0, far], point)[0] == -32.0


def test_no_position_can_reach_a_flat_support_through_the_planner():
    planner = OnlinePlanner(PlannerConfig(), straight_walk(PlannerConfig(), 4, 0.1))
    feet = (Footstep(1e17, 0.1, 0.0, "left"), Footstep(1e17, -0.1, 0.0, "right"))
    _refused(planner, lambda: planner.start(0.0, feet=feet), "feet .*within")
    assert MAX_POSITION == 1e6


def test_an_emergency_stop_with_a_new_step_timing_replans_instead_of_an_index_error():
    adjust = StepAdjustment(SOLE, adapt_timing=True, on_failure="stop")
    config = PlannerConfig(timing=Timing(0.7, 0.1), feedback="measured", step_adjustment=adjust)
    planner = OnlinePlanner(config, straight_walk(config, 8, 0.1))
    planner.start(0.0)
    t = planner.phase_start(5) + 0.3 * 0.7
    for u in np.arange(0.0, t, 0.01):
        planner.sample(float(u))
    s = planner.sample(t)
    planner.observe(t, s.cog[:2], s.cog_vel[:2] + np.array([1.0, 0.0]))  # forward, beyond any one step
    planner.replan_now(t)  # was: IndexError in Walk.anchors_from (the plan's shape from before the walk was cut)
    decision = planner.step_adjustments[-1]
    assert decision.emergency and "emergency stop" in decision.reason
    assert planner.n_steps == decision.step + 1
    samples = np.array([planner.sample(float(u)).values for u in np.arange(t, planner.end_time + 0.5, 0.01)])
    assert np.all(np.isfinite(samples))
    final = planner.sample(planner.end_time + 0.5)
    assert final.cog_vel[:2] == pytest.approx([0.0, 0.0], abs=1e-9), "the cut walk's plan ends at rest"


def test_a_standing_foot_re_anchored_keeps_the_other_one():
    """Re-anchoring F[0] rebuilt the footprints from F[1] on, F[1] from the walk's last stride."""
    config = PlannerConfig()
    planner = OnlinePlanner(config, straight_walk(config, 4, 0.25))
    planner.start(0.0)
    planner.sample(0.1)
    first, second = planner.walk.footprint(0), planner.walk.footprint(1)
    assert planner.touchdown(0.1, first.side, first.x + 0.01, first.y, first.yaw) == 0
    assert planner.walk.footprint(1) == second


# ----- each entry point's bounds -----------------------------------------------------------------------------------
def test_start_bounds():
    config = PlannerConfig()
    planner = OnlinePlanner(config, straight_walk(config, 4, 0.1))
    left, right = Footstep(0.0, 0.1, 0.0, "left"), Footstep(0.0, -0.1, 0.0, "right")
    _refused(planner, lambda: planner.start(math.inf), "t0")
    _refused(planner, lambda: planner.start(0.0, feet=(left, Footstep(0.0, -0.1, 1.6, "right"))), "turned")
    _refused(planner, lambda: planner.start(0.0, feet=(left, right), cog=(5.0, 0.0)), "cog")
    _refused(planner, lambda: planner.start(0.0, feet=(left, right), cog_vel=(0.0, 1e3)), "cog_vel")
    _refused(planner, lambda: planner.start(0.0, cog=(math.nan, 0.0)), "cog")
    planner.start(0.0, feet=(left, right), cog=(0.05, 0.0), cog_vel=(0.1, 0.0))
    assert planner.sample(0.0).cog[:2] == pytest.approx([0.05, 0.0])


def test_a_walk_whose_history_was_trimmed_cannot_start_again():
    """Its first strides are gone: starting again would ask for footprints no longer kept (an IndexError)."""
    config = PlannerConfig(timing=Timing(0.3, 0.1, start=0.3), history_steps=8)
    planner, t = _walked(config, 12.0, steps=40)
    assert planner.walk.base > 0
    _refused(planner, lambda: planner.start(t), "history was trimmed")
    assert np.all(np.isfinite(planner.sample(t).values))


def test_time_bounds_of_sample_touchdown_and_replan_now():
    planner = OnlinePlanner(PlannerConfig(), None)  # a walk by command: no end to clamp a far time to
    planner.start(0.0)
    planner.set_velocity(0.2)
    planner.sample(1.0)
    began = time.process_time()
    _refused(planner, lambda: planner.sample(1e300), "within")  # used to hang in phase_at
    _refused(planner, lambda: planner.sample(5e9), "t=5000000000.0 s must be before")  # within MAX_TIME, too far
    assert time.process_time() - began < 0.5
    _refused(planner, lambda: planner.sample(math.inf), "finite")
    _refused(planner, lambda: planner.sample(-1.0), "before the plan")
    _refused(planner, lambda: planner.replan_now(0.5), "before the latest sample")
    _refused(planner, lambda: planner.replan_now(500.0), "double supports")
    foot = planner.walk.footprint(1)
    _refused(planner, lambda: planner.touchdown(0.5, foot.side, foot.x, foot.y, foot.yaw), "before the latest")
    _refused(planner, lambda: planner.touchdown(math.nan, foot.side, foot.x, foot.y, foot.yaw), "finite")
    _refused(planner, lambda: planner.touchdown(1.0, "middle", foot.x, foot.y, foot.yaw), "side")
    _refused(planner, lambda: planner.replan_now(1.0, feedback="psychic"), "feedback")


def test_the_landing_box_takes_the_stepping_limits_and_the_planned_stride():
    planner, t = _walked(PlannerConfig(timing=Timing(0.8, 0.2)), 1.3, steps=8)
    stance, landing = planner.walk.footprint(1), planner.walk.footprint(2)
    bounds = planner._landing_bounds
    # Forward, just inside and just outside the widest limit plus the tolerance.
    inside = bounds.max_length + LANDING_TOLERANCE - 0.01
    _refused(planner, lambda: planner.touchdown(t, landing.side, stance.x + inside + 0.02, landing.y, 0.0), "along")
    planner.touchdown(t, landing.side, stance.x + inside, landing.y, 0.0)
    # A walk that plans longer strides than any limit accepts its own landings and a tolerance beyond them.
    long_walk, t = _walked(PlannerConfig(timing=Timing(0.8, 0.2)), 1.3, steps=4)
    long_walk.change_step(2, length=1.2)
    planned = long_walk.walk.footprint(3)
    long_walk.sample(long_walk.phase_start(3) + 0.3)
    long_walk.touchdown(long_walk.phase_start(3) + 0.3, planned.side, planned.x + 0.1, planned.y, planned.yaw)


def test_walk_changes_refuse_with_the_bounds_error_and_change_nothing():
    config = PlannerConfig(connection="auto", sole=SOLE)
    planner, _ = _walked(config, 1.3)
    step = planner.first_open_step()
    _refused(planner, lambda: planner.change_step(step, length=math.nan), "length")
    _refused(planner, lambda: planner.change_step(step, turn=2.0), "turn")
    _refused(planner, lambda: planner.set_velocity(math.inf), "vx")
    _refused(planner, lambda: planner.set_strides([]), "at least one stride")
    nominal = planner.walk.footprint(step + 1)
    unwound = [*planner.footprints()[2 : step + 1], Footstep(nominal.x, nominal.y, -1e300, nominal.side)]
    _refused(planner, lambda: planner.set_footsteps(unwound), "footsteps.* yaw")
    prints = planner.footprints()  # F[i + 1] is where step i lands: steps before `step` are walked
    nominal = prints[step + 1]
    wild = [*prints[2 : step + 1], Footstep(nominal.x + 5.0, nominal.y, nominal.yaw, nominal.side)]
    _refused(planner, lambda: planner.set_footsteps(wild), "stride length")


# ----- random call streams -----------------------------------------------------------------------------------------
WILD = (math.nan, math.inf, -math.inf, 1e300, -1e300, 1e9, -1e9)
STREAM_SEEDS = range(6)
STREAM_TICKS = 4000
CALL_SECONDS = 0.5
"""Longest one call may take before it counts as a hang (s): the slowest, an auto change's predictions, takes ~1 ms."""


def _value(rng: np.random.Generator, plausible: float, spread: float) -> float:
    """Mostly plausible, sometimes far, sometimes not a number a sensor should send."""
    r = rng.random()
    if r < 0.7:
        return float(plausible + rng.normal(0.0, spread))
    if r < 0.85:
        return float(plausible + rng.normal(0.0, 50.0 * spread))
    return float(rng.choice(WILD))


def _stream_config(seed: int) -> tuple[PlannerConfig, bool]:
    """A configuration per seed, and whether the walk is by command."""
    timing = Timing(0.5, 0.1, start=0.4, end=0.4, settle=1.0)
    configs = [
        PlannerConfig(timing=timing, feedback="measured", replan_dcm_error=0.02, step_adjustment=StepAdjustment(SOLE),
                      history_steps=8),
        PlannerConfig(timing=timing, connection="quasi-real-time", history_steps=8),
        PlannerConfig(timing=timing, connection="auto", sole=SOLE, history_steps=8),
        PlannerConfig(timing=timing, feedback="measured", replan_dcm_error=0.03, history_steps=8,
                      step_adjustment=StepAdjustment(SOLE, adapt_timing=True, on_failure="stop")),
    ]  # fmt: skip
    return configs[seed % len(configs)], seed % 2 == 1


def _random_call(planner: OnlinePlanner, rng: np.random.Generator, t: float, s):
    """One closed-loop call with random arguments drawn now (so both twins get the same): ``(name, call)`` with
    ``call(planner)``, or ``None``."""
    r = rng.random()
    if r < 0.01 or (r < 0.03 and s.phase % 2 == 0):  # a landing: mostly at a double support, where feet land
        side = "left" if rng.random() < 0.5 else "right"
        foot = s.left_foot if side == "left" else s.right_foot
        args = (_value(rng, t, 0.0), side, _value(rng, foot[0], 0.02), _value(rng, foot[1], 0.02),
                _value(rng, foot[3], 0.05) if rng.random() < 0.9 else float(foot[3] + 2.5))  # fmt: skip
        return "touchdown", lambda p: p.touchdown(*args)
    if r < 0.04:
        when = _value(rng, t, 0.0) if rng.random() < 0.9 else _value(rng, t, 1.0)
        feedback = [None, "planned", "measured"][int(rng.integers(3))]
        adjust = [None, False, StepAdjustment(SOLE)][int(rng.integers(3))]
        return "replan_now", lambda p: p.replan_now(when, feedback=feedback, step_adjustment=adjust)
    if r < 0.05:
        step = planner.first_open_step() + int(rng.integers(-1, 3))
        values = {"length": _value(rng, 0.1, 0.05), "width": _value(rng, 0.2, 0.02), "turn": _value(rng, 0.0, 0.2)}
        return "change_step", lambda p: p.change_step(step, **values)
    if r < 0.055:
        command = (_value(rng, 0.2, 0.1), _value(rng, 0.0, 0.05), _value(rng, 0.0, 0.2))
        return "set_velocity", lambda p: p.set_velocity(*command)
    if r < 0.06:
        strides = []
        for _ in range(int(rng.integers(1, 4))):
            length, width, turn = _value(rng, 0.1, 0.05), abs(_value(rng, 0.2, 0.02)), _value(rng, 0.0, 0.2)
            with contextlib.suppress(ValueError):  # a Stride that cannot be made is the caller's error, not ours
                strides.append(Stride(length, width, turn))
        return "set_strides", lambda p: p.set_strides([*strides, Stride(0.0, 0.2)])
    if r < 0.065:
        first_open = planner.first_open_step()
        moved = []
        for step, f in enumerate(planner.footprints(first_open + 4)[2:], start=1):  # F[step + 1]: step's landing
            if step < first_open and rng.random() < 0.8:
                moved.append(f)  # a committed landing, as walked
                continue
            x, y, yaw = _value(rng, f.x, 0.02), _value(rng, f.y, 0.02), _value(rng, f.yaw, 0.1)
            moved.append(Footstep(x, y, yaw, f.side) if all(map(math.isfinite, (x, y, yaw))) else f)
        return "set_footsteps", lambda p: p.set_footsteps(moved)
    if r < 0.066:
        return "stop", lambda p: p.stop()
    if r < 0.068:
        when = float(rng.choice([math.nan, math.inf, 1e300, t - 1.0, t + 0.5]))
        return "sample", lambda p: p.sample(when)
    return None


@contextlib.contextmanager
def _watchdog(seconds: float):
    """Fail a stream that hangs (a call that never returns), where the platform has SIGALRM."""
    if not hasattr(signal, "setitimer"):
        yield
        return

    def hang(*_):
        raise TimeoutError(f"a call stream ran over {seconds} s: a call hangs")

    previous = signal.signal(signal.SIGALRM, hang)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)


def _twins(config: PlannerConfig, by_command: bool, t0: float) -> list[OnlinePlanner]:
    """Two planners of the same walk, started at ``t0`` (s)."""
    twins = []
    for _ in range(2):
        planner = OnlinePlanner(config, None if by_command else straight_walk(config, 12, 0.1))
        planner.start(t0)
        if by_command:
            planner.set_velocity(0.2)
        twins.append(planner)
    return twins


def _run_stream(seed: int) -> dict[str, int]:
    rng = np.random.default_rng(seed)
    config, by_command = _stream_config(seed)
    a, b = _twins(config, by_command, 0.0)
    counts = {"accepted": 0, "refused": 0}
    s = a.sample(0.0)
    b.sample(0.0)
    t = 0.0
    for _ in range(STREAM_TICKS):
        t = round(t + DT, 9)
        calls = []
        cog, vel = s.cog[:2], s.cog_vel[:2]
        observed = (_value(rng, t, 0.0), (_value(rng, cog[0], 0.01), _value(rng, cog[1], 0.01)),
                    (_value(rng, vel[0], 0.05), _value(rng, vel[1], 0.05)))  # fmt: skip
        calls.append(("observe", lambda p, o=observed: p.observe(*o)))
        extra = _random_call(a, rng, t, s)
        if extra is not None:
            calls.append(extra)
        for name, call in calls:
            before = _observable(a)
            began = time.process_time()
            try:
                with warnings.catch_warnings(record=True) as said:
                    warnings.simplefilter("always")
                    result = call(a)
                assert all(issubclass(w.category, WARNINGS) for w in said), [str(w.message) for w in said]
            except DOCUMENTED:
                counts["refused"] += 1
                assert _observable(a) == before, f"a refused {name} changed the planner (seed {seed}, t={t})"
            else:
                counts["accepted"] += 1
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    twin_result = call(b)
                if name == "touchdown":
                    assert twin_result == result
            assert time.process_time() - began < CALL_SECONDS, f"{name} took {time.process_time() - began:.2f} s"
        t = max(t, a.latest_time)  # an accepted call may have moved the walk's clock on (a replan asked for later)
        s = a.sample(t)
        twin = b.sample(t)
        assert np.all(np.isfinite(s.values)), f"a sample is not finite (seed {seed}, t={t})"
        assert s.values.tolist() == twin.values.tolist(), f"a refused call left a trace (seed {seed}, t={t})"
        if t > a.end_time + 0.5:  # the walk is over (a far time accepted, a stop): a new walk from here
            a, b = _twins(config, by_command, t)
            s = a.sample(t)
            b.sample(t)
    return counts


@pytest.mark.parametrize("seed", STREAM_SEEDS)
def test_random_closed_loop_streams_refuse_cleanly(seed):
    with _watchdog(30.0):
        counts = _run_stream(seed)
    assert counts["refused"] > 100 and counts["accepted"] > 100, counts
