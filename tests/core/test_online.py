"""The online planner as a control loop sees it: every tick, every replanning, every footstep change.

Truth comes from the method (the pendulum equation, continuity across replanning, where feet must be, when
each connection mode may react) and from the paper's Section 5 outcomes, not from recorded outputs.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial import Delaunay

from rtgait.core.analysis.rollout import Rollout, ScheduledChange, rollout
from rtgait.core.geometry.footsteps import (
    Footstep,
    SoleRect,
    Stride,
    Timeline,
    Timing,
    other_side,
    place_footsteps,
    wrap_angle,
)
from rtgait.core.planner.online import (
    CONNECTION_MODES,
    SAMPLE_FIELDS,
    OnlinePlanner,
    PlannerConfig,
    StepChangeTooLateError,
    VelocityCommand,
    straight_walk,
)

EPS = 1e-7
"""Half-width (s) of the window sampled around every replanning."""
PAPER_SOLE = SoleRect(0.13, 0.10, 0.07, 0.07)
COL = {name: i for i, name in enumerate(SAMPLE_FIELDS)}
COG = slice(COL["cog_x"], COL["cog_y"] + 1)
COG_VEL = slice(COL["cog_vx"], COL["cog_vy"] + 1)
COG_ACC = slice(COL["cog_ax"], COL["cog_ay"] + 1)
ZMP = slice(COL["zmp_x"], COL["zmp_y"] + 1)
FOOT = {"left": slice(COL["lfoot_x"], COL["lfoot_yaw"] + 1), "right": slice(COL["rfoot_x"], COL["rfoot_yaw"] + 1)}


# ----- a control loop that checks every replanning ------------------------------------------------------------
@dataclass
class Walk:
    """Everything sampled on the regular ticks of a walk."""

    times: np.ndarray
    values: np.ndarray
    support: np.ndarray
    phase: np.ndarray
    replans_checked: int = 0


Action = tuple[float, Callable[[OnlinePlanner], None]]


def walk(planner: OnlinePlanner, dt: float, t_end: float, actions: Sequence[Action] = (), t0: float = 0.0) -> Walk:
    """Start ``planner`` at ``t0`` and sample it every ``dt`` up to ``t_end`` (absolute, s).

    ``actions`` run in time order, each just before the first tick at or after its time (so the planner has
    last been sampled one tick earlier). At every double-support start ``t_r`` after the first, the planner is
    also sampled at ``t_r - EPS`` and ``t_r + EPS`` and the plan before and after the replanning are compared at
    ``t_r``.
    """
    pending = sorted(actions, key=lambda a: a[0])
    planner.start(t0)
    n_ticks = math.floor((t_end - t0) / dt + 1e-9) + 1
    times = t0 + np.arange(n_ticks) * dt
    values = np.empty((n_ticks, len(SAMPLE_FIELDS)))
    support = np.empty(n_ticks, dtype=object)
    phase = np.empty(n_ticks, dtype=int)
    run = Walk(times, values, support, phase)
    q_next = 2  # the next double support whose start replans (phase 0's plan is the initial one)
    last_t = -math.inf
    for k, t in enumerate(times):
        t = float(t)
        while pending and pending[0][0] <= t:
            pending.pop(0)[1](planner)
        while planner.n_steps is None or q_next <= 2 * planner.n_steps:
            t_r = planner.phase_start(q_next)
            if t_r > t:
                break
            check_replanning(planner, q_next, t_r, max(t_r - EPS, last_t))
            run.replans_checked += 1
            q_next += 2
        sample = planner.sample(t)
        values[k], support[k], phase[k] = sample.values, sample.support, sample.phase
        last_t = t
    run.support = support.astype(str)
    return run


def check_replanning(planner: OnlinePlanner, q: int, t_r: float, t_before: float) -> None:
    """The plan made at ``t_r`` continues the one before it: COG position, velocity, acceleration and ZMP."""
    before = planner.sample(t_before)
    old = planner.current_plan
    n_plans = len(planner.plans)
    after = planner.sample(t_r + EPS)
    new = planner.current_plan
    assert len(planner.plans) == n_plans + 1, "exactly one replanning at each double-support start"
    record = planner.plans[-1]
    assert record.phase == q and record.t == t_r
    assert new.zmp.t0 == pytest.approx(t_r, abs=1e-12)

    # Exact: evaluate both plans at t_r.
    pos_old, vel_old, acc_old = (v[0] for v in old.evaluate(t_r))
    pos_new, vel_new, acc_new = (v[0] for v in new.evaluate(t_r))
    np.testing.assert_allclose(pos_new, pos_old, rtol=0, atol=1e-9, err_msg=f"COG jumps at t={t_r}")
    np.testing.assert_allclose(vel_new, vel_old, rtol=0, atol=1e-9, err_msg=f"COG velocity jumps at t={t_r}")
    np.testing.assert_allclose(acc_new, acc_old, rtol=0, atol=1e-8, err_msg=f"COG acceleration jumps at t={t_r}")
    np.testing.assert_allclose(new.zmp.evaluate(t_r)[0], old.zmp.evaluate(t_r)[0], rtol=0, atol=1e-9)
    if planner.config.first_degree == 4:
        zmp_vel_old = old.zmp.evaluate(t_r, derivative=1)[0]
        np.testing.assert_allclose(new.zmp.evaluate(t_r, derivative=1)[0], zmp_vel_old, rtol=0, atol=1e-8)

    # Through the public interface: samples on both sides differ by O(EPS).
    span = t_r + EPS - t_before
    for name, part in (("COG", COG), ("COG velocity", COG_VEL), ("ZMP", ZMP)):
        jump = np.max(np.abs(after.values[part] - before.values[part]))
        assert jump <= 50.0 * span, f"{name} jumps by {jump} across the replanning at t={t_r}"


# ----- independent descriptions of a walk -------------------------------------------------------------------
def phase_starts(timing: Timing, n_steps: int) -> np.ndarray:
    """Start times of phases 0..2n+1 and the end of the walk, relative to its start (s)."""
    durations = [timing.start]
    for i in range(1, n_steps + 1):
        durations += [timing.single_support, timing.double_support if i < n_steps else timing.end]
    durations.append(timing.settle)
    return np.concatenate(([0.0], np.cumsum(durations)))


def footprint_side(i: int, first_side: str) -> str:
    """Side of footprint F[i]: F[0] is the foot that swings first, then the feet alternate."""
    return first_side if i % 2 == 0 else other_side(first_side)


def check_walk(planner: OnlinePlanner, run: Walk, t0: float = 0.0) -> None:
    """Per-tick properties of a finite walk that has been sampled past its end."""
    cfg = planner.config
    w = planner.w
    n = planner.n_steps
    assert n is not None
    values = run.values

    # The pendulum equation on every tick (eq. 3).
    residual = values[:, ZMP] - (values[:, COG] - values[:, COG_ACC] / w**2)
    assert np.max(np.abs(residual)) < 1e-9
    assert np.all(values[:, COL["cog_z"]] == cfg.cog_height)

    # Phases and support labels against the timing alone.
    starts = t0 + phase_starts(cfg.timing, n)
    expected_phase = np.clip(np.searchsorted(starts, run.times, side="right") - 1, 0, 2 * n + 1)
    clear = np.min(np.abs(run.times[:, None] - starts[None, :]), axis=1) > 1e-9
    np.testing.assert_array_equal(run.phase[clear], expected_phase[clear])
    for q in np.unique(run.phase):
        rows = run.phase == q
        labels = set(run.support[rows])
        if q % 2 == 1 and q < 2 * n:
            stance = footprint_side((q + 1) // 2, cfg.first_side)
            assert labels == {stance}, (q, labels)
            if cfg.step_height > 0.0:  # the other foot is in the air for the whole single support
                assert np.all(values[rows & clear, FOOT[other_side(stance)]][:, 2] > 0.0)
        else:
            assert labels == {"double"}, (q, labels)

    # Feet: on the ground a foot is at z = 0 and does not move; it never teleports in flight.
    prints = planner.footprints()
    step_dist = max(math.hypot(b.x - a.x, b.y - a.y) for a, b in zip(prints[:-2], prints[2:], strict=True))
    step_turn = max(abs(wrap_angle(b.yaw - a.yaw)) for a, b in zip(prints[:-2], prints[2:], strict=True))
    dt = run.times[1] - run.times[0]
    Ts = cfg.timing.single_support
    for side, part in FOOT.items():
        pose = values[:, part]
        contact = (run.support == "double") | (run.support == side)
        assert np.all(pose[contact, 2] == 0.0)
        assert np.all(pose[:, 2] >= 0.0)
        both = contact[:-1] & contact[1:]
        moved = np.abs(np.diff(pose, axis=0))[both]
        assert moved.size == 0 or np.max(moved) < 1e-12, f"{side} foot slides while on the ground"
        dxy = np.hypot(*np.diff(pose[:, :2], axis=0).T)
        assert np.max(dxy) <= 1.9 * step_dist / Ts * dt + 1e-12  # quintic blend: peak speed 1.875 d / Ts
        assert np.max(np.abs(np.diff(pose[:, 2]))) <= 3.5 * cfg.step_height / Ts * dt + 1e-12
        dyaw = np.abs([wrap_angle(a) for a in np.diff(pose[:, 3])])
        assert np.max(dyaw) <= 1.9 * step_turn / Ts * dt + 1e-12

    # Each double support shows the footprints of the walk as planned (both feet, exact pose).
    for q in range(0, 2 * n + 2, 2):
        i = q // 2
        rows = np.flatnonzero(run.phase == q)
        for foot in (prints[i], prints[i + 1]):
            got = values[rows][:, FOOT[foot.side]]
            np.testing.assert_allclose(got[:, :2], np.tile(foot.position, (len(rows), 1)), rtol=0, atol=1e-12)
            assert np.all(np.abs([wrap_angle(y - foot.yaw) for y in got[:, 3]]) < 1e-12)

    # The ZMP the footsteps ask for: on the stance foot in single support (where the plan's ZMP is too: only
    # the connecting double support is free), a smoothstep to the next stance foot in double support, between
    # the final feet while settling.
    zmp_ref = values[:, COL["zmp_ref_x"] : COL["zmp_ref_y"] + 1]
    standing = 0.5 * (prints[0].position + prints[1].position)
    final_middle = 0.5 * (prints[n].position + prints[n + 1].position)
    for q in range(2 * n + 2):
        rows = (run.phase == q) & clear
        if not rows.any():
            continue
        if q % 2 == 1:
            target = prints[(q + 1) // 2].position if q < 2 * n else final_middle
            # While settling, a small ZMP bump that vanishes at both ends brings the COG to rest exactly.
            atol = 1e-9 if q < 2 * n else 2e-3
            np.testing.assert_allclose(values[rows, ZMP], np.tile(target, (rows.sum(), 1)), rtol=0, atol=atol)
            np.testing.assert_allclose(zmp_ref[rows], values[rows, ZMP], rtol=0, atol=1e-9)
        else:
            i = q // 2
            origin = standing if q == 0 else prints[i].position
            target = final_middle if i == n else prints[i + 1].position
            sigma = (run.times[rows] - starts[q]) / (starts[q + 1] - starts[q])
            expected = origin + np.outer(3 * sigma**2 - 2 * sigma**3, target - origin)
            np.testing.assert_allclose(zmp_ref[rows], expected, rtol=0, atol=1e-9)

    # Exactly one plan per double-support start.
    assert [p.phase for p in planner.plans] == list(range(0, 2 * n + 1, 2))

    # The end: at rest, COG over the middle of the final feet, ZMP there too.
    done = run.times >= planner.end_time - 1e-9
    assert done.any()
    final = values[done]
    left, right = final[:, FOOT["left"]], final[:, FOOT["right"]]
    middle = 0.5 * (left[:, :2] + right[:, :2])
    np.testing.assert_allclose(final[:, COG], middle, rtol=0, atol=1e-9)
    np.testing.assert_allclose(final[:, ZMP], middle, rtol=0, atol=1e-9)
    assert np.max(np.abs(final[:, COG_VEL])) < 1e-9, "the walk ends at rest"
    assert set(run.support[done]) == {"double"}


# ----- random walks with random changes ---------------------------------------------------------------------
strides_st = st.builds(Stride, st.floats(-0.1, 0.3), st.floats(0.15, 0.3), st.floats(-0.3, 0.3))


@st.composite
def random_walks(draw):
    mode = draw(st.sampled_from(CONNECTION_MODES))
    cfg = PlannerConfig(
        cog_height=draw(st.floats(0.6, 1.0)),
        timing=Timing(draw(st.floats(0.5, 1.0)), draw(st.floats(0.1, 0.4))),
        step_width=0.2,
        step_height=draw(st.sampled_from([0.0, 0.03, 0.08])),
        horizon_steps=draw(st.integers(1, 4)),
        connection=mode,
        first_degree=draw(st.sampled_from([2, 4])),
        first_side=draw(st.sampled_from(["left", "right"])),
    )
    strides = draw(st.lists(strides_st, min_size=1, max_size=7))
    n = len(strides)
    changes = draw(
        st.lists(
            st.tuples(st.integers(1, n), strides_st, st.integers(0, 3), st.floats(0.0, 1.0)),
            max_size=3,
        )
    )
    dt = draw(st.sampled_from([0.001, 0.005]))
    t0 = draw(st.sampled_from([0.0, 3.7]))
    return cfg, strides, changes, dt, t0


def deadline(cfg: PlannerConfig, step: int, t0: float = 0.0) -> float:
    """Latest time for a change of ``step``: its lift-off (real-time) or the start of the double support before
    it (quasi-real-time); for step 1 that double support is the walk's starting phase."""
    t = cfg.timing
    lift_off = t0 + t.start + (step - 1) * (t.single_support + t.double_support)
    if cfg.connection == "real-time":
        return lift_off
    return t0 if step == 1 else lift_off - t.double_support


