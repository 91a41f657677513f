"""The estimator's touch-downs against the simulator's contacts, and what happened before a fall, from a run's log.

For each ``touchdown`` event of ``sim.parquet`` (:mod:`rtgait.sim.log_file`; the landings the controller acted on):

* ``kind``: the landing's classification (``early``, ``on time``, ``late``, ``re-landing``);
* ``after_plan`` (ms): the detection's time after the plan's touch-down (the first tick of the double support the
  foot's swing ends in; negative for an early landing of the next swing: the swing's own end lies ahead);
* ``contact``: whether the simulator has the sole on the floor at that tick (a touch-down without is a false one);
  ``lag`` (ms): the detection's time after the simulator's first contact of that landing, or for a false one the
  time until the first contact after it (negative);
* ``z``, ``z_target`` (mm): the sole's true height and its target's at the detection;
* ``force``, ``force_estimate`` (N): the simulator's normal force and the estimate's vertical force on that foot;
* ``jump`` (mm): the move of the foot's IK target over the tick (the re-anchoring), along x and y;
* ``off_x``, ``off_out`` (mm): the swing sole's true position minus its target at the plan's touch-down, forward and
  outward (away from the other foot: +y for the left foot, -y for the right);
* ``pitch``, ``roll`` (mrad): the base's largest tilt over the next 0.3 s.

``--window S`` also lists the events of the last ``S`` seconds before the fall (or the run's end) with the same
columns where they name a foot, and the ticks in that window where the estimate's loaded state differs from the
simulator's contact.

    python benchmarks/touchdowns.py OUT/sim.parquet [--window 0.5] [--each]
"""

from __future__ import annotations

import argparse
import math
from typing import Any

import numpy as np

from rtgait.sim.log_file import read_sim_log

SIDES = ("left", "right")
AFTER = 0.3
"""Window (s) over which a touch-down's base tilt is taken."""


