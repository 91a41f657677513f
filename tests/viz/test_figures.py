"""The plan and pendulum figures: the minimum-margin marker, the deviation scale, tick labels, formats, labels."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ElementTree
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from rtgait.core.analysis.rollout import Rollout, rollout
from rtgait.core.planner.online import OnlinePlanner
from rtgait.io.plan_summary import summarize
from rtgait.scenario.loading import load_scenario
from rtgait.scenario.scenario import Scenario
from rtgait.viz.deviation_figure import MIN_DEVIATION_SPAN
from rtgait.viz.figures import DRAW, MARKER_GID
from rtgait.viz.margin_marker import margin_marker
from rtgait.viz.pendulum import PendulumRun, draw_pendulum
from rtgait.viz.run_data import FigureInfo, PlanRun
from rtgait.viz.style import TIME_LABEL, CleanFormatter, save, signed_mm

NEGATIVE_ZERO = re.compile(r"^[-\N{MINUS SIGN}]0(\.0*)?( mm)?$")


def _roll(name: str) -> tuple[Rollout, Scenario]:
    scenario = load_scenario(name)
    planner = OnlinePlanner(scenario.planner_config(), scenario.strides())
    return rollout(planner, scenario.dt, scenario.sole, scenario.changes), scenario


def _info(scenario: Scenario) -> FigureInfo:
    return FigureInfo(f"{scenario.name} ({scenario.connection})", scenario.sole, scenario.nominal_footprints())


@pytest.fixture(scope="module")
def fig6() -> tuple[Rollout, Scenario]:
    return _roll("fig6")


@pytest.fixture(scope="module")
def fig8() -> tuple[Rollout, Scenario]:
    return _roll("fig8")


def _by_gid(figure: Figure, gid: str) -> list[Line2D]:
    return [line for ax in figure.axes for line in ax.get_lines() if line.get_gid() == gid]


# ----- the minimum ZMP margin ----------------------------------------------------------------------------------


def test_margin_marker_rule() -> None:
    times = np.arange(10) * 0.5
    unique = np.array([3, 2, 1, 2, 3, 0.5, 3, 3, 3, 3.0])
    assert margin_marker(times, unique, [1.0]).index == 5 and margin_marker(times, unique).tied == 1
    tied = np.array([3, 1, 1, 2, 1, 1, 3, 1, 3, 3.0])
    marked = margin_marker(times, tied, [1.6])  # the first tie at or after the change (t = 2.0 s, tick 4)
    assert (marked.index, marked.tied, marked.tied_duration) == (4, 5, 2.5)
    assert margin_marker(times, tied).index == 1  # no change: the first tie
    assert margin_marker(times, tied, [4.2]).index == 1  # no tie after the change: the first tie
    assert margin_marker(times, tied + np.r_[0, 0, 5e-10, 0, 0, 0, 0, 0, 0, 0], [0.7]).index == 2  # within 1 nm


def test_fig6_marker_is_the_summarys_instant_not_the_start(fig6: tuple[Rollout, Scenario]) -> None:
    result, scenario = fig6
    summary = summarize(result, scenario)
    # The minimum itself is unchanged: the half sole width, reached at every single-support tick.
    assert summary["zmp_margin_min"] == result.zmp_margin_min == pytest.approx(0.07, abs=1e-9)
    when = summary["zmp_margin_min_time"]
    assert when > 0.0 and when > float(result.times[result.worst_index])  # not the first tie (the first lift-off)
    assert when >= result.changes[0][0]  # the first tied instant once the change is decided
    run, info = PlanRun.from_rollout(result), _info(scenario)
    (margin_marker_line,) = _by_gid(DRAW["zmp_margin"](run, info), MARKER_GID)
    assert margin_marker_line.get_xdata()[0] == pytest.approx(when)
    assert margin_marker_line.get_ydata()[0] == pytest.approx(summary["zmp_margin_min"] * 1000)
    (top_marker,) = _by_gid(DRAW["top_view"](run, info), MARKER_GID)
    xy = [top_marker.get_xdata()[0], top_marker.get_ydata()[0]]
    assert xy == pytest.approx(summary["zmp_margin_min_position"])
    assert "reached for" in top_marker.get_label()  # the caption says the minimum is tied


def test_fig4_unique_minimum_is_marked_where_it_is() -> None:
    result, scenario = _roll("fig4")
    summary = summarize(result, scenario)
    assert summary["zmp_margin_min_time"] == float(result.times[result.worst_index])
    (marker,) = _by_gid(DRAW["zmp_margin"](PlanRun.from_rollout(result), _info(scenario)), MARKER_GID)
    assert marker.get_xdata()[0] == summary["zmp_margin_min_time"] and "reached for" not in marker.get_label()


# ----- the deviation figure ------------------------------------------------------------------------------------


def test_fig8_deviation_axes_are_scaled_on_the_replans(fig8: tuple[Rollout, Scenario]) -> None:
    result, scenario = fig8
    summary = summarize(result, scenario)
    figure = DRAW["zmp_deviation"](PlanRun.from_rollout(result), _info(scenario))
    panels = [ax for ax in figure.axes if ax.get_ylabel().endswith("deviation [mm]")]
    assert len(panels) == 2
    for ax, replan_max in zip(panels, summary["zmp_deviation_max"], strict=True):
        low, high = ax.get_ylim()
        replans = next(line for line in ax.get_lines() if line.get_gid() == "deviation-replans").get_ydata()
        initial = next(line for line in ax.get_lines() if line.get_gid() == "deviation-initial").get_ydata()
        assert np.nanmax(np.abs(replans)) == pytest.approx(replan_max * 1000)
        assert low <= np.nanmin(replans) and np.nanmax(replans) <= high  # every replan in view
        assert high - low <= max(1.3 * (np.nanmax(replans) - min(np.nanmin(replans), 0.0)), MIN_DEVIATION_SPAN + 1e-9)
        if np.nanmin(initial) < low:  # the initial plan's dip is clipped and marked at the edge, not in the scale
            assert _by_gid(figure, "deviation-off-scale") and "off scale" in ax.get_title(loc="right")
    # y: the start from rest swings the ZMP some 54 mm, the replans at most 3 mm; the scale is the replans'.
    low, high = panels[1].get_ylim()
    assert high - low < 10.0 and summary["zmp_deviation_max"][1] * 1000 < high


def test_a_deviation_panel_spans_at_least_a_few_mm(fig6: tuple[Rollout, Scenario]) -> None:
    result, scenario = fig6  # lateral replans within 0.3 mm of the reference
    figure = DRAW["zmp_deviation"](PlanRun.from_rollout(result), _info(scenario))
    low, high = figure.axes[1].get_ylim()
    assert high - low == pytest.approx(MIN_DEVIATION_SPAN)


# ----- labels, units, time origin ------------------------------------------------------------------------------


def test_tick_formatter_never_writes_a_negative_zero() -> None:
    formatter = CleanFormatter(scale=1000.0)
    locs = [-0.002, -1e-19, 0.002, 0.004]
    formatter.set_locs(locs)
    assert [formatter(v) for v in locs] == ["\N{MINUS SIGN}2", "0", "2", "4"]
    formatter = CleanFormatter()
    locs = [-0.05, -0.025, -0.0, 0.025]
    formatter.set_locs(locs)
    assert [formatter(v) for v in locs] == ["\N{MINUS SIGN}0.050", "\N{MINUS SIGN}0.025", "0.000", "0.025"]
    assert signed_mm(-1e-6) == "0.0 mm" and signed_mm(-0.0341) == "\N{MINUS SIGN}34.1 mm"


def _tick_labels(figure: Figure) -> list[str]:
    figure.canvas.draw()  # tick labels are made at drawing time
    return [label.get_text() for ax in figure.axes for label in [*ax.get_xticklabels(), *ax.get_yticklabels()]]


def _pendulum_run() -> PendulumRun:
    from rtgait.io.pendulum_run import simulate_pendulum

    scenario = load_scenario("fig8")
    result = simulate_pendulum(scenario, "adaptive", [(5.0, 0.1, 250.0, 0.0)])
    return PendulumRun.from_result(result, "fig8 (quasi-real-time)")


def test_every_figure_labels_its_axes_in_one_unit_style_from_the_walks_start(fig8: tuple[Rollout, Scenario]) -> None:
    result, scenario = fig8
    run, info = PlanRun.from_rollout(result), _info(scenario)
    figures = {stem: draw(run, info) for stem, draw in DRAW.items()}
    figures["pendulum"] = draw_pendulum(_pendulum_run())
    for stem, figure in figures.items():
        for ax in figure.axes:
            assert re.search(r"\[(m|mm|s)\]", ax.get_ylabel()), (stem, ax.get_ylabel())
        bottom = figure.axes[-1]
        assert re.search(r"\[(m|s)\]", bottom.get_xlabel()), stem
        if stem != "top_view":
            assert bottom.get_xlabel() == TIME_LABEL and all(ax.get_xlim()[0] == 0.0 for ax in figure.axes), stem
        assert not [text for text in _tick_labels(figure) if NEGATIVE_ZERO.match(text)], stem
        labels = [text for ax in figure.axes for text in (ax.get_xlabel(), ax.get_ylabel())]
        assert not [text for text in labels if re.search(r"\((m|mm|s|N s)\)", text)], stem  # "[m]", never "(m)"
    legends = {stem: " ".join(t.get_text() for legend in f.legends for t in legend.get_texts()) for stem, f in
               figures.items()}  # fmt: skip
    assert "double support" in legends["zmp_cog"] and "double support" in legends["zmp_margin"]
    assert "free first segment" in legends["zmp_deviation"]
    assert "double support" in legends["pendulum"] and "push on the mass (25.0 N s" in legends["pendulum"]


# ----- formats -------------------------------------------------------------------------------------------------


def test_pdf_and_svg_files_are_valid_and_reproducible(fig6: tuple[Rollout, Scenario], tmp_path: Path) -> None:
    result, scenario = fig6
    run, info = PlanRun.from_rollout(result), _info(scenario)
    pdf = save(DRAW["zmp_cog"](run, info), tmp_path / "a.pdf").read_bytes()
    assert pdf.startswith(b"%PDF-") and pdf.rstrip().endswith(b"%%EOF")
    svg = save(DRAW["zmp_cog"](run, info), tmp_path / "a.svg")
    assert ElementTree.parse(svg).getroot().tag == "{http://www.w3.org/2000/svg}svg"
    # No date, fixed ids: the same figure gives the same bytes (what lets a remade figure be compared).
    assert save(DRAW["zmp_cog"](run, info), tmp_path / "b.svg").read_bytes() == svg.read_bytes()
    assert save(DRAW["zmp_cog"](run, info), tmp_path / "b.pdf").read_bytes() == pdf
