"""Leg odometry about the centre of pressure against rigid feet that rock about a point of their sole without
slipping: the base's true velocity is the one that keeps that point still in the world."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.estimation.contact_point import rocking_correction

RNG = np.random.default_rng(3)
SOLE = (-0.1, 0.13, -0.05, 0.07)  # x_min, x_max, y_min, y_max (m)


def rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues' rotation of ``angle`` about ``axis``."""
    k = axis / np.linalg.norm(axis)
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * kx + (1.0 - math.cos(angle)) * kx @ kx


def rocking_foot(v: np.ndarray, w: np.ndarray, contact: tuple[float, float], fz: float = 500.0):
    """A foot below the base (base frame), turning relative to it, whose sole point ``contact`` (sole frame) stands
    still in the world while the base moves at ``v`` and turns at ``w``: its sole origin ``p``, rotation ``r``,
    origin velocity ``p'`` and relative angular velocity ``u``, and a wrench whose centre of pressure is
    ``contact``."""
    p = np.array([0.05, 0.1, -0.8]) + RNG.normal(0.0, 0.02, 3)
    r = rotation(RNG.normal(size=3), 0.1)
    u = RNG.normal(0.0, 0.5, 3)
    arm = r @ np.array([contact[0], contact[1], 0.0])
    # The contact point q = p + R c is still: v + w x q + p' + u x (R c) = 0.
    p_dot = -v - np.cross(w, p + arm) - np.cross(u, arm)
    wrench = (3.0, -2.0, fz, contact[1] * fz, -contact[0] * fz, 0.1)
    return p, r, p_dot, u, wrench


def flat_foot_odometry(p: np.ndarray, p_dot: np.ndarray, w: np.ndarray) -> np.ndarray:
    """The base velocity with the sole origin held still."""
    return -np.cross(w, p) - p_dot


def correction(w: np.ndarray, *feet: tuple) -> np.ndarray:
    """The sum of the feet's terms, each ``(rotation, relative angular velocity, wrench[, share[, extents]])``."""
    total = np.zeros(3)
    for r, u, wrench, *rest in feet:
        share, extents = (rest + [1.0, SOLE][len(rest) :])[:2]
        total += rocking_correction(tuple(w), tuple(r.ravel()), tuple(u), wrench, share, extents)
    return total


@pytest.mark.parametrize("contact", [(0.13, -0.05), (0.13, 0.07), (-0.1, 0.0), (0.02, 0.03)])
def test_a_foot_rocking_on_a_corner_gives_the_base_its_velocity(contact):
    v, w = RNG.normal(0.0, 0.3, 3), RNG.normal(0.0, 0.5, 3)
    p, r, p_dot, u, wrench = rocking_foot(v, w, contact)
    flat = flat_foot_odometry(p, p_dot, w)
    corrected = flat + correction(w, (r, u, wrench))
    np.testing.assert_allclose(corrected, v, atol=1e-12)
    # The origin-held odometry errs by the foot's turn about its contact, w_foot x (R c).
    arm = r @ np.array([contact[0], contact[1], 0.0])
    np.testing.assert_allclose(flat - v, np.cross(w + u, arm), atol=1e-12)
    assert np.linalg.norm(flat - v) > 1e-3


def test_two_feet_by_their_shares():
    v, w = RNG.normal(0.0, 0.3, 3), RNG.normal(0.0, 0.5, 3)
    left = rocking_foot(v, w, (0.13, 0.07), fz=300.0)
    right = rocking_foot(v, w, (-0.1, -0.05), fz=100.0)
    shares = (0.75, 0.25)
    flat = sum(s * flat_foot_odometry(f[0], f[2], w) for s, f in zip(shares, (left, right), strict=True))
    feet = [(f[1], f[3], f[4], s) for s, f in zip(shares, (left, right), strict=True)]
    np.testing.assert_allclose(flat + correction(w, *feet), v, atol=1e-12)


def test_a_foot_flat_and_still_in_the_world_is_not_corrected():
    # The foot turns relative to the base exactly against the base's turn: it does not turn in the world.
    w = RNG.normal(0.0, 0.5, 3)
    r = rotation(RNG.normal(size=3), 0.05)
    wrench = (0.0, 0.0, 400.0, 0.05 * 400.0, -0.12 * 400.0, 0.0)  # its centre of pressure near the toe
    np.testing.assert_allclose(correction(w, (r, -w, wrench)), np.zeros(3), atol=1e-15)


def test_a_centre_of_pressure_off_the_sole_is_held_on_its_edge():
    # A wrench estimated from joint torques that puts the centre of pressure 0.3 m ahead of a foot rocking on its
    # toe corner: the contact is the corner.
    v, w = RNG.normal(0.0, 0.3, 3), RNG.normal(0.0, 0.5, 3)
    p, r, p_dot, u, _ = rocking_foot(v, w, (SOLE[1], SOLE[2]))
    fz = 60.0
    wrong = (0.0, 0.0, fz, SOLE[2] * fz, -(SOLE[1] + 0.3) * fz, 0.0)
    corrected = flat_foot_odometry(p, p_dot, w) + correction(w, (r, u, wrong))
    np.testing.assert_allclose(corrected, v, atol=1e-12)
    unbounded = correction(w, (r, u, wrong, 1.0, None))
    assert np.linalg.norm(flat_foot_odometry(p, p_dot, w) + unbounded - v) > 1e-2


def test_a_foot_without_a_positive_normal_force_is_held_at_its_origin():
    w = np.array([0.1, -0.2, 0.3])
    r = rotation(np.array([1.0, 0.0, 0.0]), 0.1)
    for fz in (0.0, -5.0):
        assert correction(w, (r, np.ones(3), (0.0, 0.0, fz, 1.0, 2.0, 0.0))).tolist() == [0.0, 0.0, 0.0]
