"""Batched planning (rtgait.core.analysis.batch) against one rollout per case, on the same cases, on one core.

The cases: the paper's fig4 walk (10 steps, change at step 5 from 0.05 m to the case's length, to the walk's end)
for 2 connection modes x 20 double-support times (0.05 to 1.5 s) x ``--lengths`` new lengths (-0.1 to 0.45 m):
200,000 cases by default. The batched path evaluates them all, family by family (each family built on first use,
its build included in the time). The single path (``rollout`` + the numbers ``rtgait plan`` reports) takes a
random sample of ``--single`` of the same cases; its rate is per case, like the batched one.

    python benchmarks/batch.py            # human-readable
    python benchmarks/batch.py --json     # {"cases_per_s": ..., "single_cases_per_s": ...}

numpy is held to one thread (BLAS, OpenMP) so that "one core" means one core.
"""

from __future__ import annotations

import os

for _name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from dataclasses import replace  # noqa: E402

import numpy as np  # noqa: E402

from rtgait.core import OnlinePlanner, Timing, rollout  # noqa: E402
from rtgait.core.analysis.batch import StraightWalk, evaluate_parameters, walk_family  # noqa: E402
from rtgait.scenario.loading import load_scenario  # noqa: E402
from rtgait.viz.margin_marker import margin_marker  # noqa: E402

MODES = ("real-time", "quasi-real-time")
DOUBLES = tuple(float(v) for v in np.round(np.geomspace(0.05, 1.5, 20), 3))


def cases(lengths: int):
    """``(walk, theta)`` per family: every case of the benchmark."""
    base = load_scenario("fig4")
    for mode in MODES:
        for double in DOUBLES:
            scenario = replace(base, connection=mode, timing=Timing(base.timing.single_support, double))
            walk = StraightWalk(scenario.planner_config(), scenario.sole, scenario.dt, scenario.steps,
                                scenario.step_length, scenario.changes)  # fmt: skip
            theta = np.repeat(walk.parameters()[None], lengths, axis=0)
            theta[:, 3] = np.linspace(-0.1, 0.45, lengths)
            yield scenario, walk, theta


def batched(lengths: int) -> tuple[int, float]:
    walk_family.cache_clear()  # every family is built inside the timed region
    families = list(cases(lengths))
    began = time.perf_counter()
    n = 0
    for _, walk, theta in families:
        n += len(evaluate_parameters(walk, theta))
    return n, time.perf_counter() - began


def single(lengths: int, sample: int, seed: int = 1) -> tuple[int, float]:
    families = list(cases(lengths))
    rng = np.random.default_rng(seed)
    picks = [(int(rng.integers(len(families))), int(rng.integers(lengths))) for _ in range(sample)]
    elapsed = 0.0
    for family, row in picks:
        scenario, _, theta = families[family]
        case = replace(scenario, changes=(replace(scenario.changes[0], length=float(theta[row, 3])),))
        began = time.perf_counter()
        run = rollout(OnlinePlanner(case.planner_config(), case.strides()), case.dt, case.sole, case.changes)
        zmp = np.stack([run.column("zmp_x"), run.column("zmp_y")], axis=1)
        ref = np.stack([run.column("zmp_ref_x"), run.column("zmp_ref_y")], axis=1)
        np.abs((zmp - ref)[run.free_segment_mask()]).max(axis=0)
        margin_marker(run.times, run.margin, [t for t, _ in run.changes])
        elapsed += time.perf_counter() - began
    return sample, elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--lengths", type=int, default=5000, help="new step lengths per family (default 5000)")
    parser.add_argument("--single", type=int, default=40, help="cases the single path rolls out (default 40)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args()
    n, seconds = batched(args.lengths)
    m, single_seconds = single(args.lengths, args.single)
    rate, single_rate = n / seconds, m / single_seconds
    if args.json:
        print(json.dumps({"cases_per_s": round(rate), "single_cases_per_s": round(single_rate, 1)}))
        return
    print(f"batched: {n} cases ({len(MODES) * len(DOUBLES)} families) in {seconds:.2f} s: {rate:,.0f} cases/s")
    print(f"single:  {m} rollouts in {single_seconds:.2f} s: {single_rate:,.1f} cases/s")
    print(f"speed-up {rate / single_rate:,.0f}x")


if __name__ == "__main__":
    main()
