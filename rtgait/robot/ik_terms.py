"""The terms of the whole-body IK's least-squares problem (:class:`~rtgait.robot.ik.WholeBodyIK`): their weights
(:class:`IKWeights`, per m^2 or rad^2) and the errors a solution leaves in them (:class:`IKErrors`, m and rad)."""

from __future__ import annotations

from typing import NamedTuple

__all__ = ["SMOOTH_LIMITS", "IKErrors", "IKWeights"]


class IKErrors(NamedTuple):
    """Task errors of a solution, measured by forward kinematics at the returned configuration.

    Attributes:
        cog: distance from the COG to its target (m).
        left_position, right_position: distance from each sole point to its target (m).
        left_orientation, right_orientation: rotation angle from each sole to its target orientation (rad).
        torso_orientation: rotation angle from the torso to upright with the feet's mean yaw (rad).
        pelvis_orientation: the same for the pelvis (rad).
        iterations: Gauss-Newton iterations made at this tick.
    """

    cog: float
    left_position: float
    left_orientation: float
    right_position: float
    right_orientation: float
    torso_orientation: float
    pelvis_orientation: float
    iterations: int

    @property
    def feet_position(self) -> float:
        """The larger of the two feet position errors (m)."""
        return max(self.left_position, self.right_position)

    @property
    def feet_orientation(self) -> float:
        """The larger of the two feet orientation errors (rad)."""
        return max(self.left_orientation, self.right_orientation)


class IKWeights(NamedTuple):
    """Weights of the least-squares problem (squared-error weights, per unit of each task).

    The feet come first (a foot that is not where planned changes the support polygon), then the COG (the
    balance), then the torso and, far behind, the pelvis; the weights matter only when the targets cannot all be
    reached. The damping and the posture pull are tiny: the damping bounds the steps where the Jacobian is nearly
    singular, the pull decides whatever the tasks leave free (on robots with more moving joints than tasks), and
    together they bias the tasks by about ``posture / task weight`` times the distance to the posture (below a
    micrometre).

    Attributes:
        cog: per m^2.
        foot_position: per m^2.
        foot_orientation: per rad^2.
        torso: per rad^2.
        pelvis: per rad^2.
        damping: on every velocity coordinate (m^2 or rad^2 per unit step).
        posture: pull of the joints toward half-sitting (per rad^2).
        limit: curvature of the joint-limit barrier at the limit (per rad^2); 0 (default): no barrier, the joints
            reach their limits exactly and are pinned there.
        limit_margin: depth of the barrier's band inside each limit (rad).

    The barrier (:class:`~rtgait.robot.ik.WholeBodyIK`) costs ``k d^3 / 3`` for a joint ``d`` rad inside the band,
    ``k = limit / (2 limit_margin)``: its gradient and curvature start at zero at the band's edge, so that the
    solution, and the velocity differenced from it, stay continuous as a joint nears its limit (:data:`SMOOTH_LIMITS`).
    """

    cog: float = 1.0
    foot_position: float = 4.0
    foot_orientation: float = 1.0
    torso: float = 1.0
    pelvis: float = 0.01
    damping: float = 1e-6
    posture: float = 1e-8
    limit: float = 0.0
    limit_margin: float = 0.05


SMOOTH_LIMITS = IKWeights(limit=0.1, limit_margin=0.05)
"""The weights for a reference that is differenced twice, into the accelerations of feed-forward torques: the
default ones with the joint-limit barrier. A joint held off its limit hands its share of the tasks to the others,
and the one that gives way is the softest task, the pelvis's orientation (weight 0.01, the waist keeping the torso
upright); a barrier much stiffer than that turns within a fraction of its band, a step in the rate again (at 10 per
rad^2 G1's hip roll's rate changed sign in one tick on the planned fig7), so its curvature at the limit is ten
times the pelvis's weight. Its band, 0.05 rad, is crossed in 50 to 100 ms at a walking joint's 0.5 to 1 rad/s, ten
to twenty times the rates' low-pass (``rtgait.robot.motion_rates``). The price: where a reachable walk takes a joint
into the band the tasks are met less exactly (G1's planned fig8, ``benchmarks/ik.py``: the COG within 0.13 mm
instead of 0.16 um; its planned fig7 within 3 mm)."""
