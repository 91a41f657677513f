"""The measurement in the feet's frame: translated so that the loaded feet stand where the IK has them.

The whole-body IK places the COM and the swing foot relative to the standing feet (its joint references carry
the targets' differences), so the walk happens in the frame where the loaded feet are at their targets. With the
loaded feet's measured sole positions ``p_i``, their targets ``t_i`` and the weights ``w_i`` of their vertical
forces (summing to 1), the offset

    d = sum_i w_i (t_i - p_i)

translates every measured position (COM, DCM, ZMP, soles, centres of pressure, landings) into that frame: a landing
is then measured from the standing foot's target, and the COM the feedback acts on is where the IK's frame has it.
The weights move ``d`` from one foot to the other with the load, without a jump. Units: m.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rtgait.control.target_blend import Pose
    from rtgait.estimation.state import FootState, Measurement

__all__ = ["feet_offset", "translated"]


def feet_offset(m: Measurement, left: Pose, right: Pose) -> tuple[float, float]:
    """The offset ``d`` (m) of the module docstring for the IK's feet targets ``left``, ``right`` ``(x, y, z, yaw)``;
    ``(0, 0)`` when no foot is loaded."""
    wl = max(m.left.normal_force, 0.0) if m.left.loaded else 0.0
    wr = max(m.right.normal_force, 0.0) if m.right.loaded else 0.0
    total = wl + wr
    if total <= 0.0:
        return 0.0, 0.0
    wl, wr = wl / total, wr / total
    pl, pr = m.left.pose, m.right.pose
    return (
        wl * (left[0] - pl[0]) + wr * (right[0] - pr[0]),
        wl * (left[1] - pl[1]) + wr * (right[1] - pr[1]),
    )


def _foot(foot: FootState, dx: float, dy: float) -> FootState:
    x, y, z, yaw = foot.pose
    return foot._replace(pose=(x + dx, y + dy, z, yaw), cop=(foot.cop[0] + dx, foot.cop[1] + dy))


def translated(m: Measurement, dx: float, dy: float) -> Measurement:
    """``m`` with every position moved by ``(dx, dy)`` (m); velocities, forces and sole-frame values as measured."""
    return m._replace(
        com=(m.com[0] + dx, m.com[1] + dy, m.com[2]),
        dcm=(m.dcm[0] + dx, m.dcm[1] + dy),
        zmp=(m.zmp[0] + dx, m.zmp[1] + dy),
        left=_foot(m.left, dx, dy),
        right=_foot(m.right, dx, dy),
        landings=tuple(landing._replace(x=landing.x + dx, y=landing.y + dy) for landing in m.landings),
    )
