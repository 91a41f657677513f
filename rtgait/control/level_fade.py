"""Handing the feedback over when a MuJoCo controller switches level mid-walk
(:meth:`rtgait.control.controller.WalkingController.set_level`).

A closed level (``stabilized``, ``adaptive``) adds to the plan a COM offset ``d`` (the DCM law's COM admittance) and
foot offsets (the foot force control's ankle tilts and foot heights). Dropping them at once when the controller
switches to ``open-loop`` would step the IK's targets by ``d`` (up to :attr:`DcmFeedbackGains.max_com_offset`, 5 cm)
and the feet by their offsets. Instead, the offsets held at the switch are faded out over :data:`LEVEL_FADE`
with the weight

    w(s) = (1 + cos(pi s)) / 2,    s = (ticks since the switch) / (ticks of the fade)  in [0, 1]

(1 -> 0 with zero slope at both ends, so the targets' velocity does not step either), while the objects here stand
in for the controller's ``feedback`` and ``foot``. Each adds the faded offsets to what the new level computes: the
plan's ZMP and no offset in ``open-loop``, or, when the controller switches back up during a fade, the output of a
fresh feedback law. At the end of the fade each puts the new level's object (or ``None``) back in its place.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from rtgait.control.foot_control import FootOffsets
from rtgait.core.laws.feedback import DcmFeedbackOutput

if TYPE_CHECKING:
    from rtgait.control.foot_control import FootForceControl
    from rtgait.core.laws.feedback import DcmFeedback

__all__ = ["LEVEL_FADE", "FeedbackFade", "FootFade", "fade_weight"]

LEVEL_FADE = 0.2
"""How long the COM and foot offsets of a closed level take to fade out after a switch to ``open-loop`` (s): a
quarter of a step of the built-in timings, short enough that a switch acts within the step under way, long enough
that a 5 cm offset moves the COM target at most 0.4 m/s (the peak rate of ``w`` is ``pi / 2`` per fade)."""


def fade_weight(k: int, n: int) -> float:
    """``w(k / n)`` of the module docstring: 1 at ``k = 0``, 0 from ``k = n`` on."""
    if k >= n:
        return 0.0
    return 0.5 * (1.0 + math.cos(math.pi * k / n))


class FeedbackFade:
    """Stands in for a controller's DCM feedback while the COM offset ``offset`` (m) fades out over ``ticks``
    ticks; ``inner`` is the new level's feedback law (``None`` in ``open-loop``: the command is the plan's ZMP).

    Args:
        owner: the controller whose ``feedback`` this replaces; it gets ``inner`` back at the end of the fade.
        inner: the new level's :class:`~rtgait.core.laws.feedback.DcmFeedback`, or ``None``.
        offset: the COM offset at the switch (m).
        ticks: length of the fade (ticks, >= 1).
    """

    def __init__(self, owner: Any, inner: DcmFeedback | None, offset: tuple[float, float], ticks: int) -> None:
        self.owner, self.inner, self.offset, self.ticks = owner, inner, offset, max(1, ticks)
        self._k = 0

    @property
    def com_offset(self) -> tuple[float, float]:
        """The COM offset the last update gave (m): the inner law's plus the faded one."""
        w = fade_weight(self._k, self.ticks)
        ix, iy = self.inner.com_offset if self.inner is not None else (0.0, 0.0)
        return ix + w * self.offset[0], iy + w * self.offset[1]

    def update(
        self, zmp_ref: Any, dcm_ref: Any, dcm: Any, polygon: Any, dt: float | None = None, zmp_measured: Any = None
    ) -> DcmFeedbackOutput:
        """One tick, as :meth:`rtgait.core.laws.feedback.DcmFeedback.update` (same arguments, m)."""
        self._k += 1
        w = fade_weight(self._k, self.ticks)
        if self.inner is not None:
            out = self.inner.update(zmp_ref, dcm_ref, dcm, polygon, dt, zmp_measured)
        else:
            zmp = (float(zmp_ref[0]), float(zmp_ref[1]))
            out = DcmFeedbackOutput(zmp, zmp, False, (0.0, 0.0), (0.0, 0.0))
        rate = (w - fade_weight(self._k - 1, self.ticks)) / self.owner.dt  # the faded part's velocity factor (1/s)
        (ox, oy), (vx, vy) = out.com_offset, out.com_offset_vel
        fx, fy = self.offset
        out = out._replace(com_offset=(ox + w * fx, oy + w * fy), com_offset_vel=(vx + rate * fx, vy + rate * fy))
        if self._k >= self.ticks:
            self.owner.feedback = self.inner
        return out

    def reset(self) -> None:
        """End the fade at once and reset the inner law (the controller's ``reset``, at a new start)."""
        self.owner.feedback = self.inner
        if self.inner is not None:
            self.inner.reset()


class FootFade:
    """Stands in for a controller's foot force control while the offsets ``offsets`` fade out over ``ticks``
    ticks; ``inner`` is the new level's foot force control (``None``: no offsets of its own).

    Args:
        owner: the controller whose ``foot`` this replaces; it gets ``inner`` back at the end of the fade.
        inner: the new level's :class:`~rtgait.control.foot_control.FootForceControl`, or ``None``.
        offsets: the offsets at the switch (rad, m).
        ticks: length of the fade (ticks, >= 1); the same as the feedback's, so both end on the same tick.
    """

    def __init__(self, owner: Any, inner: FootForceControl | None, offsets: FootOffsets, ticks: int) -> None:
        self.owner, self.inner, self.faded, self.ticks = owner, inner, offsets, max(1, ticks)
        self._k = 0
        self._last = offsets

    @property
    def offsets(self) -> FootOffsets:
        """The offsets the last update gave."""
        return self._last

    def update(self, split: Any, left: Any, right: Any, support: str, dt: float | None = None) -> FootOffsets:
        """One tick, as :meth:`rtgait.control.foot_control.FootForceControl.update`."""
        self._k += 1
        w = fade_weight(self._k, self.ticks)
        own = self.inner.update(split, left, right, support, dt) if self.inner is not None else FootOffsets()
        self._last = FootOffsets(*(a + w * b for a, b in zip(own, self.faded, strict=True)))
        if self._k >= self.ticks:
            self.owner.foot = self.inner
        return self._last

    def reset(self) -> None:
        """End the fade at once and reset the inner control."""
        self.owner.foot = self.inner
        if self.inner is not None:
            self.inner.reset()