def _tilt(c: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The base's roll and pitch (rad) at each tick, ``R = Rz Ry Rx``."""
    qx, qy, qz, qw = (np.asarray(c[f"base_q{a}"]) for a in "xyzw")
    roll = np.arctan2(2.0 * (qw * qx + qy * qz), 1.0 - 2.0 * (qx * qx + qy * qy))
    pitch = np.arcsin(np.clip(2.0 * (qw * qy - qz * qx), -1.0, 1.0))
    return roll, pitch


def _plan_touchdown(support: np.ndarray, tick: int) -> int:
    """The plan's touch-down of the swing a landing at ``tick`` ends: in a double support, the tick it began; in a
    single support (an early landing), the tick the next one begins."""
    k = tick
    if support[tick] == "double":
        while k > 0 and support[k - 1] == "double":
            k -= 1
        return k
    while k < len(support) - 1 and support[k] != "double":
        k += 1
    return k


def _lag(contact: np.ndarray, tick: int, dt: float) -> float:
    """ms after the simulator's first contact of this landing; for a false one minus the time to the next contact."""
    if contact[tick]:
        k = tick
        while k > 0 and contact[k - 1]:
            k -= 1
        return (tick - k) * dt * 1e3
    k = tick
    while k < len(contact) - 1 and not contact[k]:
        k += 1
    return -(k - tick) * dt * 1e3


def foot_row(c: dict[str, np.ndarray], tick: int, side: str, dt: float) -> dict[str, Any]:
    """The columns of the module docstring for foot ``side`` at ``tick``."""
    support = np.asarray(c["support_planned"]).astype(str)
    contact = np.asarray(c[f"{side}_contact"], dtype=bool)
    plan = _plan_touchdown(support, tick)
    out = 1.0 if side == "left" else -1.0
    before, after = max(tick - 1, 0), min(tick + 1, len(contact) - 1)
    roll, pitch = _tilt(c)
    window = slice(tick, tick + round(AFTER / dt))
    return {
        "t": float(c["t"][tick]), "side": side, "after_plan": (tick - plan) * dt * 1e3,
        "contact": bool(contact[tick]), "lag": _lag(contact, tick, dt),
        "z": c[f"{side}_sole_z"][tick] * 1e3, "z_target": c[f"{side}_target_z"][tick] * 1e3,
        "force": float(c[f"{side}_normal_force"][tick]), "force_estimate": float(c[f"{side}_force_z"][tick]),
        "jump_x": (c[f"{side}_target_x"][after] - c[f"{side}_target_x"][before]) * 1e3,
        "jump_y": (c[f"{side}_target_y"][after] - c[f"{side}_target_y"][before]) * 1e3,
        "off_x": (c[f"{side}_sole_x"][plan] - c[f"{side}_target_x"][plan]) * 1e3,
        "off_out": out * (c[f"{side}_sole_y"][plan] - c[f"{side}_target_y"][plan]) * 1e3,
        "pitch": float(np.max(np.abs(pitch[window]))) * 1e3, "roll": float(np.max(np.abs(roll[window]))) * 1e3,
    }  # fmt: skip


def _line(r: dict[str, Any]) -> str:
    contact = "yes" if r["contact"] else "NO "
    return " | ".join((
        f"{r['side']:5s} {r['after_plan']:+5.0f} ms contact {contact} lag {r['lag']:+5.0f} ms",
        f"z {r['z']:5.1f} target {r['z_target']:5.1f} mm",
        f"F {r['force']:4.0f} est {r['force_estimate']:4.0f} N",
        f"jump ({r['jump_x']:+5.1f}, {r['jump_y']:+5.1f}) off (x {r['off_x']:+5.1f}, out {r['off_out']:+5.1f}) mm",
        f"next {AFTER:g} s pitch {r['pitch']:5.1f} roll {r['roll']:5.1f} mrad",
    ))  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("log", help="a sim.parquet")
    parser.add_argument("--window", type=float, default=0.0, help="list the last S seconds before the fall (s)")
    parser.add_argument("--each", action="store_true", help="one line per touch-down")
    args = parser.parse_args()
    log = read_sim_log(args.log)
    c, meta = log.columns, log.metadata
    dt = float(meta["control_dt"])
    kinds = {e["tick"]: str(e["detail"]).split()[0] for e in meta["events"] if e["kind"] == "landing"}
    rows = []
    for e in meta["events"]:
        if e["kind"].startswith("touchdown") and e["side"] in SIDES:
            rows.append({**foot_row(c, int(e["tick"]), e["side"], dt), "kind": kinds.get(e["tick"], e["kind"])})
    if not rows:
        raise SystemExit(f"{args.log}: no touch-down")
    end = float(meta["fall_time"]) if meta.get("fell") else float(c["t"][-1])
    print(f"{args.log}: " + (f"fell at {end:.2f} s" if meta.get("fell") else "did not fall"))
    false = [r for r in rows if not r["contact"]]
    real = [r for r in rows if r["contact"]]
    counts = {k: sum(r["kind"] == k for r in rows) for k in sorted({r["kind"] for r in rows})}
    print(f"{len(rows)} touch-downs {counts}; {len(false)} without contact in the simulator")

    def median(key: str, of: list[dict[str, Any]]) -> float:
        return float(np.nanmedian([r[key] for r in of]))

    if false:
        print(f"  false: sole {median('z', false):.1f} mm up (median, {max(r['z'] for r in false):.1f} at most), "
              f"estimated force {median('force_estimate', false):.0f} N (median)")  # fmt: skip
    if real:
        print(f"  real: detected {median('lag', real):.0f} ms after the first contact (median), the simulator's "
              f"force then {median('force', real):.0f} N (median)")  # fmt: skip
    print(f"  the swing sole off its target at the plan's touch-down: forward {median('off_x', rows):+.1f} mm, "
          f"outward {median('off_out', rows):+.1f} mm (medians)")  # fmt: skip
    if args.each:
        for r in rows:
            print(f"  {r['t']:7.3f} {r['kind']:10s} {_line(r)}")
    if args.window > 0.0:
        start = end - args.window
        print(f"events from {start:.3f} s:")
        for e in meta["events"]:
            if e["t"] < start or e["kind"] == "replan":
                continue
            detail = str(e["detail"])[:100]
            foot = "  " + _line(foot_row(c, int(e["tick"]), e["side"], dt)) if e["side"] in SIDES else ""
            print(f"  {e['t']:7.3f} {e['kind']:16s} {detail}{foot}")
        t = np.asarray(c["t"])
        window = (t >= start) & (t <= end)
        for side in SIDES:
            truth = np.asarray(c[f"{side}_contact"], dtype=bool)[window]
            loaded = np.asarray(c[f"{side}_loaded"], dtype=bool)[window]
            print(f"  {side}: loaded in the air {int(np.sum(loaded & ~truth))} ticks, on the floor not loaded "
                  f"{int(np.sum(~loaded & truth))} ticks, of {len(truth)}")  # fmt: skip
    if not math.isfinite(end):
        raise SystemExit("the run has no end time")


if __name__ == "__main__":
    main()
