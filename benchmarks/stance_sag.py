"""Where a soft stance leg puts the swing foot at the plan's touch-down, and what a late call does to the swing hip.

**At each planned touch-down** (the first tick of a double support after a single support, as in
``benchmarks/swing_end.py``): the swing sole's true position minus its target along the world's ``x`` (forward on a
walk along it) and ``z``; the part of it the stance leg's joint errors make, carried by forward kinematics from the
true stance sole through the legs' relative transform ``R(q) = T_st(q)^-1 T_sw(q)`` (which does not depend on the base),

    stance leg    = T_st R(q_a) - T_st R(q_cmd)      (q_a: the measured joints with the swing leg's commanded)
    stance hip    = T_st R(q_h) - T_st R(q_cmd)      (q_h: the commanded joints with the stance hip pitch measured)

(mm); the base's pitch less the IK's (mrad: negative, the pelvis leans back); and the stance hip pitch's servo
torque ``kp (q_cmd - q)`` at the drives' robot gains (N m, the description's ``robot_kp``): the torque the
feed-forward leaves to the servo.

**At each late call** (``--late-calls``: the controller's support back to single inside the plan's double support,
the tick a late foot's descent starts): the swing hip pitch's torque over the two ticks around it and its largest
change over the next 40 ms (N m), and the swing foot's next touch-down within 0.1 s: its delay, the estimate's vertical
force, whether the simulator had contact and the sole's height.

    python benchmarks/stance_sag.py OUT/sim.parquet [OUT2/sim.parquet ...] [--each] [--late-calls]

Prints the medians over each log's touch-downs up to one second before its end (the fall).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from swing_end import SIDES, _soles, read_run, touchdowns

from rtgait.robot.model import RobotModel
from rtgait.sim.log_file import read_sim_log

TAIL = 1.0
"""Time (s) before a log's end whose touch-downs are left out: the fall's own."""
AFTER = 0.04
"""Window (s) after a late call over which the swing hip's largest torque change is taken."""
TOUCHDOWN_WITHIN = 0.1
"""A late call's touch-down is the swing foot's first within this time (s)."""
COLUMNS = ("off_x", "off_z", "stance_x", "stance_z", "hip_x", "hip_z", "pitch", "servo")


def _pitch(c: dict[str, np.ndarray], prefix: str) -> np.ndarray:
    qx, qy, qz, qw = (c[prefix + k] for k in "xyzw")
    return np.arcsin(np.clip(2.0 * (qw * qy - qz * qx), -1.0, 1.0))


def sag(path: str) -> list[dict[str, float]]:
    """Per planned touch-down of the log at ``path``: the module docstring's terms (m, rad, N m)."""
    c, robot, names, model, data, ids, measured, commanded, base = read_run(path)
    kp = {n: g for n, g in zip(names, _robot_kp(robot), strict=True)}
    pitch_error = _pitch(c, "base_q") - _pitch(c, "base_q_command")
    legs = {side: [i for i, n in enumerate(names) if n.startswith(side + "_")] for side in SIDES}
    end = float(c["t"][-1]) - TAIL
    rows = []
    for k, stance, swing in touchdowns(c["support_planned"]):
        if c["t"][k] > end:
            break

        def relative(joints: np.ndarray, k: int = k, st: str = stance, sw: str = swing) -> np.ndarray:
            soles = _soles(model, data, ids, np.concatenate([base[k], joints]))
            t_st = _soles(model, data, ids, np.concatenate([base[k], measured[k]]))[st]
            return (t_st * (soles[st].inverse() * soles[sw])).translation

        q_a = measured[k].copy()
        q_a[legs[swing]] = commanded[k][legs[swing]]
        hip = f"{stance}_hip_pitch_joint"
        q_h = commanded[k].copy()
        q_h[names.index(hip)] = measured[k][names.index(hip)]
        p_cmd = relative(commanded[k])
        stance_part, hip_part = relative(q_a) - p_cmd, relative(q_h) - p_cmd
        rows.append({
            "t": float(c["t"][k]), "swing": swing,
            "off_x": float(c[f"{swing}_sole_x"][k] - c[f"{swing}_target_x"][k]),
            "off_z": float(c[f"{swing}_sole_z"][k] - c[f"{swing}_target_z"][k]),
            "stance_x": float(stance_part[0]), "stance_z": float(stance_part[2]),
            "hip_x": float(hip_part[0]), "hip_z": float(hip_part[2]), "pitch": float(pitch_error[k]),
            "servo": float(kp[hip] * (c[f"q_command_{hip}"][k] - c[f"q_{hip}"][k])),
        })  # fmt: skip
    return rows


