"""Why a swing sole is off its target at the plan's touch-down: its height error split along the kinematic chain.

At each planned touch-down (the first tick of a double support after a single support; ``--offset`` ticks later
with a positive offset) the swing sole's true height error ``e = z_true - z_target`` is split by forward kinematics
(Pinocchio, the robot's reduced model) of the swing sole carried from the true stance sole ``T_st`` through the
legs' relative transform ``R(q) = T_st(q)^-1 T_sw(q)``, which does not depend on the base:

    e = [T_st R(q_meas)   - T_st R(q_a)]        swing leg: its joints' tracking errors (q_a: swing joints commanded)
      + [T_st R(q_a)      - T_st R(q_cmd)]      stance leg and waist: their joints' tracking errors
      + [T_st R(q_cmd)    - T_tgt R(q_cmd)]     the stance sole's pose: its tilt on the floor and its height
                                                 over its own target (``T_tgt``: the stance target, level)
      + [T_tgt R(q_cmd)   - z_target]           the IK's residual (its joints do not put the swing sole on target)

(z components, mm). Per joint: the same difference with one joint at its measured value, the rest commanded. The
swing sole height check (``fk``) compares ``T_sw(q_meas)`` at the true base with the log's ``*_sole_z``.

    python benchmarks/swing_end.py OUT/sim.parquet [--offset TICKS] [--each]

Prints the medians over the walk's touch-downs (of the joints' errors, their magnitudes: a roll or yaw error's sign
flips with the side) and, with ``--each``, one line per touch-down.
"""

from __future__ import annotations

import argparse
from typing import Any, NamedTuple

import numpy as np
import pinocchio as pin

from rtgait.robot.model import RobotModel
from rtgait.sim.log_file import read_sim_log

SIDES = ("left", "right")
TERMS = ("error", "swing_leg", "stance_leg", "stance_tilt", "stance_height", "ik_residual")


class RunLog(NamedTuple):
    """A run's ``sim.parquet`` with its robot, for the forward kinematics of its ticks.

    Attributes:
        columns: the log's columns by name.
        robot: the robot the run walked (its description's name).
        names: the joints, in the robot's order.
        model, data: its reduced Pinocchio model and a data of it.
        ids: the sole frames' ids by side.
        measured, commanded: the joints' positions and their commands per tick (rad), shape ``(k, n)``.
        base: the base's pose per tick, ``(x, y, z, qx, qy, qz, qw)`` (m), shape ``(k, 7)``.
    """

    columns: dict[str, Any]
    robot: RobotModel
    names: list[str]
    model: pin.Model
    data: pin.Data
    ids: dict[str, int]
    measured: np.ndarray
    commanded: np.ndarray
    base: np.ndarray


def read_run(path: str) -> RunLog:
    """The run logged at ``path`` (a ``sim.parquet``) with its robot's model."""
    log = read_sim_log(path)
    c = log.columns
    robot = RobotModel.load(log.metadata["robot"])
    names = list(robot.joint_names)
    ids = {"left": robot.left_sole_id, "right": robot.right_sole_id}
    return RunLog(
        c, robot, names, robot.model, robot.model.createData(), ids,
        np.column_stack([c[f"q_{n}"] for n in names]), np.column_stack([c[f"q_command_{n}"] for n in names]),
        np.column_stack([c[f"base_{a}"] for a in ("x", "y", "z", "qx", "qy", "qz", "qw")]),
    )  # fmt: skip


def _soles(model: pin.Model, data: pin.Data, ids: dict[str, int], q: np.ndarray) -> dict[str, pin.SE3]:
    pin.framesForwardKinematics(model, data, q)
    return {side: data.oMf[frame].copy() for side, frame in ids.items()}


def touchdowns(support: np.ndarray) -> list[tuple[int, str, str]]:
    """``(tick, stance side, swing side)`` at each first tick of a double support that follows a single one."""
    out = []
    for k in range(1, len(support)):
        if support[k] == "double" and support[k - 1] in SIDES:
            stance = str(support[k - 1])
            out.append((k, stance, SIDES[1 - SIDES.index(stance)]))
    return out


