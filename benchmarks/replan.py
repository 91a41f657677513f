"""Replanning latency and per-tick sampling cost of the online planner (run on demand, not in the test suite).

A long walk is driven the way a control loop drives it: one ``sample(t)`` per control period, and a footstep
change at every step (random length and width, handed over within the connection mode's deadline), so every
replan connects a genuinely new plan (3-step horizon, both axes). Reported:

* ``replan_us``: wall time of one replan inside that loop, as the planner measures it around the whole replan
  (state of the running plan, anchors, the precomputed-operator product, bookkeeping). Between two replans the
  loop runs hundreds of samples, so the replan starts with cold caches;
* ``sample_us``: wall time of one ``sample(t)`` call on ticks that do not replan;
* ``replan_back_to_back_us``: replans of consecutive double supports with nothing in between (warm caches);
* ``operator_build_us``: building one plan shape's operator, which ``start()`` does once per shape.

With ``--terrain`` every step also climbs or descends (``TERRAIN_RISE`` up for five steps, then down for five, over
and over, as on a staircase): each plan carries its vertical column (the footholds' heights, the 3D-DCM/VRP form of
``docs/method.md``), and its in-loop replan time is the one to compare with the level walk's (the goal: under 2x).

With ``--feedback measured`` the planner is told the measured COG state before every sample (``observe``; here the
plan's own state of the tick before, as a robot that follows it), so every replan connects from it; ``observe_us`` is
the wall time of one such call (its bounds checks included: :mod:`rtgait.core.input_bounds`).

Wall times on a shared virtual machine vary from run to run by a factor of two or more: run it a few times.

Usage: ``python benchmarks/replan.py [--json] [--steps N] [--dt S] [--mode real-time|quasi-real-time]
[--feedback planned|measured] [--no-gc] [--terrain]``
"""

from __future__ import annotations

import argparse
import contextlib
import gc
import json
import time

import numpy as np

from rtgait.core.geometry.footsteps import Stride, Timing
from rtgait.core.lipm.pattern import PatternKey, PlanOperator
from rtgait.core.planner.online import OnlinePlanner, PlannerConfig, StepChangeTooLateError, straight_walk


def run(
    steps: int,
    dt: float,
    mode: str,
    horizon: int,
    seed: int,
    collect_garbage: bool = True,
    feedback: str = "planned",
    terrain: bool = False,
) -> dict:
    config = PlannerConfig(timing=Timing(0.8, 0.2), connection=mode, horizon_steps=horizon, feedback=feedback)
    measured = feedback == "measured"
    planner = OnlinePlanner(config, walk_strides(config, steps, terrain))
    rng = np.random.default_rng(seed)
    planner.start(0.0)
    if not collect_garbage:
        gc.collect()
        gc.disable()  # as real-time Python control loops commonly do: no collector pauses inside a tick
    n_ticks = int(planner.end_time / dt)
    sample_ns = np.empty(n_ticks)
    observe_ns = np.empty(n_ticks if measured else 0)
    replanned = np.zeros(n_ticks, dtype=bool)
    clock = time.perf_counter_ns
    next_change_step = 2
    cog, vel = (0.0, 0.0), (0.0, 0.0)
    for k in range(n_ticks):
        t = k * dt
        if next_change_step <= steps and t >= planner.change_deadline(next_change_step) - 0.5:
            with contextlib.suppress(StepChangeTooLateError):
                planner.change_step(next_change_step, length=rng.uniform(0.0, 0.2), width=rng.uniform(0.17, 0.23))
            next_change_step += 1
        if measured:
            began = clock()
            planner.observe(t, cog, vel)
            observe_ns[k] = clock() - began
        plans_before = len(planner.plans)
        began = clock()
        sample = planner.sample(t)
        sample_ns[k] = clock() - began
        if measured:
            cog, vel = sample.cog[:2].tolist(), sample.cog_vel[:2].tolist()
        replanned[k] = len(planner.plans) != plans_before
    steady = np.array([p.compute_time for p in list(planner.plans)[1:]]) * 1e6  # all but the initial plan
    samples = sample_ns[~replanned] / 1e3
    result = {
        "replan_us": {"median": float(np.median(steady)), "p99": float(np.percentile(steady, 99))},
        "sample_us": {"median": float(np.median(samples)), "p99": float(np.percentile(samples, 99))},
        "replan_back_to_back_us": back_to_back(config, steps, terrain),
        "operator_build_us": operator_build(config),
        "replans": len(steady),
        "samples": len(samples),
        "settings": {
            "steps": steps,
            "dt": dt,
            "connection": mode,
            "horizon_steps": horizon,
            "gc": collect_garbage,
            "feedback": feedback,
            "terrain": terrain,
        },
    }
    if measured:
        observe_us = observe_ns / 1e3
        result["observe_us"] = {"median": float(np.median(observe_us)), "p99": float(np.percentile(observe_us, 99))}
    return result


