"""Sampling the plan being executed: :class:`~rtgait.core.planner.online.OnlinePlanner` takes these methods from
:class:`PlanSampling` (a mixin, like :class:`~rtgait.core.planner.layouts.PlanShapes`); it has no state of its own.

At time ``t`` (s) in segment ``j`` of the plan, ``tau = t - t_j`` into it, each horizontal axis is the closed form of
the linear inverted pendulum (``w = sqrt(g / z_c)``, 1/s):

    c(tau) = V cosh(w tau) + W sinh(w tau) + A(tau),    p(tau) = a(tau),    xi = c + c' / w

with ``A`` and ``a`` the segment's particular quartic and ZMP polynomial (m); the feet come from the walk's phase
(a swing foot on its trajectory). This is the per-tick path of a control loop: plain floats, no array per tick.
"""

from __future__ import annotations

import math

import numpy as np

from rtgait.core.geometry.footsteps import SoleRect
from rtgait.core.geometry.support import signed_margin, support_polygon
from rtgait.core.input_bounds import MAX_TIME, InputOutOfBoundsError
from rtgait.core.lipm.closed_form import CogTrajectory
from rtgait.core.lipm.pattern import DEGREE
from rtgait.core.lipm.spline import PiecewisePolynomial
from rtgait.core.planner.sample import GaitSample, SampleValues
from rtgait.core.walk.phases import phase_info

__all__ = ["PlanSampling"]

_new_tuple = tuple.__new__  # a NamedTuple from a tuple at once, without its generated __new__'s argument parsing


