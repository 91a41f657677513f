"""The measured ZMP as a pendulum carried by its weight would have it (rtgait.control.pendulum_zmp)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.control.pendulum_zmp import pendulum_zmp

MASS, G, HEIGHT = 90.0, 9.81, 0.84


def test_it_stands_for_the_com_acceleration_of_the_measured_force():
    """A point mass at height z_c held by a ground force F through its COM from the ZMP p: the horizontal force is
    F (c - p) / z_c. The pendulum ZMP gives that acceleration at the weight, w^2 (c - p_w) with w^2 = g / z_c."""
    rng = np.random.default_rng(5)
    for _ in range(200):
        com = (*rng.uniform(-1, 1, 2), HEIGHT)
        zmp = tuple(rng.uniform(-1, 1, 2))
        force = rng.uniform(0.0, 3.0) * MASS * G
        acceleration = force * (np.array(com[:2]) - zmp) / HEIGHT / MASS
        px, py = pendulum_zmp(zmp, com, force, MASS * G)
        assert G / HEIGHT * (np.array(com[:2]) - (px, py)) == pytest.approx(acceleration, abs=1e-9)


def test_at_the_weight_it_is_the_measured_zmp():
    assert pendulum_zmp((0.3, -0.1), (0.2, 0.0, HEIGHT), MASS * G, MASS * G) == pytest.approx((0.3, -0.1), abs=1e-15)


def test_a_pull_read_against_a_push_stays_near_the_com():
    """One foot reading -121 N against the other's 123 N (Talos down its stairs): M / F is metres off, the pendulum
    ZMP is within the feet's reach of the COM."""
    a, b, com = np.array([1.44, 0.08]), np.array([1.68, -0.09]), (1.58, -0.02, HEIGHT)
    moment, force = -121.0 * a + 123.0 * b, 2.0
    zmp = tuple(moment / force)
    assert math.hypot(zmp[0] - com[0], zmp[1] - com[1]) > 10.0
    px, py = pendulum_zmp(zmp, com, force, MASS * G)
    assert math.hypot(px - com[0], py - com[1]) < 0.1


def test_no_force_reading_leaves_the_zmp():
    assert pendulum_zmp((0.3, 0.1), (0.0, 0.0, HEIGHT), math.nan, MASS * G) == (0.3, 0.1)
    nan = pendulum_zmp((math.nan, math.nan), (0.0, 0.0, HEIGHT), 800.0, MASS * G)
    assert math.isnan(nan[0]) and math.isnan(nan[1])
