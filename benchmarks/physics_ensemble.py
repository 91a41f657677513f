"""The paper's cases in physics over an ensemble of physics settings: is an outcome a property of the walk, or of one
choice of timestep, contact and servo parameters? (Run on demand, not in tests.)

Each of the paper's cases (fig4, fig6, fig7, fig8; the paper: fig4 loses its balance, the others walk) is walked
in MuJoCo by :func:`rtgait.io.sim_run.simulate` under every setting of a fixed, seeded sample of physics settings:

* physics step 1 ms or 0.5 ms (half the settings each; the control period stays the robot's),
* contact time constant 2-10 ms and damping ratio 1-2 (MuJoCo's ``solref``),
* sole friction 0.6-1.0,
* every joint's armature, and every joint's kp and kd together, at 50-150 % of the drives' gains (``--gains``:
  ``stiff``, the derived stiff servos, by default; ``robot``, the real robot's own gains, with the feed-forward
  torques of whole-body inverse dynamics; ``--motor-model`` adds the motors' torque-speed envelopes, friction and the
  command a control period late).

The continuous parameters are a Latin hypercube sample (each parameter's range cut into as many equal strata as
there are settings, one value drawn in each stratum, the strata shuffled independently per parameter), so even a
small ensemble spans each range evenly. The outcome of a run is one of ``walked`` (every step landed, no fall, no
foot tipped onto an edge), ``tipped`` (a loaded foot rolled onto an edge of its sole, and the robot did not
fall), ``fell`` (the run ended in a fall) or ``incomplete`` (no fall, no tip, but a step did not land).

Runs are spread over worker processes (2 by default: this project's CI machine has 2 cores); progress goes to
stderr. ``--controller`` names the controller level (:mod:`rtgait.control.controller`): ``open-loop`` (the default
here: the plan alone, the paper's assumption, whose outcomes the paper reports), ``stabilized`` or ``adaptive``.

``--refine N`` divides every setting's physics step by ``N`` (the rest of the setting unchanged): a convergence check,
since an outcome that changes when only the step is refined belongs to the discretisation, not to the setting.
``--per-setting`` prints, after the summary, one row per setting: its values and each case's outcome, with the
time of the first tip-over (``t``) or of the fall (``f``) on the walk's clock (s).

``--state estimated|truth`` says what the closed-loop levels act on (default the estimate from the simulated sensors;
``open-loop`` acts on the plan alone either way).

Usage: ``python benchmarks/physics_ensemble.py [--json] [--per-setting] [--robot R] [--controller C] [--state S]
[--gains stiff|robot] [--motor-model] [--quick] [--settings N] [--seed S] [--refine N] [--workers W]
[--cases fig4,fig6,...]``
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import json
import math
import os
import sys
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Any

import numpy as np

from rtgait.estimation.estimator import DEFAULT_STATE, STATE_SOURCES
from rtgait.interface.command import GAIN_SETS

CASES = ("fig4", "fig6", "fig7", "fig8")
EXPECTED = {"fig4": "loses balance", "fig6": "walks", "fig7": "walks", "fig8": "walks"}
"""The paper's outcome of each case (Harada et al., Section 5): fig4's change is too large for its connection."""
OUTCOMES = ("walked", "tipped", "fell", "incomplete")
RANGES = {
    "contact_timeconst": (0.002, 0.010),  # s
    "contact_dampratio": (1.0, 2.0),
    "friction": (0.6, 1.0),
    "armature_scale": (0.5, 1.5),
    "gain_scale": (0.5, 1.5),
}
"""The continuous physics parameters of the ensemble (:class:`rtgait.sim.model.SimConfig` fields) and their ranges."""
PHYSICS_DTS = (0.001, 0.0005)
"""Physics steps of the ensemble (s), each used by half of the settings."""


@dataclasses.dataclass(frozen=True)
class Drives:
    """How the joints are driven in every setting (:class:`rtgait.sim.config.SimConfig` fields): the gain set that
    ``gain_scale`` multiplies, and whether the motors have their envelopes, friction and delay."""

    gains: str = "stiff"
    motor_model: bool = False


def ensemble(n: int, seed: int) -> list[dict[str, float]]:
    """``n`` physics settings: a Latin hypercube sample of :data:`RANGES`, physics steps alternating over
    :data:`PHYSICS_DTS` (see the module docstring). The same ``n`` and ``seed`` give the same settings."""
    rng = np.random.default_rng(seed)
    settings: list[dict[str, float]] = [{} for _ in range(n)]
    for name, (low, high) in RANGES.items():
        strata = rng.permutation(n)
        values = low + (high - low) * (strata + rng.random(n)) / n
        for setting, value in zip(settings, values, strict=True):
            setting[name] = round(float(value), 6)
    for i, setting in enumerate(settings):
        setting["physics_dt"] = PHYSICS_DTS[i % len(PHYSICS_DTS)]
    return settings


def classify(result: Any) -> str:
    """The outcome of a run: ``fell``, ``tipped``, ``incomplete`` or ``walked`` (see the module docstring)."""
    if result.fell:
        return "fell"
    if result.tipped:
        return "tipped"
    if result.steps_completed < result.steps_planned:
        return "incomplete"
    return "walked"


@functools.lru_cache(maxsize=1)
def _robot(name: str) -> Any:
    from rtgait.robot.model import RobotModel

    return RobotModel.load(name)


@functools.lru_cache(maxsize=4)
def _sim(robot_name: str, setting: tuple[tuple[str, Any], ...]) -> Any:
    """The MuJoCo model of one setting (its physics and drives), kept in the worker for the setting's other cases."""
    from rtgait.sim.model import SimConfig, build_sim_model

    return build_sim_model(_robot(robot_name), SimConfig(meshes=False, **dict(setting)))


