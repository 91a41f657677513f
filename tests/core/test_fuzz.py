"""Random command streams at 1 kHz: whatever a user throws at the planner, the invariants hold at every tick.

A stream mixes every way of changing a walk (``change_step``, ``set_velocity``, ``set_footsteps``,
``set_strides``, ``stop``), calls that must be refused, and samples whose time now and then goes backwards. Checked
at every tick:

* only documented exceptions (``ValueError``, of which ``StepChangeTooLateError`` is one);
* a refused call changes nothing; a committed footprint never moves;
* the COG position and velocity are continuous (trapezoidal consistency with the sampled velocity and
  acceleration to 1e-7 m and 1e-5 m/s per 1 ms tick: the trapezoid rule errs by w^2 p'' dt^3 / 12, a few um/s
  where a connecting ZMP brakes hardest; a jump of 0.1 um or 10 um/s would show), and so is the ZMP (its
  second difference below 1e-3 m per tick: ZMP accelerations up to 1000 m/s^2 pass, a step of 1 mm does not);
* the pendulum equation ``p = c - c''/w^2`` to 1e-8 m (short phases of 0.1 s included);
* every value finite; the planner's history bounded.

The budget is fixed (seeds and sizes), so the test is reproducible and takes a few seconds.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from rtgait.core.geometry.footsteps import Footstep, Stride, Timing
from rtgait.core.lipm.closed_form import CogTrajectory
from rtgait.core.planner.online import (
    SAMPLE_FIELDS,
    OnlinePlanner,
    PlannerConfig,
    StepChangeTooLateError,
    straight_walk,
)

DT = 1e-3
STREAMS = 24
TICKS = 20_000
COL = {name: i for i, name in enumerate(SAMPLE_FIELDS)}
POS_TOL, VEL_TOL, PENDULUM_TOL = 1e-7, 1e-5, 1e-8


def _state(planner: OnlinePlanner) -> tuple:
    walk = planner.walk
    return (tuple(planner.footprints()), walk.n_steps, walk.command, walk.finite, walk.stopping, planner.end_time)


def _random_call(planner: OnlinePlanner, rng: np.random.Generator):
    """One random change of the walk, valid or not; returns a zero-argument callable and its name."""
    open_step = planner.first_open_step()
    kind = rng.choice(["change", "velocity", "footsteps", "strides", "stop", "bad"], p=[0.3, 0.2, 0.1, 0.1, 0.1, 0.2])
    if kind == "change":
        step = int(open_step + rng.integers(-2, 4))
        length, width = float(rng.uniform(-0.1, 0.3)), float(rng.uniform(0.15, 0.3))
        through = step + int(rng.integers(0, 3)) if rng.random() < 0.5 else None
        return lambda: planner.change_step(step, length=length, width=width, through=through), kind
    if kind == "velocity":
        vx, vy, wz = rng.uniform(-0.2, 0.4), rng.uniform(-0.1, 0.1), rng.uniform(-0.3, 0.3)
        return lambda: planner.set_velocity(vx, vy, wz), kind
    if kind == "footsteps":
        prints = planner.footprints(open_step + 4)
        shift = float(rng.uniform(-0.05, 0.1))
        moved = [Footstep(f.x + shift * (i >= open_step), f.y, f.yaw, f.side) for i, f in enumerate(prints[2:], 1)]
        return lambda: planner.set_footsteps(moved), kind
    if kind == "strides":
        count = int(rng.integers(1, 5))
        strides = [Stride(float(rng.uniform(0.0, 0.2)), 0.19 + float(rng.uniform(0, 0.05)))] * count
        start = open_step + int(rng.integers(-1, 2))
        return lambda: planner.set_strides([*strides, Stride(0.0, 0.19)], from_step=start), kind
    if kind == "stop":
        return planner.stop, kind
    bad = [
        lambda: planner.change_step(0, length=0.1),
        lambda: planner.change_step(open_step, length=math.nan),
        lambda: planner.change_step(open_step, width=-0.1),
        lambda: planner.set_strides([]),
        lambda: planner.set_velocity(math.inf),
        lambda: planner.set_footsteps([Footstep(0.1, 0.1, 0.0, "left"), Footstep(0.2, 0.1, 0.0, "left")]),
        lambda: planner.change_step(open_step, length=0.1, through=open_step - 1),
    ]
    return bad[int(rng.integers(len(bad)))], "bad"


def _run_stream(seed: int) -> dict[str, int]:
    rng = np.random.default_rng(seed)
    mode = ("real-time", "quasi-real-time")[seed % 2]
    single, double = [(0.8, 0.2), (0.7, 0.1), (0.5, 0.3)][seed % 3]
    config = PlannerConfig(
        timing=Timing(single, double, start=0.6, end=0.6, settle=1.0),
        connection=mode,
        horizon_steps=int(rng.integers(1, 5)),
        history_steps=16,
    )
    strides = None if seed % 4 == 0 else straight_walk(config, int(rng.integers(2, 12)), 0.1)
    planner = OnlinePlanner(config, strides)
    planner.start(0.0)
    if strides is None:
        planner.set_velocity(0.2)
    w2 = planner.w**2
    committed: dict[int, Footstep] = {}
    rows, counts = [], {"refused": 0, "accepted": 0, "backwards": 0}
    previous: CogTrajectory | None = None
    t = 0.0
    for _ in range(TICKS):
        if rng.random() < 0.004:
            call, _kind = _random_call(planner, rng)
            before = _state(planner)
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")  # clamped commands and cancelled stops are said, not errors
                    call()
                counts["accepted"] += 1
            except ValueError:  # StepChangeTooLateError is a ValueError: the only documented failures
                assert _state(planner) == before, "a refused call changed the walk"
                counts["refused"] += 1
        if rng.random() < 0.002:
            try:
                planner.sample(t - float(rng.uniform(0.0, 0.5)))
                counts["backwards"] += 1
            except ValueError:
                pass  # before the plan under way: refused
            rows.append(None)  # breaks the continuity check across it
        replans = planner.replan_count
        values, _support, _phase = planner.sample_values(t)
        rows.append(values)
        if planner.replan_count != replans:
            if previous is not None:
                _check_connection(previous, planner.current_plan, planner.plans[-1].t, config.first_degree)
            previous = planner.current_plan
        # Committed footprints: F[i + 1] for every step i before the first open one (and the standing feet).
        open_step = planner.first_open_step()
        base = planner.walk.base
        n = planner.n_steps
        last = open_step if n is None else min(open_step, n + 1)
        for index in range(max(base, open_step - 3), last + 1):
            foot = planner.walk.footprint(index)
            if index in committed:
                assert committed[index] == foot, f"committed footprint {index} moved"
            else:
                committed[index] = foot
        t += DT
        if t > planner.end_time + 0.5:
            break
    _check_ticks(rows, w2)
    assert len(planner.plans) <= 16 and len(planner.change_log) <= 16
    assert len(planner.footprints()) <= 2 * 16 + 40
    return counts


def _check_ticks(rows: list, w2: float) -> None:
    """Continuity and the pendulum equation over runs of consecutive forward ticks."""
    runs, current = [], []
    for row in rows:
        if row is None:
            runs.append(current)
            current = []
        else:
            current.append(row)
    runs.append(current)
    c, v, a, p = (
        slice(COL[x], COL[y] + 1)
        for x, y in (("cog_x", "cog_y"), ("cog_vx", "cog_vy"), ("cog_ax", "cog_ay"), ("zmp_x", "zmp_y"))
    )
    for run in runs:
        if len(run) < 3:
            continue
        x = np.array(run)
        assert np.all(np.isfinite(x)), "a sampled value is not finite"
        residual = x[:, p] - (x[:, c] - x[:, a] / w2)
        assert np.abs(residual).max() < PENDULUM_TOL, f"pendulum residual {np.abs(residual).max():.2e} m"
        pos_err = x[1:, c] - x[:-1, c] - 0.5 * (x[1:, v] + x[:-1, v]) * DT
        vel_err = x[1:, v] - x[:-1, v] - 0.5 * (x[1:, a] + x[:-1, a]) * DT
        held = np.all(x[1:, v] == 0.0, axis=1) & np.all(x[:-1, v] == 0.0, axis=1)  # at rest after the end
        assert np.abs(pos_err[~held]).max(initial=0.0) < POS_TOL, f"COG jump {np.abs(pos_err).max():.2e} m"
        assert np.abs(vel_err[~held]).max(initial=0.0) < VEL_TOL, f"COG velocity jump {np.abs(vel_err).max():.2e}"


def _check_connection(old: CogTrajectory, new: CogTrajectory, t: float, first_degree: int) -> None:
    """At the instant a new plan takes over, the ZMP (and with the quartic its velocity) and the COG position and
    velocity of the plan before it (its left limit) are where the new one starts, to round-off."""
    before = old.evaluate(t, side="left")
    after = new.evaluate(t)
    for name, a, b in (("COG", before[0], after[0]), ("COG velocity", before[1], after[1])):
        assert np.abs(a - b).max() < 1e-9, f"{name} jumps by {np.abs(a - b).max():.2e} at the connection t={t}"
    zmp_a, zmp_b = old.zmp.evaluate(t, side="left"), new.zmp.evaluate(t)
    assert np.abs(zmp_a - zmp_b).max() < 1e-9, f"ZMP jumps by {np.abs(zmp_a - zmp_b).max():.2e} at t={t}"
    if first_degree == 4:
        dzmp_a, dzmp_b = old.zmp.evaluate(t, derivative=1, side="left"), new.zmp.evaluate(t, derivative=1)
        assert np.abs(dzmp_a - dzmp_b).max() < 1e-7, f"ZMP velocity jumps at t={t}"


@pytest.mark.parametrize("seed", range(STREAMS))
def test_random_command_streams_keep_every_invariant(seed):
    counts = _run_stream(seed)
    assert counts["accepted"] + counts["refused"] > 0


def test_the_streams_exercise_both_outcomes():
    """The budget is meaningful only if streams both accept and refuse calls: checked on a few seeds."""
    totals = {"refused": 0, "accepted": 0}
    for seed in range(100, 104):
        counts = _run_stream(seed)
        totals["refused"] += counts["refused"]
        totals["accepted"] += counts["accepted"]
    assert totals["refused"] > 0 and totals["accepted"] > 0


def test_refused_late_change_is_the_documented_error():
    config = PlannerConfig(timing=Timing(0.8, 0.2), connection="real-time")
    planner = OnlinePlanner(config, straight_walk(config, 4, 0.1))
    planner.start(0.0)
    planner.sample(planner.phase_start(3) + 0.1)
    with pytest.raises(StepChangeTooLateError):
        planner.change_step(1, length=0.2)
