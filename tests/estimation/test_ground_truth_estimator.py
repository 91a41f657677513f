"""The ground-truth estimator against hand-computed statics: point forces on a sole, two feet, landings, the DCM."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.estimation.estimator import Estimator
from rtgait.estimation.ground_truth import GroundTruthEstimator
from rtgait.interface.truth import FootContact, GroundTruth

W = math.sqrt(9.81 / 0.8)
WEIGHT = 60.0 * 9.81
LEVEL = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]


def _yawed(yaw: float) -> list[float]:
    c, s = math.cos(yaw), math.sin(yaw)
    return [c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0]


def _foot(points: list[tuple[float, float, float]], forces: list[float], sole=(0.0, 0.0, 0.0), rotation=LEVEL):
    """Vertical point forces ``forces`` (N) at ``points`` (m) on a sole: their sum and moment about the origin."""
    force = np.zeros(3)
    moment = np.zeros(3)
    for p, fz in zip(points, forces, strict=True):
        f = np.array([0.0, 0.0, fz])
        force += f
        moment += np.cross(p, f)
    return FootContact(tuple(force), tuple(moment), len(points), list(sole), list(rotation))


def _truth(t, left, right, com=(0.0, 0.0, 0.8), com_vel=(0.0, 0.0, 0.0)):
    return GroundTruth(t, com, com_vel, left, right, 0)


def test_it_is_an_estimator_that_reads_the_truth():
    estimator = GroundTruthEstimator(W, WEIGHT)
    assert isinstance(estimator, Estimator)
    assert estimator.reads_truth
    with pytest.raises(ValueError, match="ground truth"):
        estimator.update(None, None)


def test_centre_of_pressure_of_point_forces_on_a_turned_sole():
    # Two vertical forces on a sole turned 0.3 rad: the CoP is their force-weighted mean, in the world and, turned
    # back, in the sole frame.
    yaw, sole = 0.3, (0.2, 0.1, 0.0)
    points = [(0.25, 0.12, 0.0), (0.15, 0.05, 0.0)]
    forces = [300.0, 100.0]
    left = _foot(points, forces, sole, _yawed(yaw))
    right = _foot([], [], (0.0, -0.2, 0.0))
    m = GroundTruthEstimator(W, WEIGHT).update(None, _truth(0.0, left, right))
    expected = np.average(np.array(points)[:, :2], axis=0, weights=forces)
    assert m.left.cop == pytest.approx(tuple(expected), abs=1e-12)
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = expected - np.array(sole[:2])
    assert m.left.cop_local == pytest.approx((c * dx + s * dy, -s * dx + c * dy), abs=1e-12)
    assert m.left.pose == pytest.approx((*sole, yaw))
    assert math.isnan(m.right.cop[0])  # no load, no CoP
    assert m.zmp == pytest.approx(tuple(expected), abs=1e-12)  # one foot carries everything
    assert m.normal_force == pytest.approx(400.0)


def test_zmp_of_two_feet_is_the_force_weighted_mean_of_their_cops():
    left = _foot([(0.05, 0.1, 0.0)], [200.0], (0.0, 0.1, 0.0))
    right = _foot([(-0.02, -0.1, 0.0)], [600.0], (0.0, -0.1, 0.0))
    m = GroundTruthEstimator(W, WEIGHT).update(None, _truth(0.0, left, right))
    assert m.zmp == pytest.approx((0.25 * 0.05 + 0.75 * -0.02, 0.25 * 0.1 + 0.75 * -0.1), abs=1e-12)
    assert m.support == "double"


def test_the_zmp_of_a_foot_on_a_stair_is_where_its_force_meets_the_tread():
    # A pendulum on a tread 0.9 m up, its COM 0.8 m above the tread and 0.05 m ahead of the centre of pressure: the
    # ground's force points along c - p. Its ZMP is the centre of pressure on the tread; on the floor's plane 0.9 m
    # below, the same line of force meets z = 0 a further 0.9 x 0.05 / 0.8 m behind.
    tread, cop, com = 0.9, np.array([0.1, 0.2, 0.9]), np.array([0.15, 0.2, 1.7])
    force = WEIGHT * (com - cop) / (com[2] - cop[2])
    left = FootContact(tuple(force), tuple(np.cross(cop, force)), 4, [0.12, 0.2, tread], LEVEL)
    right = FootContact((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0, [0.0, -0.1, 0.75], LEVEL)
    m = GroundTruthEstimator(W, WEIGHT).update(None, _truth(0.0, left, right, com=tuple(com)))
    assert m.zmp == pytest.approx((0.1, 0.2), abs=1e-12)
    floor = GroundTruthEstimator(W, WEIGHT, ground_height=0.0).update(None, _truth(0.0, left, right, com=tuple(com)))
    assert floor.zmp == pytest.approx((0.1 - 0.9 * 0.05 / 0.8, 0.2), abs=1e-12)


def test_dcm_is_com_plus_velocity_over_omega():
    feet = _foot([(0.0, 0.1, 0.0)], [300.0], (0.0, 0.1, 0.0)), _foot([(0.0, -0.1, 0.0)], [300.0], (0.0, -0.1, 0.0))
    m = GroundTruthEstimator(W, WEIGHT).update(None, _truth(0.0, *feet, com=(0.1, -0.02, 0.8), com_vel=(0.3, 0.1, 0)))
    assert m.dcm == pytest.approx((0.1 + 0.3 / W, -0.02 + 0.1 / W))


def test_a_landing_is_reported_once_after_a_flight_and_not_after_a_scuff():
    estimator = GroundTruthEstimator(W, WEIGHT, min_unloaded_time=0.05)
    stance = _foot([(0.0, -0.1, 0.0)], [WEIGHT], (0.0, -0.1, 0.0))
    loaded = _foot([(0.2, 0.1, 0.0)], [0.5 * WEIGHT], (0.2, 0.1, 0.0))
    air = _foot([], [], (0.2, 0.1, 0.05))
    landings = []
    # Loaded, 20 ms in the air (a scuff), loaded, 100 ms in the air, loaded for good.
    schedule = [loaded] * 5 + [air] * 20 + [loaded] * 5 + [air] * 100 + [loaded] * 5
    for k, left in enumerate(schedule):
        m = estimator.update(None, _truth(k * 0.001, left, stance))
        landings += [(k, landing.side) for landing in m.landings]
    assert landings == [(130, "left")]