def run_one(
    robot_name: str, controller: str, scenario_name: str, index: int, setting: dict[str, float], state: str,
    drives: Drives | None = None,
) -> dict:  # fmt: skip
    """Walk one case under one setting, the controller on ``state`` (in a worker process); returns its outcome and a
    few numbers."""
    from rtgait.io.sim_run import mujoco_messages, simulate
    from rtgait.scenario.loading import load_scenario
    from rtgait.sim.loop_options import LoopOptions

    robot = _robot(robot_name)
    drives = drives or Drives()
    sim = _sim(robot_name, tuple(sorted({**setting, **dataclasses.asdict(drives)}.items())))
    scenario = load_scenario(scenario_name)
    began = time.perf_counter()
    with mujoco_messages() as warnings:
        result = simulate(scenario, robot, sim=sim, controller=controller, options=LoopOptions(state=state))  # type: ignore[arg-type]
    rms = result.zmp_tracking_error_rms
    return {
        "scenario": scenario_name,
        "setting": index,
        "outcome": classify(result),
        "steps": f"{result.steps_completed}/{result.steps_planned}",
        "tip_time": result.tip_time,
        "fall_time": result.fall_time,
        "fall_cause": result.fall_cause,
        "zmp_error_rms": None if not math.isfinite(rms) else rms,
        "legs_touched": result.legs_touched,
        "mujoco_warnings": len(warnings),
        "wall_time": time.perf_counter() - began,
        "pid": os.getpid(),
    }


def run_ensemble(
    robot: str, controller: str, cases: tuple[str, ...], settings: list[dict[str, float]], workers: int, quiet: bool,
    state: str = DEFAULT_STATE, drives: Drives | None = None,
) -> list[dict]:  # fmt: skip
    """Every case under every setting, the controller on ``state`` and the joints on ``drives`` (default the stiff
    servos), in ``workers`` processes; progress on stderr unless ``quiet``."""
    tasks = [
        (robot, controller, case, i, setting, state, drives) for i, setting in enumerate(settings) for case in cases
    ]
    runs: list[dict] = []
    began = time.perf_counter()
    with ProcessPoolExecutor(max_workers=workers) as pool:
        futures = [pool.submit(run_one, *task) for task in tasks]
        for done, future in enumerate(as_completed(futures), start=1):
            run = future.result()
            runs.append(run)
            if not quiet:
                elapsed = time.perf_counter() - began
                left = elapsed / done * (len(tasks) - done)
                print(
                    f"\r[{done}/{len(tasks)}] {run['scenario']} setting {run['setting']}: {run['outcome']:<10} "
                    f"{elapsed:5.0f} s elapsed, about {left:4.0f} s left",
                    end="" if done < len(tasks) else "\n",
                    file=sys.stderr,
                    flush=True,
                )
    return sorted(runs, key=lambda r: (r["scenario"], r["setting"]))