def split(path: str, offset: int = 0) -> tuple[list[str], list[dict[str, float | np.ndarray]]]:
    """The joint names and, per touch-down, the terms of the module docstring (m) and the joints' errors (rad)."""
    c, _, names, model, data, ids, measured, commanded, base = read_run(path)
    legs = {side: [i for i, n in enumerate(names) if n.startswith(side + "_")] for side in SIDES}
    rows = []
    for tick, stance, swing in touchdowns(c["support_planned"]):
        k = tick + offset
        if k >= len(base):
            break
        q_meas, q_cmd = measured[k], commanded[k]

        def relative(joints: np.ndarray, base_k: np.ndarray = base[k], st: str = stance, sw: str = swing) -> pin.SE3:
            soles = _soles(model, data, ids, np.concatenate([base_k, joints]))
            return soles[st].inverse() * soles[sw]

        true = _soles(model, data, ids, np.concatenate([base[k], q_meas]))
        t_st = true[stance]
        target = np.array([c[f"{stance}_target_{a}"][k] for a in ("x", "y", "z")])
        t_tgt = pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, float(c[f"{stance}_target_yaw"][k])), target)
        t_level = pin.SE3(t_tgt.rotation, t_st.translation)  # the stance sole where it is, level and on its heading
        q_a = q_meas.copy()
        q_a[legs[swing]] = q_cmd[legs[swing]]
        r_cmd = relative(q_cmd)
        z_true, z_target = float(c[f"{swing}_sole_z"][k]), float(c[f"{swing}_target_z"][k])
        z_a, z_cmd = (t_st * relative(q_a)).translation[2], (t_st * r_cmd).translation[2]
        z_level, z_tgt = (t_level * r_cmd).translation[2], (t_tgt * r_cmd).translation[2]
        per_joint = np.empty(len(names))
        for i in range(len(names)):
            q_i = q_cmd.copy()
            q_i[i] = q_meas[i]
            per_joint[i] = (t_st * relative(q_i)).translation[2] - z_cmd
        rows.append({
            "t": float(c["t"][k]), "swing": swing, "fk": true[swing].translation[2] - z_true,
            "error": z_true - z_target, "swing_leg": z_true - z_a, "stance_leg": z_a - z_cmd,
            "stance_tilt": z_cmd - z_level, "stance_height": z_level - z_tgt, "ik_residual": z_tgt - z_target,
            "contact": bool(c[f"{swing}_contact"][k]), "joint_error": q_meas - q_cmd, "per_joint": per_joint,
            "swing_joints": legs[swing], "stance_joints": legs[stance],
        })  # fmt: skip
    return names, rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("log", help="a sim.parquet")
    parser.add_argument("--offset", type=int, default=0, help="ticks after the planned touch-down (default 0)")
    parser.add_argument("--each", action="store_true", help="one line per touch-down")
    args = parser.parse_args()
    names, rows = split(args.log, args.offset)
    if not rows:
        raise SystemExit(f"{args.log}: no planned touch-down")
    if args.each:
        for r in rows:
            terms = " ".join(f"{key} {r[key] * 1e3:+6.2f}" for key in TERMS)
            print(f"t {r['t']:7.3f} {r['swing']:5s} {terms} (fk {r['fk'] * 1e3:+.2f}, contact {r['contact']})")
    print(f"{len(rows)} touch-downs, {sum(r['contact'] for r in rows)} with the swing sole on the floor; medians (mm):")
    print("  " + ", ".join(f"{key} {np.median([r[key] for r in rows]) * 1e3:+.2f}" for key in TERMS))
    legs = ("swing", "swing_joints"), ("stance", "stance_joints")
    joints = [n.split("_", 1)[1].removesuffix("_joint") for n in names]
    for label, key in legs:
        error = np.median([np.abs(r["joint_error"][r[key]]) for r in rows], axis=0) * 1e3
        part = np.median([r["per_joint"][r[key]] for r in rows], axis=0) * 1e3
        each = zip(rows[0][key], error, part, strict=True)
        cells = ", ".join(f"{joints[i]} {e:.1f} mrad {p:+.2f} mm" for i, e, p in each)
        print(f"  {label} leg (|measured - commanded|; the height it adds): {cells}")


if __name__ == "__main__":
    main()
