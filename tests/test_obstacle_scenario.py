"""The paper's Fig. 1 at the pendulum level: the built-in scenario 'obstacle' walked under each connection mode, its
``[[obstacle]]`` entries and their errors, and ``rtgait plan obstacle``."""

from __future__ import annotations

import dataclasses
import itertools
import json
import math
from pathlib import Path

import numpy as np
import pytest
from scenario_files import scenario_text

from rtgait.cli.main import main
from rtgait.core.analysis.rollout import rollout
from rtgait.core.geometry.footsteps import stride_between
from rtgait.core.obstacle.avoid import ObstacleReaction
from rtgait.core.obstacle.walk import avoiding_rollout
from rtgait.core.planner.online import OnlinePlanner
from rtgait.scenario import ScenarioError, load_scenario

SCENARIO = load_scenario("obstacle")
BOX = SCENARIO.obstacles[0]
MARGIN = ObstacleReaction(BOX, SCENARIO.sole, SCENARIO.dt).margin


def walk(mode: str) -> tuple[OnlinePlanner, ObstacleReaction, dict[float, tuple[np.ndarray, np.ndarray]]]:
    """The scenario in ``mode``, sampled every tick and just before and after every replan (at 1e-7 s): returns the
    planner, the reaction and, per replan time, the samples ``(before, after)``."""
    scenario = dataclasses.replace(SCENARIO, connection=mode)
    planner = OnlinePlanner(scenario.planner_config(), scenario.strides())
    reaction = ObstacleReaction(BOX, scenario.sole, scenario.dt)
    planner.start(0.0)
    replans = [planner.phase_start(q) for q in range(2, 2 * (scenario.steps + 1) + 1, 2)]
    edges = {}
    for t in np.arange(0.0, planner.end_time, scenario.dt):
        if reaction.result is None and t >= BOX.seen_at:
            reaction(planner, float(t))
        planner.sample(float(t))
        for r in replans:
            if t + 1e-7 < r <= t + scenario.dt and r not in edges:
                edges[r] = (planner.sample(r - 1e-7).values, planner.sample(r + 1e-7).values)
    return planner, reaction, edges


def sole_gap(foot, box) -> float:
    """Distance (m) between a sole and the box, both square to the world axes (> 0 apart)."""
    sole = SCENARIO.sole
    low, high = (-sole.inner, sole.outer) if foot.side == "left" else (-sole.outer, sole.inner)
    return max(box.x - box.length / 2 - (foot.x + sole.front), foot.x - sole.back - (box.x + box.length / 2),
               box.y - box.width / 2 - (foot.y + high), foot.y + low - (box.y + box.width / 2))  # fmt: skip


@pytest.mark.parametrize("mode", ["real-time", "quasi-real-time"])
def test_the_changed_footsteps_are_off_the_box_within_the_limits_and_the_cog_and_zmp_stay_continuous(mode: str) -> None:
    planner, reaction, edges = walk(mode)
    result = reaction.result
    assert result is not None and result.chosen is not None and result.chosen.side == "left"
    before, after = result.before, planner.footprints()
    # The walk as planned stepped on the box; as changed, no sole comes within the margin of it.
    assert min(sole_gap(f, BOX) for f in before) < 0.0
    assert min(sole_gap(f, BOX) for f in after) >= MARGIN - 1e-9
    # The first step the mode lets change: real-time the one about to lift off (step 3, seen in the double
    # support after step 2), quasi-real-time the next one; every footprint before it kept.
    first = {"real-time": 3, "quasi-real-time": 4}[mode]
    assert result.first_open == first
    assert after[: first + 1] == list(before[: first + 1]) and after[first + 1] != before[first + 1]
    limits = planner.config
    for i in range(first, len(after) - 1):
        width = abs(after[i + 1].y - after[i].y)
        sideways = abs(after[i + 1].y - after[i - 1].y)
        length = after[i + 1].x - after[i].x
        assert limits.min_step_width - 1e-9 <= width <= limits.step_width + limits.max_step_lateral + 1e-9
        assert math.hypot(length / limits.max_step_length, sideways / limits.max_step_lateral) <= 1.0 + 1e-9
    # COG position and velocity, and ZMP position, continuous across every replan (1e-7 s either side).
    assert len(edges) == SCENARIO.steps + 1
    for left, right in edges.values():
        assert np.abs(right[0:2] - left[0:2]).max() < 1e-6  # COG (m)
        assert np.abs(right[3:5] - left[3:5]).max() < 1e-5  # COG velocity (m/s)
        assert np.abs(right[9:11] - left[9:11]).max() < 1e-5  # ZMP (m)


