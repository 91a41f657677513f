"""Largest push each controller level survives on the point-mass pendulum, against the capturability bounds.

For every controller level (:mod:`rtgait.core.pendulum.loop`) and every horizontal direction (every 45 degrees, world
frame, 0 = the walking direction +x, 90 = to the left), the largest impulse that is survived is found by bisection:
"survived" means no fall and the walk ends at rest. The push is a constant force for 0.1 s on the mass, at one of
two instants of a step in the middle of the walk (step ``(n + 1) // 2`` of ``n``, the closing step counted):

* ``single``: centred on the middle of its single support;
* ``double``: starting when the double support after its landing begins (fig8's 0.1 s double support is then all
  inside the push).

For comparison, the capturability bounds of :mod:`rtgait.core.laws.capturability` (Koolen et al. 2012) in that
direction,
for the same instant and the step limits of the adaptive level's :class:`~rtgait.core.laws.stepping.StepAdjustment`:

* ``r_max``: reach of the stance sole from its ankle along the direction (:func:`reach_along`); in double support,
  the sole of the foot that carries the next single support;
* ``l_max``: the farthest landing of the stride box along the direction (its support function; 0 when the box lies
  behind, e.g. across the stance foot, where the feet would cross);
* first landing after ``max(remaining swing, min_time_to_touchdown)``, later ones every ``T_s + T_dbl``;
* the planned DCM's offset from the stance ankle at the push's centre.

``bound_1`` is the one-step bound, ``bound_N`` the bound for any number of steps. With ``--adapt-timing`` (step
timing adaptation, :class:`~rtgait.core.laws.stepping.StepAdjustment` ``adapt_timing``), ``bound_1 early`` is the
one-step bound with the earliest touch-down the adjustment may choose (the single support shortened to
``min_single_support``, but never sooner than ``min_time_to_touchdown`` after the push's centre). With
``--max-single-support S`` steps may also be held longer, up to ``S`` s: the ankle's answer to an outward push,
whose bound is the stance sole's own, ``bound_0 = m w (e - xi)`` with ``e`` the sole's edge along the push.

The bounds treat the push as an impulse at its centre (for a 0.1 s push the DCM moves ``sinh(w T / 2) / (w T /
2)`` = 1.005 times as far), the foot and the reach as discs, and the ZMP as jumping to the new foot at touch-down
(no double support): a guide, not a hard limit, most of all across the stance foot, where the other foot's sole
cannot be used before it lands. ``share`` is the largest impulse survived divided by ``bound_1``.

A walk that the pendulum does not survive even unpushed gets 0 (the point mass is unstable: ``open-loop`` on fig8,
12.7 s long, falls at about 10 s from round-off amplified by ``e^{w t}``; see :mod:`rtgait.core.pendulum.loop`).

Usage: ``python benchmarks/lipm_pushes.py [--json] [--controller C ...] [--scenario fig8] [--mass 57] [--dt 0.002]
[--phase single|double ...] [--tolerance 0.25] [--adapt-timing [--max-single-support S]] [--grid 32]
[--durations 4]``
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import time
from collections.abc import Sequence

import numpy as np

from rtgait.core.analysis.rollout import rollout
from rtgait.core.geometry.footsteps import Footstep
from rtgait.core.laws.capturability import max_capturable_impulse, reach_along
from rtgait.core.laws.stepping import StepAdjustment, SteppingLimits
from rtgait.core.pendulum.loop import DEFAULT_MASS, run_pendulum_loop
from rtgait.core.planner.levels import CONTROLLER_LEVELS
from rtgait.core.planner.online import OnlinePlanner
from rtgait.core.push import Push
from rtgait.scenario.loading import load_scenario
from rtgait.scenario.scenario import Scenario

PUSH_DURATION = 0.1
"""Length of every push (s)."""
DIRECTIONS = tuple(range(0, 360, 45))
"""Push directions (degrees, world frame, counter-clockwise from +x)."""
PHASES = ("single", "double")


@dataclasses.dataclass(frozen=True)
class PushSite:
    """Where and when a push acts: its window start (s), its centre (s), the stance foot of the capture, the side
    of the next landing and the time until it."""

    phase: str
    step: int
    start: float
    centre: float
    stance: Footstep
    remaining: float
    dcm: np.ndarray


def push_site(scenario: Scenario, phase: str, dt: float) -> PushSite:
    """The push instant of ``phase`` on the middle step of ``scenario``, and the planned state there."""
    step = (len(scenario.strides()) + 1) // 2
    timing = scenario.timing
    planner = OnlinePlanner(scenario.planner_config(), scenario.strides())
    planner.start(0.0)
    single_start = planner.phase_start(2 * step - 1)  # footstep changes move footprints, never phase times
    if phase == "single":
        centre = single_start + 0.5 * timing.single_support
        start = centre - 0.5 * PUSH_DURATION
        stance_index = step  # F[step] carries step `step`'s single support
        remaining = single_start + timing.single_support - centre
    else:
        start = single_start + timing.single_support
        centre = start + 0.5 * PUSH_DURATION
        stance_index = step + 1  # the foot that just landed carries the next single support
        remaining = start + timing.double_support + timing.single_support - centre
    # The plan as walked unpushed (changes at their deadlines), up to the push's centre.
    walked = rollout(planner, dt, scenario.sole, scenario.changes, duration=centre)
    dcm = np.array([walked.column("dcm_x")[-1], walked.column("dcm_y")[-1]])
    stance = walked.footprints[stance_index]
    return PushSite(phase, step, start, centre, stance, remaining, dcm)


def landing_reach(adjust: StepAdjustment, stance: Footstep, direction: np.ndarray) -> float:
    """``l_max`` along ``direction``: the largest ``L . u`` over the stride box of ``adjust`` around ``stance`` (m),
    at least 0. The box is ``|along| <= max_length``, ``min_width <= lateral <= max_width`` on the landing's side."""
    c, s = math.cos(stance.yaw), math.sin(stance.yaw)
    along = c * direction[0] + s * direction[1]  # the direction in the stance frame
    lateral = -s * direction[0] + c * direction[1]
    side = -1.0 if stance.side == "left" else 1.0  # the landing foot is the other one
    lateral *= side
    limits = adjust.limits
    reach = limits.max_length * abs(along) + max(limits.min_width * lateral, limits.max_width * lateral)
    return max(reach, 0.0)