def _robot_kp(robot: RobotModel) -> list[float]:
    """The joints' ``robot_kp`` (N m/rad) from the description (``robot.joint_names`` order)."""
    gains = []
    for name in robot.joint_names:
        value = robot.description.joint_actuation(name).robot_kp
        if value is None:
            raise SystemExit(f"{robot.name}: joint {name} has no robot_kp, the servo torque needs the robot's gains")
        gains.append(float(value))
    return gains


def late_calls(path: str) -> list[dict[str, object]]:
    """Per late call of the log at ``path``: the module docstring's swing hip torques and the touch-down after."""
    log = read_sim_log(path)
    c = log.columns
    t = c["t"]
    control = np.asarray(c["support_control"]).astype(str)
    planned = np.asarray(c["support_planned"]).astype(str)
    window = max(1, round(AFTER / float(t[1] - t[0])))
    rows: list[dict[str, object]] = []
    for k in range(1, len(t) - window):
        if not (control[k] in SIDES and control[k - 1] == "double" and planned[k] == "double"):
            continue
        swing = SIDES[1 - SIDES.index(control[k])]
        tau = c[f"tau_{swing}_hip_pitch_joint"]
        row: dict[str, object] = {
            "t": float(t[k]), "swing": swing, "before": float(tau[k - 1]), "after": float(tau[k + 1]),
            "largest": float(np.max(np.abs(tau[k : k + window] - tau[k - 1]))),
        }  # fmt: skip
        for event in log.events:
            near = t[k] <= event["t"] <= t[k] + TOUCHDOWN_WITHIN
            if event["kind"] == "touchdown" and event["side"] == swing and near:
                j = int(np.searchsorted(t, event["t"] - 1e-9))
                row.update({
                    "delay": float(t[j] - t[k]), "estimate": float(c[f"{swing}_force_z"][j]),
                    "contact": bool(c[f"{swing}_contact"][j]), "z": float(c[f"{swing}_sole_z"][j]),
                })  # fmt: skip
                break
        rows.append(row)
    return rows


def _summary(path: str, rows: list[dict[str, float]]) -> str:
    m = {key: float(np.median([r[key] for r in rows])) * (1.0 if key == "servo" else 1e3) for key in COLUMNS}
    return (
        f"{path}: {len(rows)} planned touch-downs, medians: swing sole off its target x {m['off_x']:+.1f} z "
        f"{m['off_z']:+.1f} mm; the stance leg's errors x {m['stance_x']:+.1f} z {m['stance_z']:+.1f} mm, "
        f"its hip pitch alone x {m['hip_x']:+.1f} z {m['hip_z']:+.1f} mm; base pitch less the IK's "
        f"{m['pitch']:+.1f} mrad; stance hip pitch servo torque {m['servo']:+.2f} N m"
    )


def _late_call_line(r: dict[str, object]) -> str:
    after = "no touch-down"
    if "delay" in r:
        after = (
            f"touch-down +{float(r['delay']) * 1e3:.0f} ms, estimate {float(r['estimate']):.0f} N, "
            f"contact {r['contact']}, sole {float(r['z']) * 1e3:.1f} mm"
        )
    return (
        f"  late call {float(r['t']):7.3f} {r['swing']!s:5} swing hip pitch {float(r['before']):+6.1f} -> "
        f"{float(r['after']):+6.1f} N m, largest change {float(r['largest']):.1f} N m in {AFTER * 1e3:.0f} ms; {after}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("logs", nargs="+", help="sim.parquet files")
    parser.add_argument("--each", action="store_true", help="one line per touch-down (and late call)")
    parser.add_argument("--late-calls", action="store_true", help="the late calls' swing hip torques")
    args = parser.parse_args()
    for path in args.logs:
        rows = sag(path)
        if not rows:
            print(f"{path}: no planned touch-down before the last {TAIL:g} s")
            continue
        if args.each:
            for r in rows:
                cells = " ".join(f"{key} {r[key] * (1.0 if key == 'servo' else 1e3):+6.1f}" for key in COLUMNS)
                print(f"  t {r['t']:7.3f} {r['swing']:5s} {cells}")
        print(_summary(path, rows))
        if not args.late_calls:
            continue
        calls = late_calls(path)
        for r in calls if args.each else []:
            print(_late_call_line(r))
        if calls:
            step = np.median([abs(float(r["after"]) - float(r["before"])) for r in calls])
            largest = np.median([float(r["largest"]) for r in calls])
            false = sum(1 for r in calls if "delay" in r and not r["contact"])
            print(
                f"  {len(calls)} late calls: swing hip pitch torque step {step:.1f} N m over two ticks, largest "
                f"change {largest:.1f} N m (medians); {false} followed by a touch-down without contact"
            )


if __name__ == "__main__":
    main()