def test_quasi_real_time_avoids_it_with_the_zmp_inside_and_real_time_leaves_the_soles() -> None:
    """The paper's Section 4.1: real-time connection changes the step about to lift off and leaves one double support
    to absorb it, which at T_dbl = 0.1 s takes the ZMP out of the support polygon; quasi-real-time decides one double
    support earlier (the step after) and keeps it inside."""
    margins = {}
    for mode in ("real-time", "quasi-real-time"):
        scenario = dataclasses.replace(SCENARIO, connection=mode)
        result, seen = avoiding_rollout(scenario.planner_config(), scenario.strides(), scenario.dt, scenario.sole,
                                        scenario.obstacles)  # fmt: skip
        (avoidance,) = seen
        margins[mode] = result.zmp_margin_min
        # The batched prediction the choice was made on is the rollout's own number.
        assert avoidance.predicted_by == "batch"
        assert avoidance.chosen.zmp_margin == pytest.approx(result.zmp_margin_min, abs=1e-9)
        if mode == "real-time":
            # The failure is the change being absorbed: after the obstacle was seen, in the connecting double support.
            assert result.times[result.worst_index] > avoidance.time
            assert result.support[result.worst_index] == "double"
    assert margins["quasi-real-time"] >= 0.0
    assert margins["real-time"] < -0.05


def test_without_obstacles_the_walk_is_the_plain_rollout() -> None:
    plain = dataclasses.replace(SCENARIO, obstacles=())
    result, seen = avoiding_rollout(plain.planner_config(), plain.strides(), plain.dt, plain.sole, ())
    reference = rollout(OnlinePlanner(plain.planner_config(), plain.strides()), plain.dt, plain.sole)
    assert seen == () and np.array_equal(result.values, reference.values)


BOX_TEXT = """
[[obstacle]]
x = 1.0
y = 0.0
length = 0.3
width = 0.2
height = 0.3
seen_at = 1.5
"""


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("width = 0.2", "width = -0.2", "obstacle[0].width must be a number > 0 m, got -0.2"),
        ("height = 0.3", "height = -1", "obstacle[0].height must be a number >= 0 m, got -1"),
        ("seen_at = 1.5", "seen_at = 999.0", "obstacle[0].seen_at must be within the walk (before"),
        ("seen_at = 1.5", "seen_at = nan", "obstacle[0].seen_at must be a number >= 0 s, got nan"),
        ("seen_at = 1.5\n", "seen_at = 1.5\nyaw = 7.0\n", "obstacle[0].yaw must be within [-pi, pi] rad, got 7.0"),
        ("seen_at = 1.5\n", "", "missing required key obstacle[0].seen_at"),
        ("seen_at = 1.5\n", "seen_at = 1.5\nradius = 2\n", "unknown key obstacle[0].radius"),
        ("[[obstacle]]", "[obstacle]", "obstacle must be an array of tables, written [[obstacle]]"),
    ],
)
def test_bad_obstacle_entries_are_refused_in_one_line(tmp_path: Path, old: str, new: str, message: str) -> None:
    path = tmp_path / "probe.toml"
    path.write_text(scenario_text() + BOX_TEXT.replace(old, new), encoding="utf-8")
    with pytest.raises(ScenarioError) as error:
        load_scenario(path)
    assert message in str(error.value) and "\n" not in str(error.value)


def test_an_obstacle_entry_and_stride_limits_load(tmp_path: Path) -> None:
    path = tmp_path / "probe.toml"
    limits = "\n[robot.velocity]\nmax_step_lateral = 0.2\nmin_step_width = 0.15\n"
    text = scenario_text().replace("\n[timing]", limits + "\n[timing]", 1) + BOX_TEXT.replace(
        "seen_at", "yaw = 0.5\nseen_at"
    )
    path.write_text(text, encoding="utf-8")
    scenario = load_scenario(path)
    (box,) = scenario.obstacles
    assert (box.x, box.y, box.length, box.width, box.height, box.yaw, box.seen_at) == (
        1.0,
        0.0,
        0.3,
        0.2,
        0.3,
        0.5,
        1.5,
    )
    config = scenario.planner_config()
    assert (config.max_step_lateral, config.min_step_width, config.max_step_length) == (0.2, 0.15, 0.3)
    path.write_text(text.replace("max_step_lateral = 0.2", "max_step_lateral = -1"), encoding="utf-8")
    with pytest.raises(ScenarioError, match=r"robot\.velocity\.max_step_lateral must be within"):
        load_scenario(path)