def bounds(
    scenario: Scenario, site: PushSite, mass: float, direction_deg: float, adjust: StepAdjustment
) -> tuple[float, float, float]:
    """One-step and any-number-of-steps capturability bounds (N s) of an impulse at ``site`` along the direction,
    and the one-step bound with the earliest touch-down step timing adaptation may choose."""
    u = np.array([math.cos(math.radians(direction_deg)), math.sin(math.radians(direction_deg))])
    stance = site.stance
    r_max = reach_along(scenario.sole.corners(stance), stance.position, u)
    l_max = landing_reach(adjust, stance, u)
    w = math.sqrt(scenario.gravity / scenario.cog_height)
    common = dict(
        mass=mass, omega=w, r_max=r_max, l_max=l_max, step_time=scenario.timing.step_period,
        remaining=site.remaining, min_remaining=adjust.limits.min_time_to_touchdown,
    )  # fmt: skip
    offset = site.dcm - stance.position
    one = float(max_capturable_impulse(offset, u, steps=1, **common))
    many = float(max_capturable_impulse(offset, u, steps=math.inf, **common))
    shortening = max(scenario.timing.single_support - adjust.limits.min_single_support, 0.0)
    common["remaining"] = min(site.remaining, max(site.remaining - shortening, adjust.limits.min_time_to_touchdown))
    early = float(max_capturable_impulse(offset, u, steps=1, **common))
    return one, many, early


def survives(
    scenario: Scenario, controller: str, mass: float, dt: float, push: Push | None, adjust: StepAdjustment
) -> bool:
    """Whether the walk with ``push`` ends at rest without a fall."""
    result = run_pendulum_loop(
        scenario.planner_config(), scenario.strides(), scenario.sole, controller=controller, mass=mass, dt=dt,
        pushes=() if push is None else (push,), changes=scenario.changes, step_adjustment=adjust,
    )  # fmt: skip
    return not result.fell and result.ended_at_rest


def largest_impulse(
    scenario: Scenario,
    controller: str,
    mass: float,
    dt: float,
    site: PushSite,
    direction_deg: float,
    ceiling: float,
    tolerance: float,
    adjust: StepAdjustment,
) -> tuple[float, int]:
    """Bisection for the largest impulse (N s) survived along the direction, within ``tolerance``; and the runs."""
    u = (math.cos(math.radians(direction_deg)), math.sin(math.radians(direction_deg)))

    def ok(impulse: float) -> bool:
        force = impulse / PUSH_DURATION
        push = Push(site.start, PUSH_DURATION, (force * u[0], force * u[1]))
        return survives(scenario, controller, mass, dt, push, adjust)

    low, high, runs = 0.0, ceiling, 0
    while ok(high):  # the ceiling should fail; widen it if not
        runs += 1
        low, high = high, 2.0 * high
    runs += 1
    while high - low > tolerance:
        middle = 0.5 * (low + high)
        runs += 1
        if ok(middle):
            low = middle
        else:
            high = middle
    return low, runs


