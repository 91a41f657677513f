"""A scenario on the point-mass pendulum: the walk it runs, the mass it uses, and the files it writes."""

from __future__ import annotations

import csv
import dataclasses
import itertools
import json
import math
import types

import numpy as np
import pytest

from rtgait.core.geometry.footsteps import Timing
from rtgait.core.pendulum.loop import DEFAULT_DT
from rtgait.core.push import Push
from rtgait.io.pendulum_run import (
    DEFAULT_MASS,
    PENDULUM_CSV_COLUMNS,
    as_push,
    scenario_mass,
    simulate_pendulum,
    write_pendulum_outputs,
)
from rtgait.scenario.loading import load_scenario


@pytest.fixture(scope="module")
def short_walk():
    """fig8's robot and timing, 3 steps with the change at step 2, short ends: a 5.5 s walk."""
    scenario = load_scenario("fig8")
    change = dataclasses.replace(scenario.changes[0], step=2, through=3)
    timing = Timing(0.7, 0.1, start=0.8, end=0.8, settle=0.8)
    return dataclasses.replace(scenario, name="fig8-short", steps=3, timing=timing, changes=(change,))


def test_the_scenario_walk_with_its_change_is_walked(short_walk):
    result = simulate_pendulum(short_walk, "stabilized", dt=0.005)
    assert not result.fell and result.ended_at_rest
    assert result.steps_completed == result.steps_planned == 4
    xs = [round(f.x, 9) for f in result.footprints]
    # Step 1 of 0.05 m, then the change to 0.15 m from step 2 on, then the closing step beside the last footprint.
    assert xs == [0.0, 0.0, 0.05, 0.2, 0.35, 0.35]
    assert result.extra["scenario"] == "fig8-short"
    assert result.mass == DEFAULT_MASS == 57.0


def test_defaults_period_and_mass(short_walk):
    assert scenario_mass(short_walk) == DEFAULT_MASS
    assert scenario_mass(short_walk, 90.0) == 90.0
    assert scenario_mass(types.SimpleNamespace(mass=42.0)) == 42.0  # a scenario with a [robot] mass
    with pytest.raises(ValueError, match="mass"):
        scenario_mass(short_walk, -1.0)
    result = simulate_pendulum(short_walk, "open-loop", mass=90.0)
    assert result.dt == DEFAULT_DT == 0.001 and result.mass == 90.0


def test_pushes_are_given_as_tuples_or_push(short_walk):
    assert as_push((1.0, 0.1, 20.0, -5.0)) == Push(1.0, 0.1, (20.0, -5.0))
    push = Push(2.0, 0.1, (0.0, 10.0))
    assert as_push(push) is push
    with pytest.raises(ValueError, match="push"):
        as_push((1.0, 0.1, 20.0))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="controller"):
        simulate_pendulum(short_walk, "magic")  # type: ignore[arg-type]


def test_outputs_csv_and_summary(short_walk, tmp_path):
    push = (2.7, 0.1, 60.0, 0.0)  # 6 N s forward, centred on the middle of step 3's single support
    result = simulate_pendulum(short_walk, "adaptive", pushes=[push], dt=0.004)
    summary = write_pendulum_outputs(result, tmp_path / "out", extra={"note": "test"})
    on_disk = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert on_disk == summary
    for key in ("fell", "fall_time", "steps_completed", "steps_planned", "step_adjustments", "pushes",
                "ended_at_rest", "zmp_tracking_error_rms", "real_time_factor", "controller", "model"):  # fmt: skip
        assert key in summary, key
    assert summary["model"] == "lipm" and summary["controller"] == "adaptive"
    assert summary["scenario"] == "fig8-short" and summary["note"] == "test"
    assert summary["fell"] is False and summary["ended_at_rest"] is True
    (entry,) = summary["pushes"]
    assert entry["start"] == 2.7 and entry["duration"] == 0.1 and entry["force"] == [60.0, 0.0, 0.0]
    assert entry["impulse"] == pytest.approx([6.0, 0.0, 0.0], rel=1e-12)
    assert summary["rows"] == result.ticks and summary["files"] == ["sim.csv", "summary.json"]

    with open(tmp_path / "out" / "sim.csv", encoding="utf-8", newline="") as stream:
        rows = list(csv.reader(stream))
    assert tuple(rows[0]) == PENDULUM_CSV_COLUMNS
    assert len(rows) - 1 == result.ticks
    table = {name: [row[i] for row in rows[1:]] for i, name in enumerate(rows[0])}
    np.testing.assert_allclose(np.array(table["t"], dtype=float), result.times, atol=1e-9)
    np.testing.assert_allclose(np.array(table["cog_x"], dtype=float), result.cog[:, 0], atol=1e-9)
    np.testing.assert_allclose(np.array(table["dcm_y"], dtype=float), result.dcm[:, 1], atol=1e-9)
    assert set(table["support"]) == {"double", "left", "right"}
    assert {int(v) for v in table["saturated"]} <= {0, 1}
    assert [int(v) for v in table["phase"]] == result.phase.tolist()


def test_a_fall_is_written_with_its_time(short_walk, tmp_path):
    result = simulate_pendulum(short_walk, "stabilized", pushes=[(2.55, 0.1, 0.0, 600.0)], dt=0.005)
    assert result.fell
    summary = write_pendulum_outputs(result, tmp_path)
    assert summary["fell"] is True and summary["ended_at_rest"] is False
    assert summary["fall_time"] == pytest.approx(result.times[-1])
    last = (tmp_path / "sim.csv").read_text().splitlines()[-1].split(",")
    assert math.isnan(float(last[PENDULUM_CSV_COLUMNS.index("zmp_command_x")]))


def test_the_step_limits_given_bound_every_landing(short_walk):
    """``step_adjustment`` (a robot's ``[stepping]`` limits, as ``simulate --model lipm --robot R`` passes them):
    every landing the pushed walk makes stays in that stride box around the footprint before it, which the core's
    default box (0.45 m wide) would not keep to."""
    from rtgait.core.laws.stepping import SteppingLimits
    from rtgait.core.planner.online import OnlinePlanner

    planner = OnlinePlanner(short_walk.planner_config(), short_walk.strides())
    planner.start(0.0)
    push = Push(planner.phase_start(3) + 0.3, 0.1, (0.0, -1500.0))  # 15 N s to the right, mid single support

    def widest(result) -> float:
        prints = result.footprints
        return max(abs(b.y - a.y) for a, b in itertools.pairwise(prints[1:]))  # lateral: the walk heads +x

    default = simulate_pendulum(short_walk, "adaptive", [push])
    assert default.step_adjustment_count and widest(default) > 0.3
    limits = SteppingLimits(min_width=0.15, max_width=0.25)
    bounded = simulate_pendulum(short_walk, "adaptive", [push], step_adjustment=limits.adjustment(short_walk.sole))
    assert bounded.step_adjustment_count and widest(bounded) <= 0.25 + 1e-9
