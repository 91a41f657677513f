"""Cost of closing the loop through the planner (run on demand, not in the test suite).

* ``tick_us``: one 1 kHz control tick of planner and feedback with ``feedback="measured"``: ``observe`` (the COG
  state measured), ``sample_values`` (replans at double-support starts included) and ``DcmFeedback.update``, over a
  10-step walk of the paper's fig8 timing (0.7 / 0.1 s);
* ``adjust_us``: one ``replan_now`` that needs a step adjustment (a push at mid single support, 24 directions and
  sizes): the plan from the measured state, the decision over ``grid**2`` candidates, the plan remade with the new
  landing; operators warm (each case is run twice and the second timed);
* ``decision_us`` and ``candidates_per_s``: the decision alone
  (:func:`rtgait.core.laws.landing_choice.propose_landing`);
* ``timing_adaptation``: the same three with step timing adaptation on (``adapt_timing``: ``--durations`` single
  supports times the square of ``--timing-grid`` landings, 4 x 256 = 1,024 candidates by default), the operators of the
  candidate timings included (built in one batch at the decision when the plan starts mid-phase, as here: every case
  has a fresh planner).

Wall times on a shared virtual machine vary between runs: run it a few times.

Usage: ``python benchmarks/stepping.py [--json] [--grid N] [--timing-grid N] [--durations D]``
"""

from __future__ import annotations

import argparse
import gc
import json
import time

import numpy as np

from rtgait.core.geometry.footsteps import SoleRect, Timing
from rtgait.core.geometry.support import support_polygon
from rtgait.core.laws import landing_choice
from rtgait.core.laws.feedback import DcmFeedback
from rtgait.core.laws.stepping import StepAdjustment
from rtgait.core.planner.online import OnlinePlanner, PlannerConfig, straight_walk

SOLE = SoleRect(0.13, 0.10, 0.07, 0.07)
DT = 0.001


def _config(grid: int, durations: int | None = None) -> PlannerConfig:
    adjust = StepAdjustment(SOLE, grid=grid, adapt_timing=durations is not None, durations=durations or 4)
    return PlannerConfig(
        timing=Timing(0.7, 0.1), connection="quasi-real-time", feedback="measured", step_adjustment=adjust
    )


def tick_cost(grid: int) -> dict:
    config = _config(grid)
    planner = OnlinePlanner(config, straight_walk(config, 10, 0.1))
    feedback = DcmFeedback(planner.w)
    planner.start(0.0)
    n = int(planner.end_time / DT)
    cost = np.empty(n)
    clock = time.perf_counter_ns
    polygons: dict[int, np.ndarray] = {}
    cog, vel, dcm, phase = (0.0, 0.0), (0.0, 0.0), (0.0, 0.0), 0
    for k in range(n):
        t = k * DT
        began = clock()
        planner.observe(t, cog, vel)
        values, _support, phase = planner.sample_values(t)
        polygon = polygons.get(phase)
        if polygon is None:  # once per phase, as a loop caches it
            polygon = polygons[phase] = support_polygon(planner.contact_feet(phase), SOLE)
        feedback.update((values.zmp_x, values.zmp_y), (values.dcm_x, values.dcm_y), dcm, polygon, DT)
        cost[k] = clock() - began
        # The robot follows the plan (the benchmark times the loop, not a disturbance).
        cog, vel, dcm = (values.cog_x, values.cog_y), (values.cog_vx, values.cog_vy), (values.dcm_x, values.dcm_y)
    us = cost / 1e3
    return {"median": float(np.median(us)), "p99": float(np.percentile(us, 99)), "ticks": n}