@settings(max_examples=14, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(random_walks())
def test_random_walks_with_changes_are_continuous_and_consistent(case):
    cfg, strides, changes, dt, t0 = case
    planner = OnlinePlanner(cfg, strides)
    expected = list(strides)
    actions: list[Action] = []
    timed = []
    for step, stride, extra, u in changes:
        through = min(step + extra, len(strides))
        limit = deadline(cfg, step, t0)
        when = t0 + u * (limit - t0) - 2 * dt  # strictly before the deadline, with a tick to spare
        timed.append((when, step, stride, through))
    timed.sort(key=lambda c: c[0])
    for when, step, stride, through in timed:

        def change(p, step=step, stride=stride, through=through):
            p.change_step(step, length=stride.length, width=stride.width, turn=stride.turn, through=through)

        actions.append((when, change))
        for k in range(step, through + 1):
            expected[k - 1] = stride
    end = t0 + phase_starts(cfg.timing, len(strides))[-1] + 0.3
    run = walk(planner, dt, end, actions, t0=t0)
    assert run.replans_checked == len(strides)
    assert len(planner.change_log) == len(changes)
    check_walk(planner, run, t0)
    # The feet landed where the changed strides put them.
    start = (planner.footprints()[0], planner.footprints()[1])
    for got, want in zip(planner.footprints(), place_footsteps(start, expected), strict=True):
        assert (got.x, got.y, got.yaw, got.side) == pytest.approx((want.x, want.y, want.yaw, want.side), abs=1e-12)


@pytest.mark.parametrize("mode", CONNECTION_MODES)
def test_swing_foot_lifts_off_and_touches_down_gently(mode):
    """Around lift-off and touch-down: foot on the ground at the instants, in the air just inside, no speed."""
    cfg = PlannerConfig(timing=Timing(0.7, 0.25), step_height=0.06, connection=mode)
    planner = OnlinePlanner(cfg, [Stride(0.25, 0.2, 0.2), Stride(-0.1, 0.25, -0.1), Stride(0.2, 0.2, 0.0)] * 2)
    planner.start(0.0)
    Ts, h = cfg.timing.single_support, 1e-3
    prints = planner.footprints()
    for i in range(1, planner.n_steps + 1):
        lift_off = cfg.timing.start + (i - 1) * cfg.timing.step_period
        touch_down = lift_off + Ts
        foot = FOOT[prints[i - 1].side]
        start, end = prints[i - 1], prints[i + 1]

        def pose(t, foot=foot):
            return planner.sample(t).values[foot]

        # Sampled forward in time: just after lift-off, then just before touch-down.
        after_lift = [pose(lift_off + h), pose(lift_off + 2 * h)]
        before_touch = [pose(touch_down - 2 * h), pose(touch_down - h)]
        for near, far, ground in ((*after_lift, start), (before_touch[1], before_touch[0], end)):
            for p in (near, far):
                assert 0.0 < p[2] < 64 * (2 * h / Ts) ** 3 * cfg.step_height * 1.01  # in the air, barely
                assert math.hypot(p[0] - ground.x, p[1] - ground.y) < 1e-6
                assert abs(wrap_angle(p[3] - ground.yaw)) < 1e-6
            velocity = np.abs(far - near) / h
            velocity[3] = abs(wrap_angle(far[3] - near[3])) / h
            assert np.max(velocity) < 1e-3  # O(h^2): the foot starts and stops at rest
        mid = planner.sample(lift_off + 0.5 * Ts)
        assert mid.values[foot][2] == pytest.approx(cfg.step_height, abs=1e-12)  # the peak is mid-swing
        landed = planner.sample(touch_down + h)
        assert landed.support == "double"
        np.testing.assert_array_equal(landed.values[foot], [end.x, end.y, 0.0, end.yaw])


# ----- connection modes (method.md section 5) -----------------------------------------------------------------
def paper_config(mode: str, single: float, double: float) -> PlannerConfig:
    return PlannerConfig(cog_height=0.8, timing=Timing(single, double), step_width=0.19, connection=mode)


@pytest.mark.parametrize("mode", CONNECTION_MODES)
def test_change_deadlines(mode):
    cfg = paper_config(mode, 0.8, 0.2)
    for step in (1, 2, 5, 10):
        planner = OnlinePlanner(cfg, straight_walk(cfg, 10, 0.1))
        planner.start(0.0)
        limit = deadline(cfg, step)
        assert planner.change_deadline(step) == pytest.approx(limit, abs=1e-12)
        if limit > 0.0:
            planner.sample(limit - 0.01)
            planner.change_step(step, length=0.12)  # just in time
            assert planner.footprints()[step + 1].x == pytest.approx(0.1 * (step - 1) + 0.12)
        planner.sample(limit + 0.01)
        with pytest.raises(StepChangeTooLateError, match=f"step {step}"):
            planner.change_step(step, length=0.13)
        # A later step is still open.
        planner.change_step(step + 1, length=0.11)


def test_deadlines_of_the_two_modes_differ_by_the_double_support():
    for single, double in ((0.8, 0.2), (0.7, 0.1), (0.8, 1.5)):
        rt = OnlinePlanner(paper_config("real-time", single, double), [Stride(0.1, 0.19)] * 6)
        qrt = OnlinePlanner(paper_config("quasi-real-time", single, double), [Stride(0.1, 0.19)] * 6)
        rt.start(0.0)
        qrt.start(0.0)
        for step in range(1, 7):
            assert rt.change_deadline(step) == pytest.approx(1.0 + (step - 1) * (single + double), abs=1e-12)
            # The double support before step 1 is the starting phase (1 s here), before later steps T_dbl.
            gap = 1.0 if step == 1 else double
            assert rt.change_deadline(step) - qrt.change_deadline(step) == pytest.approx(gap, abs=1e-12)


def run_with_change(cfg: PlannerConfig, step: int, length: float, dt: float = 0.005, change: bool = True) -> Walk:
    """A 10-step walk of 0.1 m steps; ``step`` and the later ones get ``length``, decided at the deadline."""
    planner = OnlinePlanner(cfg, straight_walk(cfg, 10, 0.1))
    actions = []
    if change:
        when = deadline(cfg, step) - 0.5 * dt  # the last tick before the deadline has just been sampled
        actions.append((when, lambda p: p.change_step(step, length=length, through=10)))
    run = walk(planner, dt, planner.timeline.end_time + 0.2, actions)
    check_walk(planner, run)
    return run


def first_difference(a: Walk, b: Walk, part: slice) -> float:
    differs = np.any(np.abs(a.values[:, part] - b.values[:, part]) > 1e-6, axis=1)
    return float(a.times[np.argmax(differs)]) if differs.any() else math.inf


def test_real_time_change_moves_the_swing_foot_at_once_and_the_cog_one_step_later():
    cfg = paper_config("real-time", 0.8, 0.2)
    k = 5
    changed, unchanged = run_with_change(cfg, k, 0.2), run_with_change(cfg, k, 0.2, change=False)
    P = cfg.timing.step_period
    lift_off = 1.0 + (k - 1) * P
    landing_dbl = lift_off + cfg.timing.single_support  # double support after step k lands: phase 2k
    # COG and ZMP identical until that double support, different in it.
    before = changed.times < landing_dbl - 1e-9
    for part in (COG, COG_VEL, COG_ACC, ZMP):
        np.testing.assert_array_equal(changed.values[before, part], unchanged.values[before, part])
        first = first_difference(changed, unchanged, part)
        assert landing_dbl < first < landing_dbl + cfg.timing.double_support
    # The swing foot of step k already goes to the new place: F[k+1] = 4 * 0.1 + 0.2 instead of 0.5.
    swing = footprint_side(k - 1, cfg.first_side)
    x_changed, x_unchanged = changed.values[:, FOOT[swing]][:, 0], unchanged.values[:, FOOT[swing]][:, 0]
    during = (changed.times > lift_off) & (changed.times < landing_dbl)
    assert np.all(x_changed[during] > x_unchanged[during] - 1e-12)
    assert np.any(x_changed[during] > x_unchanged[during] + 1e-3)
    at_touchdown = np.argmin(np.abs(changed.times - (landing_dbl + 0.1)))
    assert x_changed[at_touchdown] == pytest.approx(0.6, abs=1e-12)
    assert x_unchanged[at_touchdown] == pytest.approx(0.5, abs=1e-12)
    # The swing foot's path before lift-off is untouched.
    before = changed.times < lift_off
    np.testing.assert_array_equal(changed.values[before], unchanged.values[before])


def test_quasi_real_time_change_reacts_at_the_double_support_before_the_step():
    cfg = paper_config("quasi-real-time", 0.7, 0.1)
    k = 5
    changed, unchanged = run_with_change(cfg, k, 0.2), run_with_change(cfg, k, 0.2, change=False)
    P = cfg.timing.step_period
    dbl_before = 1.0 + (k - 1) * P - cfg.timing.double_support  # phase 2k - 2
    before = changed.times < dbl_before - 1e-9
    np.testing.assert_array_equal(changed.values[before], unchanged.values[before])
    for part in (COG, ZMP):
        first = first_difference(changed, unchanged, part)
        assert dbl_before < first < dbl_before + cfg.timing.double_support
    # The step in progress keeps its length: F[k] is where it was, F[k+1] moved.
    swing_prev = footprint_side(k - 2, cfg.first_side)
    rows = (changed.times > dbl_before) & (changed.times < dbl_before + 0.05)
    np.testing.assert_array_equal(
        changed.values[rows][:, FOOT[swing_prev]], unchanged.values[rows][:, FOOT[swing_prev]]
    )


# ----- the paper's Section 5 outcomes -----------------------------------------------------------------------
def inside_support_hull(planner: OnlinePlanner, zmp: np.ndarray, phase: np.ndarray) -> np.ndarray:
    """Whether each ZMP sample lies in the convex hull of the sole corners in contact (Delaunay test)."""
    inside = np.empty(len(zmp), dtype=bool)
    for q in np.unique(phase):
        corners = np.vstack([PAPER_SOLE.corners(f) for f in planner.contact_feet(int(q))])
        mask = phase == q
        inside[mask] = Delaunay(corners).find_simplex(zmp[mask], tol=1e-12) >= 0
    return inside


def paper_rollout(mode: str, single: float, double: float, before: float, after: float) -> tuple[Rollout, bool]:
    cfg = paper_config(mode, single, double)
    planner = OnlinePlanner(cfg, straight_walk(cfg, 10, before))
    result = rollout(planner, 0.005, PAPER_SOLE, [ScheduledChange(5, length=after, through=10)])
    zmp = result.values[:, ZMP]
    inside = inside_support_hull(planner, zmp, result.phase)
    # rollout's margin and the independent hull test agree on every tick (away from the boundary itself).
    clear = np.abs(result.margin) > 1e-9
    np.testing.assert_array_equal(inside[clear], result.margin[clear] > 0.0)
    assert result.footprints[-1].x == pytest.approx(4 * before + 6 * after)
    return result, bool(inside.all())


@pytest.mark.parametrize(
    ("name", "mode", "single", "double", "before", "after", "stays_inside"),
    [
        ("fig4", "real-time", 0.8, 0.2, 0.05, 0.15, False),
        ("fig6", "real-time", 0.8, 0.2, 0.11, 0.12, True),
        ("fig7", "real-time", 0.8, 1.5, 0.05, 0.15, True),
        ("fig8", "quasi-real-time", 0.7, 0.1, 0.05, 0.15, True),
        ("fig8 in real-time mode", "real-time", 0.7, 0.1, 0.05, 0.15, False),
    ],
)
def test_paper_outcomes(name, mode, single, double, before, after, stays_inside):
    result, inside = paper_rollout(mode, single, double, before, after)
    assert inside == stays_inside, name
    assert result.zmp_outside == (not stays_inside), name
    if not stays_inside:
        # The failure is the connection that absorbs the change: the double support after step 5 lands.
        assert result.phase[result.worst_index] == 10, name
        assert result.zmp_margin_min < -0.02, name
    else:
        assert result.zmp_margin_min > 0.01, name
    assert len(result.changes) == 1 and result.changes[0][1] == 5


def test_quasi_real_time_absorbs_what_real_time_cannot():
    """Same timing (fig8's), same change: the mode alone decides whether the ZMP leaves the feet."""
    rt, rt_inside = paper_rollout("real-time", 0.7, 0.1, 0.05, 0.15)
    qrt, qrt_inside = paper_rollout("quasi-real-time", 0.7, 0.1, 0.05, 0.15)
    assert qrt_inside and not rt_inside
    assert qrt.zmp_margin_min > rt.zmp_margin_min + 0.1


# ----- turning ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize(("turn", "steps"), [(0.15, 8), (-0.2, 6), (0.3, 12)])
def test_turning_walk_ends_with_the_total_yaw(turn, steps):
    cfg = PlannerConfig(timing=Timing(0.7, 0.2), step_width=0.2)
    strides = [Stride(0.1, 0.2, turn)] * steps + [Stride(0.0, 0.2, 0.0)]
    planner = OnlinePlanner(cfg, strides)
    run = walk(planner, 0.005, planner.timeline.end_time + 0.2)
    check_walk(planner, run)
    final = run.values[-1]
    for side in ("left", "right"):
        assert wrap_angle(final[FOOT[side]][3] - steps * turn) == pytest.approx(0.0, abs=1e-12)
    # Footprint F[i + 1] has turned i times; double support after step i shows F[i] and F[i + 1].
    for i in range(1, steps + 1):
        rows = run.phase == 2 * i
        for j in (i, i + 1):
            yaw = (j - 1) * turn
            foot = FOOT[footprint_side(j, cfg.first_side)]
            assert np.all(np.abs([wrap_angle(v - yaw) for v in run.values[rows][:, foot][:, 3]]) < 1e-12)
    # The final feet stand side by side across the final heading, the COG between them.
    heading = steps * turn
    gap = final[FOOT["left"]][:2] - final[FOOT["right"]][:2]
    np.testing.assert_allclose(gap, 0.2 * np.array([-math.sin(heading), math.cos(heading)]), atol=1e-12)


# ----- velocity interface -----------------------------------------------------------------------------------
def velocity_walk(cfg: PlannerConfig, commands: list[tuple[float, tuple[float, float, float]]], stop_at: float,
                  dt: float = 0.005) -> tuple[OnlinePlanner, Walk]:  # fmt: skip
    planner = OnlinePlanner(cfg, None)
    actions: list[Action] = [(t, lambda p, c=c: p.set_velocity(*c)) for t, c in commands]
    ended: list[float] = []

    def stop(p: OnlinePlanner) -> None:
        p.stop()
        ended.append(p.end_time)

    actions.append((stop_at, stop))
    # Run long enough for any stop: the walk then needs at most two steps, the end and the settling.
    t = cfg.timing
    end = stop_at + 2 * t.step_period + t.end + t.settle + 0.3
    run = walk(planner, dt, end, actions)
    assert ended and ended[0] <= end - 0.2
    return planner, run


def test_forward_velocity_command():
    cfg = PlannerConfig()  # T_s 0.8, T_dbl 0.2: one step per second
    planner, run = velocity_walk(cfg, [(2.0, (0.2, 0.0, 0.0))], stop_at=14.0)
    check_walk(planner, run)
    # Steady state: the COG advances 0.2 m per step period.
    a, b = np.searchsorted(run.times, [6.0, 12.0])
    speed = (run.values[b, COG] - run.values[a, COG]) / (run.times[b] - run.times[a])
    assert speed[0] == pytest.approx(0.2, rel=0.02)
    assert abs(speed[1]) < 0.01
    # Commanded strides never exceed the configured bounds and are straight.
    prints = planner.footprints()
    assert all(abs(p.yaw) < 1e-12 for p in prints)
    assert max(b.x - a.x for a, b in itertools.pairwise(prints)) <= cfg.max_step_length + 1e-12


@pytest.mark.parametrize(
    ("command", "direction"),
    [((0.0, 0.05, 0.0), "left"), ((0.0, -0.05, 0.0), "right"), ((-0.1, 0.0, 0.0), "back"),
     ((0.1, 0.0, 0.15), "turn left"), ((0.1, 0.0, -0.15), "turn right")],
)  # fmt: skip
def test_velocity_commands_move_the_right_way(command, direction):
    cfg = PlannerConfig()
    vx, vy, wz = command
    planner, run = velocity_walk(cfg, [(2.0, command)], stop_at=12.0)
    check_walk(planner, run)
    final = run.values[-1]
    start = run.values[0]
    moved = final[COG] - start[COG]
    yaw = final[FOOT["left"]][3]
    # Commanded from t = 2 s to t = 12 s: ten steps of one second.
    if direction in ("left", "right"):
        assert moved[1] == pytest.approx(vy * 10.0, rel=0.15)
        assert abs(moved[0]) < 1e-9 and abs(yaw) < 1e-12
    elif direction == "back":
        assert moved[0] == pytest.approx(vx * 10.0, rel=0.15)
    else:
        assert wrap_angle(yaw - wz * 10.0) == pytest.approx(0.0, abs=0.1 * abs(wz) * 10.0)
        assert np.sign(moved[1]) == np.sign(wz)  # turning left walks to the left
        assert moved[0] > 0.0


def test_changing_the_command_mid_walk_keeps_continuity_and_stops_at_rest():
    cfg = PlannerConfig(timing=Timing(0.7, 0.15), connection="quasi-real-time")
    commands = [(1.3, (0.25, 0.0, 0.0)), (4.41, (0.1, 0.04, 0.15)), (6.77, (-0.04, -0.04, -0.16)), (9.02, (0.3, 0, 0))]
    planner, run = velocity_walk(cfg, commands, stop_at=11.5, dt=0.001)
    assert run.replans_checked == planner.n_steps
    check_walk(planner, run)


def test_stop_before_walking_and_nan_command():
    planner = OnlinePlanner(PlannerConfig(), None)
    with pytest.raises(ValueError, match="vx"):
        planner.set_velocity(math.nan, 0.0, 0.0)
    with pytest.raises(ValueError, match="wz"):
        planner.set_velocity(0.1, 0.0, math.inf)
    with pytest.raises(ValueError, match="vy"):
        VelocityCommand(0.0, math.nan)
    assert planner.n_steps is None
    planner.stop()
    assert planner.n_steps == 1
    run = walk(planner, 0.005, planner.timeline.end_time + 0.1)
    check_walk(planner, run)


# ----- absolute footsteps -----------------------------------------------------------------------------------
def arc_footsteps(n: int, first_side: str, radius: float = 1.5, dtheta: float = 0.12, width: float = 0.2):
    """Footprints of steps 1..n along a left arc, independently of the stride code; the last two side by side."""
    steps = []
    for i in range(1, n + 1):
        side = footprint_side(i + 1, first_side)  # step i lands F[i + 1]
        theta = dtheta * min(i, n - 1)
        centre = np.array([radius * math.sin(theta), radius * (1.0 - math.cos(theta))])
        normal = np.array([-math.sin(theta), math.cos(theta)])
        pos = centre + (0.5 * width if side == "left" else -0.5 * width) * normal
        steps.append(Footstep(float(pos[0]), float(pos[1]), theta, side))
    return steps


@pytest.mark.parametrize("mode", CONNECTION_MODES)
def test_set_footsteps_lands_the_feet_there(mode):
    cfg = PlannerConfig(step_width=0.2, connection=mode)
    planner = OnlinePlanner(cfg, [Stride(0.1, 0.2)])
    steps = arc_footsteps(9, cfg.first_side)
    planner.set_footsteps(steps)
    assert planner.n_steps == 9
    run = walk(planner, 0.005, planner.timeline.end_time + 0.1)
    check_walk(planner, run)
    for i, foot in enumerate(steps, start=1):
        rows = run.phase == 2 * i  # double support after step i: F[i + 1] is on the ground
        pose = run.values[rows][:, FOOT[foot.side]]
        np.testing.assert_allclose(pose[:, :2], np.tile(foot.position, (rows.sum(), 1)), rtol=0, atol=1e-12)
        np.testing.assert_allclose(pose[:, 3], foot.yaw, rtol=0, atol=1e-12)


def test_set_footsteps_while_walking():
    cfg = PlannerConfig(step_width=0.2)
    planner = OnlinePlanner(cfg, [Stride(0.1, 0.2)] * 8 + [Stride(0.0, 0.2)])
    arc = arc_footsteps(8, cfg.first_side, radius=1.0, dtheta=0.1)
    sent: list[Footstep] = []

    def redirect(p: OnlinePlanner) -> None:
        open_step = p.first_open_step()
        assert open_step == 4  # t = 3.55 s is in step 3's single support
        walked = p.footprints(open_step)[2:]  # where steps 1..3 landed
        # Steps 4..8 follow the arc, moved so that its step 3 coincides with the real one.
        shift = walked[-1].position - arc[open_step - 2].position
        sent.extend(Footstep(f.x + shift[0], f.y + shift[1], f.yaw, f.side) for f in arc[open_step - 1 :])
        # Moving a step that has already landed is refused, and changes nothing.
        bad = [Footstep(walked[0].x + 0.05, walked[0].y, walked[0].yaw, walked[0].side), *walked[1:], *sent]
        with pytest.raises(StepChangeTooLateError, match="footstep 1"):
            p.set_footsteps(bad)
        p.set_footsteps([*walked, *sent])

    run = walk(planner, 0.005, 13.5, [(3.55, redirect)])
    assert planner.n_steps == 8
    check_walk(planner, run)
    for i, foot in enumerate(sent, start=4):
        landed = planner.footprints()[i + 1]
        assert (landed.x, landed.y, landed.yaw, landed.side) == pytest.approx((foot.x, foot.y, foot.yaw, foot.side))


# ----- bad input ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("make", "field"),
    [
        (lambda: Timing(-0.8, 0.2), "single_support"),
        (lambda: Timing(0.8, -0.2), "double_support"),
        (lambda: Timing(0.8, 0.2, start=0.0), "start"),
        (lambda: Timing(0.8, 0.2, settle=math.nan), "settle"),
        (lambda: Stride(math.nan, 0.2), "length"),
        (lambda: PlannerConfig(connection="soon"), "connection"),
        (lambda: PlannerConfig(cog_height=-0.8), "cog_height"),
        (lambda: PlannerConfig(horizon_steps=0), "horizon_steps"),
        (lambda: PlannerConfig(step_width=math.nan), "step_width"),
        (lambda: OnlinePlanner(PlannerConfig(), []), "stride"),
        (lambda: straight_walk(PlannerConfig(), 0, 0.1), "steps"),
    ],
)
def test_bad_configuration_is_refused_naming_the_field(make, field):
    with pytest.raises(ValueError, match=field):
        make()