def run(
    scenario: Scenario,
    controllers: Sequence[str],
    phases: Sequence[str],
    mass: float,
    dt: float,
    tolerance: float,
    adjust: StepAdjustment | None = None,
) -> list[dict]:
    """Every case; ``adjust``: the adaptive level's step adjustment (default ``StepAdjustment(sole=scenario.sole)``)."""
    adjust = adjust if adjust is not None else StepAdjustment(sole=scenario.sole)
    cases = []
    sites = {phase: push_site(scenario, phase, dt) for phase in phases}
    for controller in controllers:
        unpushed = survives(scenario, controller, mass, dt, None, adjust)
        for phase in phases:
            site = sites[phase]
            for direction in DIRECTIONS:
                one, many, early = bounds(scenario, site, mass, direction, adjust)
                began = time.perf_counter()
                if unpushed:
                    # A ceiling that no controller can survive: twice the any-steps bound, at least 20 N s.
                    best, runs = largest_impulse(
                        scenario, controller, mass, dt, site, direction, max(2.0 * many, 20.0), tolerance, adjust
                    )
                else:
                    best, runs = 0.0, 0
                cases.append(
                    {
                        "controller": controller,
                        "phase": phase,
                        "direction_deg": direction,
                        "step": site.step,
                        "push_start": site.start,
                        "push_duration": PUSH_DURATION,
                        "max_impulse_Ns": best,
                        "capturability_bound_Ns": one,
                        "n_step_bound_Ns": many,
                        "capturability_bound_early_Ns": early,
                        "recovered_share": best / one if one > 0.0 else None,
                        "recovered_share_n_step": best / many if many > 0.0 else None,
                        "unpushed_survives": unpushed,
                        "runs": runs,
                        "seconds": time.perf_counter() - began,
                    }
                )
    return cases


def table(cases: list[dict], early: bool = False) -> str:
    """The cases as a text table; ``early``: with the column of the earliest-touch-down one-step bound."""
    extra = (f" {'b_1 early':>9}", f" {'N s':>9}") if early else ("", "")
    lines = [
        f"{'controller':<11} {'phase':<7} {'dir':>4} {'max J':>7} {'bound_1':>8} {'bound_N':>8}{extra[0]} {'share':>6}",
        f"{'':<11} {'':<7} {'deg':>4} {'N s':>7} {'N s':>8} {'N s':>8}{extra[1]} {'':>6}",
    ]
    for case in cases:
        share = case["recovered_share"]
        column = f" {case['capturability_bound_early_Ns']:>9.1f}" if early else ""
        lines.append(
            f"{case['controller']:<11} {case['phase']:<7} {case['direction_deg']:>4} {case['max_impulse_Ns']:>7.1f} "
            f"{case['capturability_bound_Ns']:>8.1f} {case['n_step_bound_Ns']:>8.1f}{column} "
            f"{'-' if share is None else f'{share:.2f}':>6}"
            + ("" if case["unpushed_survives"] else "  (falls unpushed)")
        )
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument(
        "--controller", action="append", choices=CONTROLLER_LEVELS, help="level(s) to test (default all)"
    )
    parser.add_argument("--scenario", default="fig8", help="built-in scenario name or TOML path (default fig8)")
    parser.add_argument("--mass", type=float, default=DEFAULT_MASS, help="point mass in kg (default 57)")
    parser.add_argument("--dt", type=float, default=0.002, help="control period in s (default 0.002)")
    parser.add_argument("--phase", action="append", choices=PHASES, help="push instant(s) (default both)")
    parser.add_argument("--tolerance", type=float, default=0.25, help="bisection resolution in N s (default 0.25)")
    parser.add_argument("--adapt-timing", action="store_true", help="adaptive: step timing adaptation on")
    parser.add_argument("--grid", type=int, default=32, help="adaptive: landing candidates per axis (default 32)")
    parser.add_argument("--durations", type=int, default=4, help="with --adapt-timing: durations (default 4)")
    parser.add_argument(
        "--max-single-support", type=float, default=None, metavar="S",
        help="with --adapt-timing: steps may also be held up to S s (default: only shortened)",
    )  # fmt: skip
    args = parser.parse_args(argv)
    scenario = load_scenario(args.scenario)
    if args.max_single_support is not None and not args.adapt_timing:
        parser.error("--max-single-support needs --adapt-timing")
    try:
        adjust = StepAdjustment(
            scenario.sole, SteppingLimits(max_single_support=args.max_single_support), grid=args.grid,
            adapt_timing=args.adapt_timing, durations=args.durations,
        )  # fmt: skip
    except ValueError as error:
        parser.error(str(error))
    controllers = args.controller or list(CONTROLLER_LEVELS)
    phases = args.phase or list(PHASES)
    began = time.perf_counter()
    cases = run(scenario, controllers, phases, args.mass, args.dt, args.tolerance, adjust)
    elapsed = time.perf_counter() - began
    if args.json:
        settings = {
            "scenario": scenario.name, "mass": args.mass, "dt": args.dt, "tolerance_Ns": args.tolerance,
            "push_duration": PUSH_DURATION, "seconds": elapsed, "adapt_timing": args.adapt_timing,
            "grid": args.grid, "durations": args.durations if args.adapt_timing else 1,
            "max_single_support": args.max_single_support,
        }  # fmt: skip
        json.dump({"settings": settings, "cases": cases}, sys.stdout, indent=2)
        print()
    else:
        print(
            f"{scenario.name}: {args.mass:g} kg point mass, dt {args.dt * 1e3:g} ms, 0.1 s pushes on step "
            f"{cases[0]['step'] if cases else '-'}, bisection to {args.tolerance:g} N s ({elapsed:.0f} s)"
        )
        print(table(cases, early=args.adapt_timing))


if __name__ == "__main__":
    main()