def _pushed_planner(config: PlannerConfig, push: tuple[float, float]) -> tuple[OnlinePlanner, float]:
    planner = OnlinePlanner(config, straight_walk(config, 8, 0.1))
    planner.start(0.0)
    t_push = planner.phase_start(5) + 0.25
    t = 0.0
    while t < t_push:
        s, _, _ = planner.sample_values(t)
        planner.observe(t, (s.cog_x, s.cog_y), (s.cog_vx, s.cog_vy))
        t += DT
    s, _, _ = planner.sample_values(t)
    planner.observe(t, (s.cog_x, s.cog_y), (s.cog_vx + push[0], s.cog_vy + push[1]))
    return planner, t


def adjust_cost(grid: int, durations: int | None = None) -> dict:
    config = _config(grid, durations)
    total, decision, retimed = [], [], 0
    original = landing_choice.propose_landing

    def timed(*args, **kwargs):
        began = time.perf_counter()
        result = original(*args, **kwargs)
        decision.append(time.perf_counter() - began)
        return result

    import rtgait.core.planner.adjusting as adjusting  # the planner calls it through this module's name

    adjusting.propose_landing = timed
    try:
        for angle in np.linspace(0.0, 2.0 * np.pi, 12, endpoint=False):
            for speed in (0.12, 0.2):
                push = (speed * np.cos(angle), speed * np.sin(angle))
                for attempt in range(2):
                    planner, t = _pushed_planner(config, push)
                    decision.clear()
                    began = time.perf_counter()
                    planner.replan_now(t)
                    elapsed = time.perf_counter() - began
                    if attempt == 1 and planner.step_adjustment_count:
                        total.append((elapsed, decision[-1]))
                        last = planner.step_adjustments[-1]
                        retimed += last.single_support < last.nominal_single_support
    finally:
        adjusting.propose_landing = original
    whole = np.array([a for a, _ in total]) * 1e6
    alone = np.array([b for _, b in total]) * 1e6
    return {
        "adjust_us": {"median": float(np.median(whole)), "p99": float(np.percentile(whole, 99))},
        "decision_us": {"median": float(np.median(alone)), "p99": float(np.percentile(alone, 99))},
        "candidates_per_s": float(grid * grid * (durations or 1) / (np.median(alone) * 1e-6)),
        "adjustments": len(total),
        "candidates": grid * grid * (durations or 1),
        **({"retimed": retimed} if durations else {}),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--grid", type=int, default=32, help="candidates per axis (default 32: 1,024 candidates)")
    parser.add_argument("--timing-grid", type=int, default=16, help="with timing adaptation (default 16)")
    parser.add_argument("--durations", type=int, default=4, help="single supports per decision (default 4)")
    args = parser.parse_args()
    gc.collect()
    result = {"tick_us": tick_cost(args.grid), **adjust_cost(args.grid)}
    result["timing_adaptation"] = adjust_cost(args.timing_grid, args.durations)
    if args.json:
        print(json.dumps(result))
        return
    tick, adjust, decide = result["tick_us"], result["adjust_us"], result["decision_us"]
    print(
        f"tick (observe + sample + DCM feedback), 1 kHz, feedback=measured: median {tick['median']:.2f} us, "
        f"p99 {tick['p99']:.2f} us over {tick['ticks']} ticks"
    )
    print(
        f"replan_now with a step adjustment over {result['candidates']} candidates: "
        f"median {adjust['median']:.0f} us, p99 {adjust['p99']:.0f} us ({result['adjustments']} pushes)"
    )
    print(
        f"the decision alone: median {decide['median']:.0f} us, p99 {decide['p99']:.0f} us: "
        f"{result['candidates_per_s']:.3g} candidates/s"
    )
    timing = result["timing_adaptation"]
    print(
        f"with timing adaptation ({args.durations} single supports x {args.timing_grid**2} landings): replan_now "
        f"median {timing['adjust_us']['median']:.0f} us, p99 {timing['adjust_us']['p99']:.0f} us; the decision "
        f"median {timing['decision_us']['median']:.0f} us; {timing['retimed']} of {timing['adjustments']} "
        "shortened the step"
    )


if __name__ == "__main__":
    main()