def summarize(robot: str, controller: str, cases: tuple[str, ...], runs: list[dict]) -> list[dict]:
    """Per case: the share of settings in which it walked, fell, tipped (and was incomplete), and the share that
    agrees with the paper's outcome (:data:`EXPECTED`)."""
    table = []
    for case in cases:
        outcomes = [r["outcome"] for r in runs if r["scenario"] == case]
        counts = Counter(outcomes)
        n = len(outcomes)
        agree = counts["walked"] if EXPECTED[case] == "walks" else counts["fell"] + counts["tipped"]
        errors = [r["zmp_error_rms"] for r in runs if r["scenario"] == case and r["zmp_error_rms"] is not None]
        table.append(
            {
                "scenario": case,
                "robot": robot,
                "controller": controller,
                "settings": n,
                **{outcome: counts[outcome] / n for outcome in OUTCOMES},
                "paper": EXPECTED[case],
                "agrees_with_paper": agree / n,
                "zmp_error_rms_median": float(np.median(errors)) if errors else None,
            }
        )
    return table


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--per-setting", action="store_true", help="also print every setting's outcomes")
    parser.add_argument("--robot", default="talos")
    parser.add_argument(
        "--controller", default="open-loop", choices=("open-loop", "stabilized", "adaptive"),
        help="controller level (default open-loop, the paper's assumption)",
    )  # fmt: skip
    parser.add_argument("--quick", action="store_true", help="8 settings instead of the default 48")
    parser.add_argument("--settings", type=int, default=None, help="number of settings (default 48, 8 with --quick)")
    parser.add_argument("--seed", type=int, default=2024, help="seed of the sample of settings")
    parser.add_argument("--refine", type=int, default=1, help="divide every setting's physics step by this (default 1)")
    parser.add_argument("--workers", type=int, default=2, help="worker processes (default 2)")
    parser.add_argument("--cases", default=",".join(CASES), help="comma-separated cases (default: the paper's four)")
    parser.add_argument("--state", choices=STATE_SOURCES, default=DEFAULT_STATE,
                        help=f"what the controller acts on (default {DEFAULT_STATE})")  # fmt: skip
    parser.add_argument("--gains", choices=GAIN_SETS, default="stiff",
                        help="the gains scaled: stiff (default) or robot, with feed-forward torques")  # fmt: skip
    parser.add_argument("--motor-model", action="store_true",
                        help="the motors' torque-speed envelopes, friction and one period of delay")  # fmt: skip
    args = parser.parse_args()
    drives = Drives(gains=args.gains, motor_model=args.motor_model)
    cases = tuple(case for case in args.cases.split(",") if case)
    unknown = [case for case in cases if case not in EXPECTED]
    if unknown:
        parser.error(f"--cases: {', '.join(unknown)} has no paper outcome to compare with (known: {', '.join(CASES)})")
    n = args.settings if args.settings is not None else (8 if args.quick else 48)
    if n < 1 or args.workers < 1 or args.refine < 1:
        parser.error("--settings, --refine and --workers must be >= 1")
    settings = ensemble(n, args.seed)
    for setting in settings:
        setting["physics_dt"] /= args.refine
    began = time.perf_counter()
    runs = run_ensemble(
        args.robot, args.controller, cases, settings, args.workers, quiet=False, state=args.state, drives=drives
    )
    wall = time.perf_counter() - began
    table = summarize(args.robot, args.controller, cases, runs)
    if args.json:
        report = {
            "cases": table,
            "seed": args.seed,
            "refine": args.refine,
            "state": args.state,
            "drives": dataclasses.asdict(drives),
            "ensemble": settings,
            "runs": runs,
            "wall_time": wall,
        }
        print(json.dumps(report))
        return
    motors = " with the motor model" if drives.motor_model else ""
    print(f"{args.robot}, {args.controller} on the {args.state} state, {drives.gains} gains{motors}: {n} physics "
          f"settings (seed {args.seed}), {len(runs)} runs in {wall:.0f} s")  # fmt: skip
    for name, (low, high) in RANGES.items():
        print(f"  {name}: {low:g} to {high:g}")
    print(f"  physics_dt: {', '.join(f'{dt / args.refine:g}' for dt in PHYSICS_DTS)} s")
    print()
    print("| case | paper | walked | tipped | fell | incomplete | agrees with the paper | ZMP error RMS (median) |")
    print("|---|---|---|---|---|---|---|---|")
    for row in table:
        error = row["zmp_error_rms_median"]
        print(
            f"| {row['scenario']} | {row['paper']} | {row['walked']:.0%} | {row['tipped']:.0%} | {row['fell']:.0%} | "
            f"{row['incomplete']:.0%} | {row['agrees_with_paper']:.0%} | "
            f"{'-' if error is None else f'{error * 1000:.0f} mm'} |"
        )
    disagreeing = [r for r in runs if (r["outcome"] == "walked") != (EXPECTED[r["scenario"]] == "walks")]
    if disagreeing:
        print("\nsettings that disagree with the paper:")
        for run in disagreeing:
            setting = dataclasses.asdict(_Setting(**settings[run["setting"]]))
            print(f"  {run['scenario']} setting {run['setting']}: {run['outcome']} ({run['steps']} steps) {setting}")
    if args.per_setting:
        print()
        print(per_setting_table(cases, settings, runs))


