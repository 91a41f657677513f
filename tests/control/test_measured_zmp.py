"""A measured ZMP is one the feet's contacts can produce only within the soles' reach (rtgait.control.measured_zmp)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.control.measured_zmp import sole_radius, within_soles
from rtgait.core.geometry.footsteps import SoleRect

SOLE = SoleRect(front=0.105, back=0.105, inner=0.065, outer=0.065)


def corners(x, y, yaw):
    """The sole's four corners (m) about its sole point ``(x, y)`` turned by ``yaw``."""
    c, s = math.cos(yaw), math.sin(yaw)
    local = [(SOLE.front, SOLE.outer), (SOLE.front, -SOLE.inner), (-SOLE.back, -SOLE.inner), (-SOLE.back, SOLE.outer)]
    return np.array([(x + c * u - s * v, y + s * u + c * v) for u, v in local])


def test_every_zmp_of_pushing_contacts_is_within_the_soles_reach():
    """Random feet and random non-negative forces at the soles' corners: their centre of pressure always passes."""
    rng = np.random.default_rng(3)
    radius = sole_radius(SOLE)
    for _ in range(2000):
        a = (*rng.uniform(-1, 1, 2), rng.uniform(-3, 3))
        b = (a[0] + rng.uniform(-0.5, 0.5), a[1] + rng.uniform(-0.5, 0.5), rng.uniform(-3, 3))
        points = np.vstack([corners(*a), corners(*b)])
        forces = rng.exponential(size=8) * (rng.uniform(size=8) < 0.7)
        if forces.sum() == 0.0:
            continue
        x, y = forces @ points / forces.sum()
        assert within_soles(x, y, a, b, radius + 1e-12)  # a corner lies at r exactly: its rounding


def test_a_pull_read_against_a_push_gives_a_zmp_beyond_reach():
    """One foot reading -121 N against the other's 123 N (Talos down the stairs): the ZMP of M / F is metres off."""
    a, b = (1.44, 0.08, 0.0), (1.68, -0.09, 0.0)
    moment = -121.0 * np.array(a[:2]) + 123.0 * np.array(b[:2])
    x, y = moment / (123.0 - 121.0)
    assert abs(x) > 10.0 and not within_soles(x, y, a, b, sole_radius(SOLE))
    assert not within_soles(math.nan, math.nan, a, b, sole_radius(SOLE))


@pytest.mark.parametrize(("offset", "inside"), [(-1e-9, True), (1e-4, False)])
def test_the_bound_is_the_widened_segment(offset, inside):
    """A point just within ``r`` beside the segment's middle passes, one a little farther does not; the same beyond
    its ends."""
    a, b = (0.0, 0.1), (0.3, -0.1)
    r = sole_radius(SOLE)
    assert r == pytest.approx(math.hypot(0.105, 0.065))
    ux, uy = 0.3 / math.hypot(0.3, 0.2), -0.2 / math.hypot(0.3, 0.2)
    for cx, cy in [(0.15, 0.0), a, b]:
        x, y = cx - uy * (r + offset), cy + ux * (r + offset)
        if (cx, cy) == a:  # beyond the end, along the segment
            x, y = cx - ux * (r + offset), cy - uy * (r + offset)
        assert within_soles(x, y, a, b, r) == inside