def test_bad_planner_calls_are_refused_naming_the_field():
    cfg = PlannerConfig()
    planner = OnlinePlanner(cfg, straight_walk(cfg, 4, 0.1))
    with pytest.raises(RuntimeError, match="start"):
        planner.sample(0.0)
    planner.start(1.0)
    with pytest.raises(ValueError, match="t="):
        planner.sample(0.5)  # before the walk's start
    with pytest.raises(ValueError, match="t="):
        planner.sample(math.nan)
    with pytest.raises(ValueError, match="t0"):
        planner.start(math.nan)
    with pytest.raises(ValueError, match="length"):
        planner.change_step(2, length=math.nan)
    with pytest.raises(ValueError, match="step 9 does not exist"):
        planner.change_step(9, length=0.1)
    with pytest.raises(ValueError, match="step"):
        planner.change_step(0, length=0.1)
    with pytest.raises(ValueError, match="through"):
        planner.change_step(3, length=0.1, through=2)
    with pytest.raises(ValueError, match="does not exist"):
        planner.change_step(3, length=0.1, through=7)
    # None of the refused calls changed the walk.
    assert [f.x for f in planner.footprints()] == pytest.approx([0.0, 0.0, 0.1, 0.2, 0.3, 0.4, 0.4])
    planner.sample(3.0)
    with pytest.raises(ValueError, match="before the plan"):
        planner.sample(1.5)  # plans only go forward in time


