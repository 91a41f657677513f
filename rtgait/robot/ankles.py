"""The ankle joints of a robot, found from its sole frames, and the foot tilts added to them.

Foot force control tilts each sole about its x (roll) and y (pitch) axes; the IK keeps the soles level, so the tilts
go to the ankle joints afterwards: the joint closest to the foot whose axis is the sole's x or y axis, found from
the sole frame's Jacobian at half-sitting (the angular part of a joint's column, in the sole frame, is its axis).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from rtgait.interface.task_targets import FootOffsets

if TYPE_CHECKING:
    from rtgait.robot.model import RobotModel

__all__ = ["AnkleJoints", "add_ankle_offsets", "find_ankle_joints"]


class AnkleJoints(NamedTuple):
    """Where the foot tilts go in the joint vector ``q[7:]`` of the robot's reduced model: per foot the index of the
    joint closest to the foot whose axis is the sole's x axis (roll) and y axis (pitch), and the sign that turns a
    foot rotation into that joint's rotation (+1 when the joint axis points along the sole axis)."""

    left_roll: int
    left_pitch: int
    right_roll: int
    right_pitch: int
    left_roll_sign: float
    left_pitch_sign: float
    right_roll_sign: float
    right_pitch_sign: float


def find_ankle_joints(robot: RobotModel, alignment: float = 0.95) -> AnkleJoints:
    """The ankle roll and pitch joints of ``robot`` (a :class:`~rtgait.robot.model.RobotModel`), from the sole
    frames' Jacobians at half-sitting: the angular part of a joint's column in the sole frame is its axis there.

    Raises:
        ValueError: a foot has no joint within ``alignment`` (cosine) of its sole's x or y axis.
    """
    import pinocchio as pin  # the robot layer's dependency; kept out of the module's import for the pure parts

    model = robot.model
    data = model.createData()
    found: dict[str, tuple[int, float]] = {}
    for side, frame in (("left", robot.left_sole_id), ("right", robot.right_sole_id)):
        jacobian = pin.computeFrameJacobian(model, data, robot.q_half_sitting, frame, pin.ReferenceFrame.LOCAL)
        for name, axis in (("roll", 0), ("pitch", 1)):
            best = None
            for column in range(6, model.nv):  # the free flyer's 6 first; joints after it have one coordinate each
                component = float(jacobian[3 + axis, column])
                norm = float(np.linalg.norm(jacobian[3:6, column]))
                if norm > 0.0 and abs(component) / norm >= alignment:
                    best = (column - 6, 1.0 if component > 0.0 else -1.0)  # the last one found is the most distal
            if best is None:
                raise ValueError(f"{robot.name}: no joint of the {side} leg turns its sole about its {name} axis")
            found[f"{side}_{name}"] = best
    return AnkleJoints(
        found["left_roll"][0], found["left_pitch"][0], found["right_roll"][0], found["right_pitch"][0],
        found["left_roll"][1], found["left_pitch"][1], found["right_roll"][1], found["right_pitch"][1],
    )  # fmt: skip


def add_ankle_offsets(joints: np.ndarray, ankles: AnkleJoints, offsets: FootOffsets) -> None:
    """Add the foot tilts of ``offsets`` to the ankle joints of ``joints`` (``q[7:]`` or servo targets, rad), in place.

    Turning an ankle joint turns the foot about the joint's axis, which passes above the sole point (0.107 m on
    Talos): besides the tilt, the sole point moves by that height times the angle (1 mm at 10 mrad), which a foot
    pressed on the ground does not do; it is the price of keeping the IK's soles level.
    """
    joints[ankles.left_roll] += ankles.left_roll_sign * offsets.left_roll
    joints[ankles.left_pitch] += ankles.left_pitch_sign * offsets.left_pitch
    joints[ankles.right_roll] += ankles.right_roll_sign * offsets.right_roll
    joints[ankles.right_pitch] += ankles.right_pitch_sign * offsets.right_pitch
