"""Replanning latency and per-tick sampling cost of the online planner (run on demand, not in the test suite).

A long walk is driven the way a control loop drives it: one ``sample(t)`` per control period, and a footstep
change at every step (random length and width, handed over within the connection mode's deadline), so every
replan connects a genuinely new plan (3-step horizon, both axes). Reported:

* ``replan_us``: wall time of one replan as the planner measures it around the whole replan (state of the
  running plan, anchors, the precomputed-operator product, bookkeeping), excluding the first replan of each plan
  shape, which builds and caches that shape's operator (reported as ``pattern_build_us``);
* ``sample_us``: wall time of one ``sample(t)`` call on ticks that do not replan.

Usage: ``python benchmarks/replan.py [--json] [--steps N] [--dt S] [--mode real-time|quasi-real-time]``
"""

from __future__ import annotations

import argparse
import contextlib
import gc
import json
import time

import numpy as np

from rtgait.core.footsteps import Timing
from rtgait.core.online import OnlinePlanner, PlannerConfig, StepChangeTooLateError, straight_walk


def run(steps: int, dt: float, mode: str, horizon: int, seed: int, collect_garbage: bool = True) -> dict:
    config = PlannerConfig(timing=Timing(0.8, 0.2), connection=mode, horizon_steps=horizon)
    planner = OnlinePlanner(config, straight_walk(config, steps, 0.1))
    rng = np.random.default_rng(seed)
    planner.start(0.0)
    if not collect_garbage:
        gc.collect()
        gc.disable()  # as real-time Python control loops commonly do: no collector pauses inside a tick
    n_ticks = int(planner.end_time / dt)
    sample_ns = np.empty(n_ticks)
    replanned = np.zeros(n_ticks, dtype=bool)
    clock = time.perf_counter_ns
    next_change_step = 2
    for k in range(n_ticks):
        t = k * dt
        if next_change_step <= steps and t >= planner.change_deadline(next_change_step) - 0.5:
            with contextlib.suppress(StepChangeTooLateError):
                planner.change_step(next_change_step, length=rng.uniform(0.0, 0.2), width=rng.uniform(0.17, 0.23))
            next_change_step += 1
        plans_before = len(planner.plans)
        began = clock()
        planner.sample(t)
        sample_ns[k] = clock() - began
        replanned[k] = len(planner.plans) != plans_before
    times = np.array([p.compute_time for p in planner.plans]) * 1e6
    # A replan whose plan shape was not seen before also builds that shape's operator (once per shape).
    shapes_seen: set = set()
    first_of_shape = np.zeros(len(planner.plans), dtype=bool)
    for i, record in enumerate(planner.plans):
        shape = (record.phase == 0, record.n_segments)
        first_of_shape[i] = shape not in shapes_seen
        shapes_seen.add(shape)
    steady = times[~first_of_shape]
    samples = sample_ns[~replanned] / 1e3
    return {
        "replan_us": {"median": float(np.median(steady)), "p99": float(np.percentile(steady, 99))},
        "sample_us": {"median": float(np.median(samples)), "p99": float(np.percentile(samples, 99))},
        "pattern_build_us": {"median": float(np.median(times[first_of_shape])), "count": int(first_of_shape.sum())},
        "replans": len(steady),
        "samples": len(samples),
        "settings": {
            "steps": steps, "dt": dt, "connection": mode, "horizon_steps": horizon, "gc": collect_garbage,
        },
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--steps", type=int, default=400, help="steps of the walk (default 400)")
    parser.add_argument("--dt", type=float, default=0.001, help="control period in s (default 0.001)")
    parser.add_argument("--mode", default="real-time", choices=("real-time", "quasi-real-time"))
    parser.add_argument("--horizon", type=int, default=3, help="horizon in steps (default 3)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--no-gc", action="store_true", help="disable Python's cyclic garbage collector while timing")
    args = parser.parse_args()
    result = run(args.steps, args.dt, args.mode, args.horizon, args.seed, collect_garbage=not args.no_gc)
    gc.enable()
    if args.json:
        print(json.dumps(result))
        return
    print(
        f"walk: {args.steps} steps, dt {args.dt * 1e3:g} ms, {args.mode}, horizon {args.horizon} steps, "
        f"garbage collector {'off' if args.no_gc else 'on'}"
    )
    print(f"replan : median {result['replan_us']['median']:7.2f} us   p99 {result['replan_us']['p99']:7.2f} us"
          f"   ({result['replans']} replans)")
    print(f"sample : median {result['sample_us']['median']:7.2f} us   p99 {result['sample_us']['p99']:7.2f} us"
          f"   ({result['samples']} ticks)")
    print(f"operator build (once per plan shape): median {result['pattern_build_us']['median']:.0f} us, "
          f"{result['pattern_build_us']['count']} shapes")


if __name__ == "__main__":
    main()