def test_rollout_rejects_bad_period_and_endless_walks():
    cfg = PlannerConfig()
    with pytest.raises(ValueError, match="dt"):
        rollout(OnlinePlanner(cfg, straight_walk(cfg, 2, 0.1)), 0.0, PAPER_SOLE)
    with pytest.raises(ValueError, match="finite duration"):
        rollout(OnlinePlanner(cfg, None), 0.01, PAPER_SOLE)


# ----- timeline ---------------------------------------------------------------------------------------------
@settings(max_examples=40, deadline=None)
@given(st.floats(0.3, 1.2), st.floats(0.05, 1.5), st.floats(0.2, 2.0), st.floats(0.2, 2.0), st.floats(0.2, 3.0),
       st.none() | st.integers(1, 12))  # fmt: skip
def test_timeline_phases_follow_the_durations(single, double, start, end, settle, n):
    timing = Timing(single, double, start, end, settle)
    timeline = Timeline(timing, n)
    last = 2 * n + 1 if n is not None else 25
    kinds = [timeline.kind(q) for q in range(last + 1)]
    expected_kinds = ["start"] + [("single" if q % 2 else "double") for q in range(1, last + 1)]
    if n is not None:
        expected_kinds[2 * n], expected_kinds[2 * n + 1] = "end", "settle"
    assert kinds == expected_kinds
    if n is not None:
        np.testing.assert_allclose([timeline.start_time(q) for q in range(last + 1)], phase_starts(timing, n)[:-1])
        assert timeline.end_time == pytest.approx(phase_starts(timing, n)[-1])
    for q in range(last):
        assert timeline.start_time(q + 1) - timeline.start_time(q) == pytest.approx(timeline.duration(q))
        middle = timeline.start_time(q) + 0.5 * timeline.duration(q)
        assert timeline.phase_at(middle) == q
    assert timeline.phase_at(-1.0) == 0
    if n is not None:
        assert timeline.phase_at(timeline.end_time + 10.0) == 2 * n + 1