def _outcome_cell(run: dict) -> str:
    """One run as ``outcome steps`` plus ``t <tip time>`` and ``f <fall time>`` where they happened (s)."""
    cell = f"{run['outcome']} {run['steps']}"
    if run.get("tip_time") is not None:
        cell += f" t {run['tip_time']:.2f}"
    if run.get("fall_time") is not None:
        cell += f" f {run['fall_time']:.2f}"
    return cell


def per_setting_table(cases: tuple[str, ...], settings: list[dict[str, float]], runs: list[dict]) -> str:
    """A markdown table, one row per setting in order of contact time constant: the setting's values (physics step
    and contact time constant in ms, the rest as given) and each case's outcome (:func:`_outcome_cell`)."""
    by_setting: dict[int, dict[str, dict]] = {}
    for run in runs:
        by_setting.setdefault(run["setting"], {})[run["scenario"]] = run
    columns = ("setting", "dt (ms)", "timeconst (ms)", "dampratio", "friction", "armature", "gains", *cases)
    header = "| " + " | ".join(columns) + " |"
    lines = [header, "|" + "---|" * (7 + len(cases))]
    for index in sorted(by_setting, key=lambda i: settings[i]["contact_timeconst"]):
        s = settings[index]
        values = (
            f"| {index} | {s['physics_dt'] * 1000:g} | {s['contact_timeconst'] * 1000:.2f} "
            f"| {s['contact_dampratio']:.2f} | {s['friction']:.2f} | {s['armature_scale']:.2f} "
            f"| {s['gain_scale']:.2f} |"
        )
        cells = [_outcome_cell(by_setting[index][case]) if case in by_setting[index] else "-" for case in cases]
        lines.append(values + " " + " | ".join(cells) + " |")
    return "\n".join(lines)


@dataclasses.dataclass(frozen=True)
class _Setting:
    """One setting, for printing in a fixed order."""

    physics_dt: float
    contact_timeconst: float
    contact_dampratio: float
    friction: float
    armature_scale: float
    gain_scale: float


if __name__ == "__main__":
    main()