TERRAIN_RISE = 0.1
"""Height change of each step of ``--terrain`` (m)."""


def walk_strides(config: PlannerConfig, steps: int, terrain: bool) -> list[Stride]:
    """A straight walk of 0.1 m steps; with ``terrain``, up ``TERRAIN_RISE`` for five steps, down for five, ..."""
    strides = straight_walk(config, steps, 0.1)
    if not terrain:
        return strides
    return [
        Stride(s.length, s.width, s.turn, rise=TERRAIN_RISE if (k // 5) % 2 == 0 else -TERRAIN_RISE)
        for k, s in enumerate(strides[:-1])
    ] + strides[-1:]


def back_to_back(config: PlannerConfig, steps: int, terrain: bool = False) -> dict:
    """Replans with nothing in between (one sample per double support): the cost with warm caches."""
    planner = OnlinePlanner(config, walk_strides(config, steps, terrain))
    planner.start(0.0)
    for k in range(steps):
        planner.sample(planner.phase_start(2 * k))
    times = np.array([p.compute_time for p in list(planner.plans)[1:-4]]) * 1e6  # steady walking only
    return {"median": float(np.median(times)), "p99": float(np.percentile(times, 99))}


def operator_build(config: PlannerConfig) -> dict:
    """Building one plan shape's operator (done in ``start()`` for every shape a walk needs)."""
    planner = OnlinePlanner(config, straight_walk(config, 10, 0.1))
    key = PatternKey(
        kinds=tuple(planner.timeline.kind(q) for q in range(2, 9)),
        durations=tuple(planner.timeline.duration(q) for q in range(2, 9)),
        w=planner.w,
        first_degree=config.first_degree,
    )
    times = []
    for _ in range(50):
        began = time.perf_counter()
        PlanOperator(key)
        times.append((time.perf_counter() - began) * 1e6)
    return {"median": float(np.median(times))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--steps", type=int, default=400, help="steps of the walk (default 400)")
    parser.add_argument("--dt", type=float, default=0.001, help="control period in s (default 0.001)")
    parser.add_argument("--mode", default="real-time", choices=("real-time", "quasi-real-time"))
    parser.add_argument("--horizon", type=int, default=3, help="horizon in steps (default 3)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--no-gc", action="store_true", help="disable Python's cyclic garbage collector while timing")
    parser.add_argument("--feedback", default="planned", choices=("planned", "measured"))
    parser.add_argument("--terrain", action="store_true", help="every step climbs or descends 0.1 m (module doc)")
    args = parser.parse_args()
    result = run(
        args.steps, args.dt, args.mode, args.horizon, args.seed, collect_garbage=not args.no_gc,
        feedback=args.feedback, terrain=args.terrain,
    )  # fmt: skip
    gc.enable()
    if args.json:
        print(json.dumps(result))
        return
    print(
        f"walk: {args.steps} steps, dt {args.dt * 1e3:g} ms, {args.mode}, horizon {args.horizon} steps, "
        f"garbage collector {'off' if args.no_gc else 'on'}, feedback {args.feedback}"
        + (f", terrain +-{TERRAIN_RISE:g} m per step" if args.terrain else "")
    )
    print(
        f"replan : median {result['replan_us']['median']:7.2f} us   p99 {result['replan_us']['p99']:7.2f} us"
        f"   ({result['replans']} replans)"
    )
    print(
        f"sample : median {result['sample_us']['median']:7.2f} us   p99 {result['sample_us']['p99']:7.2f} us"
        f"   ({result['samples']} ticks)"
    )
    if "observe_us" in result:
        print(f"observe: median {result['observe_us']['median']:7.2f} us   p99 {result['observe_us']['p99']:7.2f} us")
    print(
        f"replan back to back: median {result['replan_back_to_back_us']['median']:7.2f} us   "
        f"p99 {result['replan_back_to_back_us']['p99']:7.2f} us"
    )
    print(f"operator build (once per plan shape, in start()): median {result['operator_build_us']['median']:.0f} us")


if __name__ == "__main__":
    main()