class PlanSampling:
    """The sampling methods of :class:`~rtgait.core.planner.online.OnlinePlanner` (see the module docstring)."""

    @property
    def current_plan(self) -> CogTrajectory:
        """The plan being executed as a :class:`CogTrajectory` (for analysis; sampling does not need it)."""
        if self._plan is None:
            raise RuntimeError("no plan yet: call start() and sample()")
        plan = self._plan
        data = (plan.layout.G @ plan.y).reshape(len(plan.durations), 12, 2)  # (m, 12, axes)
        zmp = PiecewisePolynomial(plan.t_start, np.array(plan.durations), data[:, : DEGREE + 1])
        return CogTrajectory(zmp=zmp, V=data[:, -2], W=data[:, -1], w=self.w)

    def sample(self, t: float) -> GaitSample:
        """COG (pos, vel, acc), ZMP, reference ZMP, feet poses, DCM and support at absolute time ``t`` (s).

        ``t`` must be finite, within :data:`~rtgait.core.input_bounds.MAX_TIME`, not before the plan under way and
        less than :data:`~rtgait.core.limits.MAX_REPLANS_PER_SAMPLE` double supports past the next replan
        (:class:`~rtgait.core.input_bounds.InputOutOfBoundsError` otherwise, nothing changed)."""
        values, support, phase = self.sample_values(t)
        return GaitSample(t, np.fromiter(values, float, len(values)), support, phase)

    def sample_values(self, t: float) -> tuple[SampleValues, str, int]:
        """As :meth:`sample` but returns the values as a :class:`SampleValues` of plain floats, read by field (for
        tight loops), with the support and the phase."""
        if t >= self._commit_time or t >= self._next_replan_time or t > MAX_TIME:
            self._catch_up(t)
        plan = self._plan
        if plan is None or not t >= plan.t_start:  # also rejects NaN
            if not self.started:
                raise RuntimeError("call start() before sample()")
            raise InputOutOfBoundsError(
                f"t={t} s must not be before the plan being executed (starts at {self._earliest()} s)"
            )
        rel = t - self._t0
        phase = self._phase
        if phase is None or not phase.start <= rel < phase.end:
            phase = self._phase = phase_info(self._walk, self.timeline, rel, self._swing_retarget)
        q = phase.index
        if t > self._latest:
            self._latest = t
            if q != self._walk.latest_phase:
                self._walk.reach(q)
        j = q - plan.phase0
        if j < 0:  # t on a phase boundary, rounded to the phase before the plan's first
            j = 0
        elif j >= len(plan.durations):
            j = len(plan.durations) - 1
        tau = t - plan.t_start - plan.offsets[j]
        if tau > plan.durations[j]:  # past the end of the walk: hold the final state
            tau = plan.durations[j]
        w = self.w
        e = math.exp(w * tau)
        ch, sh = 0.5 * (e + 1.0 / e), 0.5 * (e - 1.0 / e)
        axes = []  # per horizontal axis: (cog, vel, acc, zmp, zmp_ref, dcm)
        for axis, coeffs in enumerate(plan.segment(j)):
            a0, a1, a2, a3, a4, A0, A1, A2, A3, A4, V, W = coeffs
            hom = V * ch + W * sh
            cog = hom + A0 + tau * (A1 + tau * (A2 + tau * (A3 + tau * A4)))
            vel = w * (V * sh + W * ch) + A1 + tau * (2.0 * A2 + tau * (3.0 * A3 + tau * 4.0 * A4))
            acc = w * w * hom + 2.0 * A2 + tau * (6.0 * A3 + tau * 12.0 * A4)
            zmp = a0 + tau * (a1 + tau * (a2 + tau * (a3 + tau * a4)))
            if j == 0:
                r0, r1, r2, r3 = plan.first_reference[axis]
                s = tau + plan.reference_offset
                zmp_ref = r0 + s * (r1 + s * (r2 + s * r3))
            else:
                zmp_ref = zmp
            axes.append((cog, vel, acc, zmp, zmp_ref, cog + vel / w))
        (cog_x, cog_vx, cog_ax, zmp_x, zmp_ref_x, dcm_x), (cog_y, cog_vy, cog_ay, zmp_y, zmp_ref_y, dcm_y) = axes
        cog_z, cog_vz, cog_az = self.config.cog_height, 0.0, 0.0
        if plan.z is not None:  # the vertical column, as the horizontal axes above
            _, _, _, _, _, A0, A1, A2, A3, A4, V, W = plan.z_segment(j)
            hom = V * ch + W * sh
            cog_z += hom + A0 + tau * (A1 + tau * (A2 + tau * (A3 + tau * A4)))
            cog_vz = w * (V * sh + W * ch) + A1 + tau * (2.0 * A2 + tau * (3.0 * A3 + tau * 4.0 * A4))
            cog_az = w * w * hom + 2.0 * A2 + tau * (6.0 * A3 + tau * 12.0 * A4)
        if phase.swing_from is None:  # both feet on the ground, left then right
            lfoot_x, lfoot_y, lfoot_z, lfoot_yaw, rfoot_x, rfoot_y, rfoot_z, rfoot_yaw = phase.feet
        else:
            swing = phase.swing(rel, self.config.step_height, self.config.descent_bend)
            left, right = (phase.feet, swing) if phase.support == "left" else (swing, phase.feet)
            lfoot_x, lfoot_y, lfoot_z, lfoot_yaw = left
            rfoot_x, rfoot_y, rfoot_z, rfoot_yaw = right
        values = _new_tuple(SampleValues, (  # in field order
            cog_x, cog_y, cog_z, cog_vx, cog_vy, cog_vz, cog_ax, cog_ay, cog_az,
            zmp_x, zmp_y, zmp_ref_x, zmp_ref_y,
            lfoot_x, lfoot_y, lfoot_z, lfoot_yaw, rfoot_x, rfoot_y, rfoot_z, rfoot_yaw,
            dcm_x, dcm_y,
        ))  # fmt: skip
        return values, phase.support, q

    def _earliest(self) -> float:
        return self._t0 if self._plan is None else self._plan.t_start

    def zmp_margin(self, sample: GaitSample, sole: SoleRect) -> float:
        """Signed distance (m) of the sample's planned ZMP to its support polygon; negative = outside."""
        polygon = support_polygon(self.contact_feet(sample.phase), sole)
        return float(signed_margin(sample.zmp, polygon)[0])
