"""The feet in contact as the estimator's anchors in the world: each foot's sole pose remembered while it stands,
the base placed so that the leg kinematics put the soles on them.

Each foot ``i`` has an anchor ``a_i = (x, y, z, yaw)``, the world pose of its sole frame. With the IMU's orientation
of the base ``R'`` (its yaw the IMU's), the sole rotations ``R_i`` and positions ``p_i`` in the base frame
(leg kinematics) and the weights ``w_i = max(f_z,i, 0) / sum_j max(f_z,j, 0)`` of the feet's vertical forces:

    delta = sum_i w_i wrap(yaw_a,i - yaw(R' R_i)),      R = Rz(delta) R'        (yaw from the feet; rad)
    p = sum_i w_i (a_i - R p_i)                                                     (base position, m)

The weights move the base's anchoring from one foot to the other as the load shifts, without a jump even when the
two anchors disagree by a few millimetres. Then each anchor is pulled toward its sole's pose ``s_i = (p + R p_i,
yaw(R R_i))`` by the share of the weight the *other* foot carries:

    a_i <- a_i + (1 - w_i) (s_i - a_i)

A swinging foot (``w_i = 0``) has its anchor follow its sole; a foot that carries the robot keeps its anchor; a
landing foot takes its anchor from where the stance foot's anchor puts it and settles it as it takes the load. So
each foot is re-anchored at each landing and remembered while it stands, like mc_rtc's KinematicInertial anchor
frame and the contact points of contact-aided estimators, but without freezing an anchor at the tick the foot
touched: what a sole still moves after the first touch (it rolls flat, the sole sinks under the load) is taken up
while the foot is light. With ``e`` the anchors' disagreement with the kinematics (``a_1 - a_2 - R (p_1 - p_2)``),
one tick halves it at equal loads and moves the base by ``w_1 w_2 (w_1 - w_2) e``: nothing at equal loads, and, for
a sinking that follows the load from one foot to the other, nothing over the whole transfer (the integral of
``w (1 - w) (1 - 2 w)`` over ``w`` in [0, 1] is 0). A tick without load on either foot (a flight, a fall) keeps the
last weights and has both anchors follow their soles: the base keeps the place and yaw of the last tick, turned on
by the IMU.

The world frame is fixed at the start, by the standing feet's poses when given (the plan's, so that the estimate and
the plan share a frame), else by the feet's midpoint at the origin on the ground with the IMU's heading.
"""

from __future__ import annotations

import math

__all__ = ["FootAnchors"]

Pose = tuple[float, float, float, float]
Vector = tuple[float, float, float]


class FootAnchors:
    """The feet's anchors (module docstring)."""

    def __init__(self) -> None:
        self.poses: list[Pose] | None = None
        """Left and right anchors ``(x, y, z, yaw)`` (m, rad); ``None`` before :meth:`start`."""

    def reset(self) -> None:
        """Forget the anchors: the next tick starts the world frame afresh."""
        self.poses = None

    def start(self, left: Vector, right: Vector, yaws: tuple[float, float], feet: tuple[Pose, Pose] | None) -> float:
        """Anchor both feet at the start; returns the yaw correction ``delta`` (rad) that turns the IMU's heading
        into the world frame's.

        Args:
            left, right: the soles' positions relative to the base, in world axes with the IMU's yaw (m).
            yaws: the soles' yaws in the IMU's heading (rad).
            feet: the soles' world poses ``(x, y, z, yaw)``; ``None``: the feet's midpoint at the origin, on the ground
                (``z = 0`` there), the IMU's heading.
        """
        if feet is None:
            mx, my, mz = (0.5 * (a + b) for a, b in zip(left, right, strict=True))
            self.poses = [(left[0] - mx, left[1] - my, left[2] - mz, yaws[0]),
                          (right[0] - mx, right[1] - my, right[2] - mz, yaws[1])]  # fmt: skip
            return 0.0
        self.poses = [tuple(float(v) for v in foot) for foot in feet]  # type: ignore[misc]
        left_turn = math.remainder(feet[0][3] - yaws[0], math.tau)
        return left_turn + 0.5 * math.remainder(feet[1][3] - yaws[1] - left_turn, math.tau)

    def yaw_correction(self, weight_left: float, yaw_left: float, yaw_right: float) -> float:
        """``delta`` (rad) for the soles' yaws in the IMU's heading and the left foot's weight (module docstring)."""
        poses = self.poses
        assert poses is not None
        left = math.remainder(poses[0][3] - yaw_left, math.tau)
        right = math.remainder(poses[1][3] - yaw_right, math.tau)
        # The weighted mean taken about the left foot's turn: no wrap-around between the two.
        return left + (1.0 - weight_left) * math.remainder(right - left, math.tau)

    def base_position(self, weight_left: float, left: Vector, right: Vector) -> Vector:
        """``p`` (m) for the soles' positions relative to the base in world axes (module docstring)."""
        poses = self.poses
        assert poses is not None
        (lx, ly, lz, _), (rx, ry, rz, _) = poses
        wl = weight_left
        wr = 1.0 - wl
        return (
            wl * (lx - left[0]) + wr * (rx - right[0]),
            wl * (ly - left[1]) + wr * (ry - right[1]),
            wl * (lz - left[2]) + wr * (rz - right[2]),
        )

    def settle(self, weight_left: float, left: Pose, right: Pose, standing: bool = True) -> None:
        """Pull each anchor toward its sole's pose now, ``left`` and ``right`` ``(x, y, z, yaw)`` (m, rad), by the share
        of the weight the other foot carries (module docstring); ``standing=False`` (no foot on the ground): all the
        way."""
        poses = self.poses
        assert poses is not None
        gain_left, gain_right = (1.0 - weight_left, weight_left) if standing else (1.0, 1.0)
        # A foot without gain keeps its anchor.
        if gain_left != 0.0:
            poses[0] = _pulled(poses[0], left, gain_left)
        if gain_right != 0.0:
            poses[1] = _pulled(poses[1], right, gain_right)


def _pulled(anchor: Pose, pose: Pose, gain: float) -> Pose:
    """``anchor`` moved toward ``pose`` by ``gain`` (the yaw along the shorter way)."""
    x, y, z, yaw = anchor
    px, py, pz, pyaw = pose
    return (
        x + gain * (px - x),
        y + gain * (py - y),
        z + gain * (pz - z),
        yaw + gain * math.remainder(pyaw - yaw, math.tau),
    )