def test_plan_obstacle_reports_and_summarises_each_mode(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "out"
    assert main(["plan", "obstacle", "--out", str(out), "--no-figures"]) == 0
    printed = capsys.readouterr().out
    assert "obstacle    real-time: seen at 2.550 s, steps left from step 3" in printed
    assert "obstacle    quasi-real-time: seen at 2.550 s, steps left from step 4" in printed
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    walks = {w["connection"]: w for w in summary["obstacle_walks"]}
    assert walks["quasi-real-time"]["avoided"] and not walks["quasi-real-time"]["zmp_outside"]
    assert walks["real-time"]["zmp_outside"]
    assert summary["zmp_margin_min"] == walks["quasi-real-time"]["zmp_margin_min"]  # the scenario's own mode
    assert summary["files"] == ["trajectory.csv", "summary.json"]


def test_the_figure_draws_one_top_view_per_mode(tmp_path: Path) -> None:
    pytest.importorskip("matplotlib")
    from rtgait.io.obstacle_outputs import obstacle_runs
    from rtgait.viz.obstacle_figure import draw_obstacle_walks, plot_obstacle_walks

    runs = obstacle_runs(SCENARIO)
    figure = draw_obstacle_walks(runs, SCENARIO.sole, "obstacle")
    titles = [ax.get_title() for ax in figure.axes]
    assert titles[0].startswith("real-time: steps left from step 3") and "LEAVES the support polygon" in titles[0]
    assert titles[1].startswith("quasi-real-time: steps left from step 4") and "ZMP inside" in titles[1]
    path = plot_obstacle_walks(runs, SCENARIO.sole, "obstacle", tmp_path / "obstacle.png")
    assert path.stat().st_size > 10_000


def test_the_closest_sole_distance_of_a_run() -> None:
    from rtgait.io.obstacle_outputs import closest_sole_distance

    sole = SCENARIO.sole  # 0.23 x 0.14 m, the ankle 0.10 m from the heel
    # Two ticks: the right sole's toe 0.05 m short of the box's near face, then the left sole 0.02 m beside its side.
    near_face, side_face = BOX.x - BOX.length / 2, BOX.y + BOX.width / 2
    poses = np.array([
        [[0.0, 1.0, 0.0], [near_face - sole.front - 0.05, BOX.y, 0.0]],
        [[BOX.x, side_face + sole.inner + 0.02, 0.0], [0.0, -1.0, 0.0]],
    ])  # fmt: skip
    assert closest_sole_distance(poses, sole, BOX) == pytest.approx(0.02)
    assert closest_sole_distance(poses[:1], sole, BOX) == pytest.approx(0.05)
    poses[0, 1, 0] += 0.10  # the toe now 0.05 m into the box
    assert closest_sole_distance(poses, sole, BOX) == 0.0


@pytest.mark.parametrize(("x", "seen_at"), [(3.95, 15.0), (3.95, 12.0), (0.5, 5.0)])
def test_a_box_seen_too_late_or_already_passed_leaves_the_walk_as_it_is(x: float, seen_at: float) -> None:
    """Under the last footsteps when the walk is ending, too close to step around, or behind the robot: the walk is
    not changed (and says so), it does not fail."""
    box = dataclasses.replace(BOX, x=x, seen_at=seen_at)
    plain = rollout(OnlinePlanner(SCENARIO.planner_config(), SCENARIO.strides()), SCENARIO.dt, SCENARIO.sole)
    result, (avoidance,) = avoiding_rollout(SCENARIO.planner_config(), SCENARIO.strides(), SCENARIO.dt,
                                            SCENARIO.sole, (box,))  # fmt: skip
    assert avoidance.chosen is None or avoidance.chosen.side == "none"
    assert result.footprints == plain.footprints


def test_every_candidate_s_batched_prediction_is_its_rollout_s_margin() -> None:
    """Each side weighed (round the box, or over a low one: lengths changed) is predicted by the batched operators as
    a rollout that hands the same change to the planner at the same tick measures it."""
    low = dataclasses.replace(BOX, y=-0.12, length=0.10, width=0.10, height=0.01)
    config = dataclasses.replace(SCENARIO, connection="real-time").planner_config()
    _, (avoidance,) = avoiding_rollout(config, SCENARIO.strides(), SCENARIO.dt, SCENARIO.sole, (low,))
    assert [c.side for c in avoidance.candidates] == ["left", "right", "over"]
    k0 = avoidance.first_open
    for candidate in avoidance.candidates:
        prints = candidate.detour.footprints[k0:]
        strides = [stride_between(a, b) for a, b in itertools.pairwise(prints)]

        def change(planner: OnlinePlanner, t: float, strides: list = strides) -> None:
            planner.set_strides(strides, k0)

        result = rollout(OnlinePlanner(config, SCENARIO.strides()), SCENARIO.dt, SCENARIO.sole,
                         reactions=[(low.seen_at, change)])  # fmt: skip
        assert candidate.zmp_margin == pytest.approx(result.zmp_margin_min, abs=1e-9), candidate.side