@pytest.mark.parametrize(("single", "double"), [(0.8, 0.2), (0.7, 0.1), (0.5, 0.15)])
def test_timeline_phase_at_its_own_start_times(single, double):
    timeline = Timeline(Timing(single, double), 10)
    wrong = [q for q in range(22) if timeline.phase_at(timeline.start_time(q)) != q]
    assert wrong == []


def test_quasi_real_time_change_at_its_deadline_is_refused():
    """Sampled exactly at the double-support start, the plan of step 3 is made: changing step 3 is too late."""
    cfg = PlannerConfig(timing=Timing(0.5, 0.15), connection="quasi-real-time")
    planner = OnlinePlanner(cfg, straight_walk(cfg, 6, 0.1))
    planner.start(0.0)
    limit = planner.change_deadline(3)
    planner.sample(limit)
    assert planner.plans[-1].phase == 4  # the plan of the double support before step 3 exists
    with pytest.raises(StepChangeTooLateError):
        planner.change_step(3, length=0.3)


def test_real_time_change_at_lift_off_is_refused():
    cfg = PlannerConfig(timing=Timing(0.7, 0.1), connection="real-time")
    planner = OnlinePlanner(cfg, straight_walk(cfg, 6, 0.1))
    planner.start(0.0)
    planner.sample(planner.change_deadline(2))  # step 2 lifts off now
    with pytest.raises(StepChangeTooLateError):
        planner.change_step(2, length=0.3)


