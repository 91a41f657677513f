"""The inertia of the foot below an ankle sensor (rtgait.estimation.foot_inertia) against motions whose accelerations
are known in closed form: a foot bobbing under a still base, and a still foot under a base that spins (the
centripetal acceleration the difference of velocities must find)."""

from __future__ import annotations

import math

import pytest

from rtgait.estimation.foot_inertia import INERTIA_NOISE, FootInertia
from rtgait.interface.body_kinematics import BodyKinematics, ForceSensorMount, FrameMotion

G = 9.81
MASS = 1.6  # kg, Talos's foot below its ankle sensor
DT = 0.001
CORE = 2.0 * INERTIA_NOISE  # N: what the removal takes for its noise


def _cored(force: float) -> float:
    """The soft threshold of the module docstring, written out independently."""
    return math.copysign(max(abs(force) - CORE, 0.0), force)


EYE = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
MOUNT = ForceSensorMount((0.0, 0.0, 0.1), EYE, MASS, (0.02, 0.0, 0.05))
IMU = FrameMotion((0.0, 0.0, 0.3), EYE, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))


def _kinematics(left: FrameMotion, right: FrameMotion) -> BodyKinematics:
    return BodyKinematics((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), left, right, IMU)


def test_a_bobbing_foot_under_a_still_base_has_its_mass_times_its_acceleration():
    # Beyond twice the removal's noise; within it, nil (a still foot's removal would be noise alone).
    amplitude, omega = 0.02, 2.0 * math.pi * 20.0  # 20 Hz, 316 m/s^2 at the peaks: 500 N of inertia
    inertia = FootInertia((MOUNT, MOUNT), G)
    still = FrameMotion((0.0, -0.1, -0.8), EYE, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    errors = []
    for k in range(200):
        t = k * DT
        z, vz = amplitude * math.sin(omega * t), amplitude * omega * math.cos(omega * t)
        foot = FrameMotion((0.0, 0.1, -0.8 + z), EYE, (0.0, 0.0, vz), (0.0, 0.0, 0.0))
        left, right = inertia.update(DT if k else 0.0, (0.0, 0.0, 1.0), (0.0, 0.0, 0.0), (0.0, 0.0, G),
                                     _kinematics(foot, still))  # fmt: skip
        if k:
            # The mean acceleration of the tick that ends at t (the difference of its velocities), exactly.
            vz_last = amplitude * omega * math.cos(omega * (t - DT))
            errors.append(left - _cored(MASS * (vz - vz_last) / DT))
            assert right == pytest.approx(0.0, abs=1e-9)
        else:
            assert left == right == 0.0  # no difference at the first tick
    assert max(map(abs, errors)) < 1e-6


def test_a_still_foot_under_a_spinning_base_carries_the_centripetal_acceleration():
    # The base turns about its x axis at w; the foot, 0.8 m below the IMU's level, circles it: its acceleration
    # towards the axis is w^2 r, of which the vertical part, at the foot straight below, is +w^2 r.
    w = 3.0
    foot = FrameMotion((0.0, 0.0, -0.9), EYE, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    inertia = FootInertia((MOUNT, MOUNT), G)
    values = []
    for k in range(3):
        angle = w * k * DT
        up = (0.0, math.sin(angle), math.cos(angle))  # the world's vertical in the turning base frame
        # The IMU (at the axis' height + 0.3 m) is accelerated too: its specific force in the base frame.
        r_imu = 0.3
        centripetal_imu = (0.0, 0.0, -w * w * r_imu)
        world_g = tuple(G * u for u in up)
        specific = tuple(a + b for a, b in zip(centripetal_imu, world_g, strict=True))
        values.append(inertia.update(DT if k else 0.0, up, (w, 0.0, 0.0), specific, _kinematics(foot, foot)))
    # The foot's centre: 0.9 - 0.05 m below the base origin, 0.85 + 0.3 m below the IMU: w^2 r relative to it.
    radius_foot = 0.9 - MOUNT.com[2]
    expected = MASS * w * w * radius_foot - CORE  # 12.2 N less the noise's share
    assert values[2][0] == pytest.approx(expected, rel=0.01)
    assert values[2][1] == pytest.approx(expected, rel=0.01)


def test_a_still_foot_under_a_still_base_has_no_inertia():
    inertia = FootInertia((MOUNT, MOUNT), G)
    foot = FrameMotion((0.0, 0.1, -0.8), EYE, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    for k in range(3):
        # An IMU reading 1 m/s^2 too much (1.6 N on the foot, within the threshold) is taken as nil.
        values = inertia.update(DT if k else 0.0, (0.0, 0.0, 1.0), (0.0, 0.0, 0.0), (0.0, 0.0, G + 1.0),
                                _kinematics(foot, foot))  # fmt: skip
        assert values == (0.0, 0.0)
