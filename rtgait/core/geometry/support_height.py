"""The support height a stance holds under the virtual repellent point, and how it is lowered before a step down.

In the 3D-DCM/VRP form (``docs/method.md``) the support height ``h`` rests on the footholds' heights: on the stance
foot's ``z_i`` over its single support, carried to the next stance over the double support, and the COG height is
``zc`` above it, smoothed by the pendulum. Before a step down that puts the whole drop on the landing leg: at the
touch-down the COG is still about ``zc`` above the stance tread, ``zc + r`` above the lower one (``r`` the riser),
beyond a leg sized for ``zc``. Humans and HRP-4 bend the stance knee instead. Here a stance foothold ``F[i]`` whose
swing lands on a lower stair-like foothold ``F[i + 1]`` (both level, at least ``MIN_RISE`` apart) holds

    h_i = z_i + DESCENT_SHARE (z_{i+1} - z_i),         DESCENT_SHARE = 1/2                             (1)

so that at the touch-down the COG is ``zc - r/2`` above the stance sole and ``zc + r/2`` above the landing one: the
riser split evenly between the two legs, the stance knee bending by what the landing leg is spared. Every other
stance (level ground, a step up, a slope, whose footholds turn the soles instead) holds ``h_i = z_i``: those walks
are unchanged. The price is the term ``(p_z - h) c''_xy / (c_z'' + g)`` of the horizontal ZMP (``docs/method.md``
eq. 4) in those single supports, ``r/2`` times the COG's horizontal acceleration over ``g``: millimetres, measured by
:func:`rtgait.core.analysis.height_error.zmp_error`.
"""

from __future__ import annotations

from collections.abc import Sequence

from rtgait.core.geometry.footsteps import Footstep
from rtgait.core.geometry.toe_off import stair_rise

__all__ = ["DESCENT_SHARE", "stance_support_height", "support_heights"]

DESCENT_SHARE = 0.5
"""Share of a step down's drop (the riser) the support height of the stance before it takes (module docstring):
one half, the drop split evenly between the stance leg and the landing leg."""


def stance_support_height(stance: Footstep, landing: Footstep | None) -> float:
    """The support height (m) the VRP holds over the single support on ``stance`` whose swing lands on ``landing``
    (``None``: not known yet): eq. (1) before a stair-like step down, the stance's own height otherwise."""
    if landing is None:
        return stance.z
    drop = stair_rise(stance, landing)
    return stance.z + DESCENT_SHARE * drop if drop < 0.0 else stance.z


def support_heights(prints: Sequence[Footstep]) -> list[float]:
    """The support height (m) each footprint of a walk ``F[0..]`` holds as a stance, its swing landing on the next
    (:func:`stance_support_height`; the last one, with no landing, its own height): what the batched evaluation takes
    for the walk's stance anchors (:mod:`rtgait.core.analysis.family_height`)."""
    landings = [*prints[1:], None]
    return [stance_support_height(stance, landing) for stance, landing in zip(prints, landings, strict=True)]