def test_walk_cannot_be_extended_once_its_final_double_support_began():
    cfg = PlannerConfig(timing=Timing(0.5, 0.15))
    planner = OnlinePlanner(cfg, straight_walk(cfg, 2, 0.1))  # 3 steps: the final double support is phase 6
    planner.start(0.0)
    planner.sample(planner.phase_start(6))
    assert planner.plans[-1].phase == 6
    with pytest.raises(StepChangeTooLateError):
        planner.set_velocity(0.2)


def test_stop_twice_does_not_lengthen_the_walk():
    cfg = PlannerConfig()
    planner = OnlinePlanner(cfg, None)
    planner.start(0.0)
    planner.set_velocity(0.2)
    walk_to = [0.0]

    def advance(t_end: float) -> None:
        while walk_to[0] < t_end:
            planner.sample(walk_to[0])
            walk_to[0] += 0.005

    advance(4.3)
    planner.stop()
    end = planner.end_time
    advance(5.3)
    planner.stop()  # e.g. a joystick loop that keeps sending "stop" while the stick is released
    assert planner.end_time == end


# ----- rollout extras ---------------------------------------------------------------------------------------
def test_rollout_free_segments_are_the_connecting_double_supports():
    cfg = paper_config("real-time", 0.8, 0.2)
    result = rollout(OnlinePlanner(cfg, straight_walk(cfg, 4, 0.1)), 0.01, PAPER_SOLE)
    mask = result.free_segment_mask()
    starts = phase_starts(cfg.timing, 5)
    clear = np.min(np.abs(result.times[:, None] - starts[None, :]), axis=1) > 1e-9
    connecting = (result.phase % 2 == 0) & (result.phase >= 2)
    np.testing.assert_array_equal(mask[clear], connecting[clear])
    assert [p.phase for p in result.connections] == [2, 4, 6, 8, 10]
    assert set(result.polygons) == set(range(12))


def test_planner_zmp_margin_matches_the_geometry():
    cfg = paper_config("real-time", 0.8, 0.2)
    planner = OnlinePlanner(cfg, straight_walk(cfg, 4, 0.1))
    planner.start(0.0)
    single = planner.sample(1.4)  # middle of step 1's single support: ZMP on the stance foot's origin
    assert single.support != "double"
    stance = single.left_foot if single.support == "left" else single.right_foot
    np.testing.assert_allclose(single.zmp, stance[:2], atol=1e-12)
    assert planner.zmp_margin(single, PAPER_SOLE) == pytest.approx(0.07, abs=1e-12)  # half the sole width
