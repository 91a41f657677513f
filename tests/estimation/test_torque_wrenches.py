"""The soles' wrenches from the legs' joint torques (rtgait.estimation.torque_wrenches) against their definition: the
motion handed to the legs' inverse dynamics (finite-differenced joint and base accelerations, the base origin's
specific force from an IMU off the origin), the wrench through the Jacobian and its first-order low-pass."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.estimation.joint_friction import MEASURED_STICTION_SPEED, JointFriction
from rtgait.estimation.torque_wrenches import DEFAULT_WRENCH_CUTOFF, TorqueWrenches

DT = 0.002
G = 9.81


class Legs:
    """Two legs of six joints whose inverse dynamics are a fixed torque plus a linear term in the base's specific
    force, recording the motion they are handed."""

    joint_count = 14
    leg_joints = (tuple(range(6)), tuple(range(7, 13)))  # a joint between the legs: index arrays, not a slice

    def __init__(self) -> None:
        rng = np.random.default_rng(2)
        self.jacobians = rng.normal(size=(2, 6, 6)) + 3.0 * np.eye(6)
        self.base = rng.normal(size=(2, 6))
        self.gain = rng.normal(size=(2, 6, 3))
        self.calls: list[tuple] = []

    def leg_dynamics(self, angular_velocity, acceleration, joint_accelerations):
        self.calls.append((angular_velocity, acceleration, joint_accelerations.copy()))
        return self.jacobians, self.base + self.gain @ np.asarray(acceleration[:3])


def _torques_for(legs: Legs, wrenches: np.ndarray, specific: np.ndarray) -> np.ndarray:
    """The joint torques under the sole wrenches ``wrenches``: tau = tau_id - J^T F, in the robot's joint order."""
    needed = legs.base + legs.gain @ specific
    torques = np.zeros(legs.joint_count)
    for i, joints in enumerate(legs.leg_joints):
        torques[list(joints)] = needed[i] - legs.jacobians[i].T @ wrenches[i]
    return torques


def test_the_legs_are_handed_the_finite_differenced_motion():
    legs = Legs()
    estimate = TorqueWrenches(legs, cutoff=math.inf, acceleration_cutoff=math.inf)
    rng = np.random.default_rng(5)
    velocities = [rng.normal(size=legs.joint_count) for _ in range(3)]
    gyro = [tuple(rng.normal(size=3)) for _ in range(3)]
    imu, imu_velocity, specific = (0.05, -0.02, 0.1), (0.01, 0.02, -0.03), (0.3, -0.2, 9.7)
    for k in range(3):
        estimate.update(DT, velocities[k], np.zeros(legs.joint_count), gyro[k], specific, imu, imu_velocity)
    first, last = legs.calls[0], legs.calls[-1]
    np.testing.assert_array_equal(first[2], 0.0)  # no earlier tick: no accelerations
    np.testing.assert_allclose(last[2], (velocities[2] - velocities[1]) / DT, rtol=1e-12)
    alpha = (np.array(gyro[2]) - np.array(gyro[1])) / DT
    np.testing.assert_allclose(last[1][3:], alpha, rtol=1e-12)
    # f_B = f_I - w' x p_I - w x (w x p_I) - 2 w x p_I'
    w, p, u = np.array(gyro[2]), np.array(imu), np.array(imu_velocity)
    expected = np.array(specific) - np.cross(alpha, p) - np.cross(w, np.cross(w, p)) - 2.0 * np.cross(w, u)
    np.testing.assert_allclose(last[1][:3], expected, rtol=1e-12)
    assert last[0] == gyro[2]


def test_the_accelerations_are_low_passed_from_the_first_difference_on():
    # y_k = beta y_k-1 + (1 - beta) x_k on each finite-differenced acceleration, started at the first difference.
    legs = Legs()
    cutoff = 30.0
    estimate = TorqueWrenches(
        legs, cutoff=math.inf, acceleration_cutoff=cutoff, contact_cutoff=math.inf, momentum=False
    )
    rng = np.random.default_rng(7)
    velocities = [rng.normal(size=legs.joint_count) for _ in range(6)]
    gyro = [tuple(rng.normal(size=3)) for _ in range(6)]
    wrenches = rng.normal(size=(2, 6)) * 50.0
    specific = np.array([0.0, 0.0, G])
    torques = _torques_for(legs, wrenches, specific)
    for k in range(6):
        estimate.update(DT, velocities[k], torques, gyro[k], tuple(specific), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    assert len(legs.calls) == 6  # one evaluation of the legs' dynamics a tick
    beta = math.exp(-2.0 * math.pi * cutoff * DT)
    joints = (velocities[1] - velocities[0]) / DT
    base = (np.array(gyro[1]) - np.array(gyro[0])) / DT
    np.testing.assert_allclose(legs.calls[1][2], joints, rtol=1e-12)
    for k in range(2, 6):
        joints = beta * joints + (1.0 - beta) * (velocities[k] - velocities[k - 1]) / DT
        base = beta * base + (1.0 - beta) * (np.array(gyro[k]) - np.array(gyro[k - 1])) / DT
        np.testing.assert_allclose(legs.calls[k][2], joints, rtol=1e-12)
        np.testing.assert_allclose(legs.calls[k][1][3:], base, rtol=1e-12)
    # These legs' dynamics do not depend on the joint accelerations: the contact forces are the torques' wrenches.
    np.testing.assert_allclose(estimate.contact_forces, wrenches[:, 0:3], atol=1e-9)


def test_the_contact_forces_are_low_passed_at_their_own_cut_off():
    legs = Legs()
    estimate = TorqueWrenches(legs, cutoff=30.0, contact_cutoff=60.0, momentum=False)
    specific = np.array([0.0, 0.0, G])
    before = np.array([[1.0, -2.0, 150.0, 0.5, -1.0, 0.1], [0.0, 0.0, 80.0, 0.0, 0.0, 0.0]])
    after = np.array([[0.0, 0.0, 0.0, 0.0, 0.0, 0.0], [-3.0, 4.0, 200.0, 1.0, 2.0, -0.2]])
    zero = np.zeros(legs.joint_count)
    for wrenches in (before, after, after, after):
        reported = estimate.update(DT, zero, _torques_for(legs, wrenches, specific), (0.0, 0.0, 0.0), tuple(specific),
                                   (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))  # fmt: skip
    slow, fast = math.exp(-2.0 * math.pi * 30.0 * DT), math.exp(-2.0 * math.pi * 60.0 * DT)
    np.testing.assert_allclose(reported, after + (before - after) * slow**3, atol=1e-9)
    np.testing.assert_allclose(estimate.contact_forces, (after + (before - after) * fast**3)[:, 0:3], atol=1e-9)


def test_an_imu_off_a_spinning_base_gives_the_origins_specific_force():
    # The base's origin stands still, upright, while the base spins up about a tilted axis: an IMU 0.1 m off the
    # origin feels w' x p + w x (w x p) besides gravity; the legs are handed the origin's specific force, g upward.
    legs = Legs()
    estimate = TorqueWrenches(legs, cutoff=math.inf)
    axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    alpha, p = 4.0 * axis, np.array([0.1, 0.05, -0.03])
    for k in range(5):
        w = alpha * k * DT  # the axis is fixed in the base, so the base-frame angular velocity grows along it
        f = np.cross(alpha, p) + np.cross(w, np.cross(w, p)) + np.array([0.0, 0.0, G])
        estimate.update(DT, np.zeros(legs.joint_count), np.zeros(legs.joint_count), tuple(w), tuple(f), tuple(p),
                        (0.0, 0.0, 0.0))  # fmt: skip
    np.testing.assert_allclose(legs.calls[-1][1], (0.0, 0.0, G, *alpha), atol=1e-9)


def test_the_wrench_through_the_jacobian_low_passed():
    legs = Legs()
    cutoff = 30.0
    estimate = TorqueWrenches(legs, cutoff=cutoff, momentum=False)
    specific = np.array([0.0, 0.0, G])
    before = np.array([[1.0, -2.0, 150.0, 0.5, -1.0, 0.1], [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]])
    after = np.array([[0.0, 0.0, 0.0, 0.0, 0.0, 0.0], [-3.0, 4.0, 200.0, 1.0, 2.0, -0.2]])
    zero = np.zeros(legs.joint_count)

    def update(wrenches: np.ndarray, dt: float = DT):
        return np.array(estimate.update(dt, zero, _torques_for(legs, wrenches, specific), (0.0, 0.0, 0.0),
                                        tuple(specific), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)))  # fmt: skip

    np.testing.assert_allclose(update(before), before, atol=1e-9)  # the first tick: the wrench as it is
    beta = math.exp(-2.0 * math.pi * cutoff * DT)
    for k in range(1, 6):
        out = update(after)
        np.testing.assert_allclose(out, after + (before - after) * beta**k, atol=1e-9)
    # A repeated reading keeps the last wrenches.
    np.testing.assert_array_equal(update(before, 0.0), out)
    # Without the filter: the wrench at once.
    estimate = TorqueWrenches(legs, cutoff=math.inf, momentum=False)
    update(before)
    np.testing.assert_allclose(update(after), after, atol=1e-9)


def test_bad_settings_are_refused():
    legs = Legs()
    assert DEFAULT_WRENCH_CUTOFF > 0.0
    with pytest.raises(ValueError, match="cut-off"):
        TorqueWrenches(legs, cutoff=0.0)
    with pytest.raises(ValueError, match="accelerations' filter cut-off"):
        TorqueWrenches(legs, acceleration_cutoff=-1.0)
    with pytest.raises(ValueError, match="contact forces' filter cut-off"):
        TorqueWrenches(legs, contact_cutoff=0.0)
    legs.leg_joints = (tuple(range(6)), tuple(range(7, 12)))
    with pytest.raises(ValueError, match="leg_joints"):
        TorqueWrenches(legs)


def test_the_joints_friction_is_taken_out_of_the_motor_torques():
    """Motor torques that carry the gears' friction on top of the links' torques: with the friction given, the
    wrench is the ground's; without it, the friction reads as a wrench of J^-T tau_f."""
    legs = Legs()
    rng = np.random.default_rng(7)
    coulomb, viscous = rng.uniform(1.0, 2.5, legs.joint_count), rng.uniform(0.1, 0.3, legs.joint_count)
    friction = JointFriction(coulomb, viscous)
    velocities = rng.uniform(-3.0, 3.0, legs.joint_count)
    velocities[0] = 0.3 * MEASURED_STICTION_SPEED  # a slow joint: a part of F_c
    # The friction opposing each joint's velocity, written out here (tanh-smoothed Coulomb, viscous).
    tau_f = np.array([c * math.tanh(v / MEASURED_STICTION_SPEED) + b * v
                      for c, b, v in zip(coulomb, viscous, velocities, strict=True)])  # fmt: skip
    specific = np.array([0.0, 0.0, G])
    ground = np.array([[2.0, -1.0, 160.0, 0.5, -1.0, 0.1], [-3.0, 4.0, 120.0, 1.0, 2.0, -0.2]])
    motor = _torques_for(legs, ground, specific) + tau_f

    def estimate(with_friction: JointFriction | None) -> np.ndarray:
        wrenches = TorqueWrenches(legs, cutoff=math.inf, acceleration_cutoff=math.inf, friction=with_friction)
        return np.array(wrenches.update(DT, velocities, motor, (0.0, 0.0, 0.0), tuple(specific), (0.0, 0.0, 0.0),
                                        (0.0, 0.0, 0.0)))  # fmt: skip

    np.testing.assert_allclose(estimate(friction), ground, atol=1e-9)
    phantom = np.array([np.linalg.solve(legs.jacobians[i].T, tau_f[list(joints)])
                        for i, joints in enumerate(legs.leg_joints)])  # fmt: skip
    np.testing.assert_allclose(estimate(None), ground - phantom, atol=1e-9)
    with pytest.raises(ValueError, match="one value per joint"):
        TorqueWrenches(legs, friction=JointFriction(coulomb[:3], viscous[:3]))


class FreeLegs:
    """Two six-joint legs on a base at rest, without gravity, of constant inertia ``M`` each (``M q'' = tau + J^T
    F``): their inverse dynamics for the joints' accelerations are ``M q''``."""

    joint_count = 12
    leg_joints = (tuple(range(6)), tuple(range(6, 12)))

    def __init__(self) -> None:
        rng = np.random.default_rng(11)
        roots = rng.normal(size=(2, 6, 6)) * 0.3
        self.inertia = roots @ roots.transpose(0, 2, 1) + 0.2 * np.eye(6)  # kg m^2, symmetric positive definite
        self.jacobians = rng.normal(size=(2, 6, 6)) * 0.2 + 0.5 * np.eye(6)

    def leg_dynamics(self, angular_velocity, acceleration, joint_accelerations):
        legs = joint_accelerations.reshape(2, 6)
        return self.jacobians, np.einsum("lij,lj->li", self.inertia, legs)


def _torque_step_run(estimate: TorqueWrenches, legs: FreeLegs, step: float = 20.0, ticks: int = 12) -> np.ndarray:
    """The left leg's hip torque rises by ``step`` (N m) over one period (linear between the readings) and holds;
    the feet are free, the joints' velocities the exact ones. Returns the contact forces' largest magnitude."""
    torques, velocities = np.zeros(legs.joint_count), np.zeros(legs.joint_count)
    largest = 0.0
    for k in range(ticks):
        new = np.zeros(legs.joint_count)
        new[0] = step if k >= 3 else 0.0
        # The velocity's change over the period is M^-1 times the torque's integral: the trapezoid, exact for a ramp.
        mean = 0.5 * (torques + new)
        velocities = velocities + DT * np.concatenate([np.linalg.solve(legs.inertia[i], mean[6 * i : 6 * i + 6])
                                                       for i in (0, 1)])  # fmt: skip
        torques = new
        estimate.update(DT, velocities, torques, (0.0, 0.0, 0.0), (0.0, 0.0, G), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        largest = max(largest, float(np.abs(estimate.contact_forces).max()))
    return largest


def test_a_torque_step_on_a_free_leg_reads_no_contact_force():
    # The momentum observer: the torque that accelerates the leg shows in its momentum as well, whatever the filter.
    legs = FreeLegs()
    assert _torque_step_run(TorqueWrenches(legs, momentum=True), legs) < 1e-9
    # The filtered accelerations' residual reads the step as a ground force of tens of newtons on the free foot.
    assert _torque_step_run(TorqueWrenches(legs, momentum=False), legs) > 10.0


def test_the_momentum_observer_recovers_a_static_legs_wrench_through_its_low_pass():
    # A static leg (no motion) under the ground's wrench: tau = tau_id - J^T F. The observer's input is the torques'
    # mean over the period, so a step of the wrench enters half on its first tick, then whole, through one low-pass.
    legs = Legs()
    cutoff = 30.0
    estimate = TorqueWrenches(legs, cutoff=cutoff, momentum=True)
    specific = np.array([0.0, 0.0, G])
    before = np.array([[1.0, -2.0, 150.0, 0.5, -1.0, 0.1], [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]])
    after = np.array([[0.0, 0.0, 0.0, 0.0, 0.0, 0.0], [-3.0, 4.0, 200.0, 1.0, 2.0, -0.2]])
    zero = np.zeros(legs.joint_count)

    def update(wrenches: np.ndarray) -> np.ndarray:
        return np.array(estimate.update(DT, zero, _torques_for(legs, wrenches, specific), (0.0, 0.0, 0.0),
                                        tuple(specific), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)))  # fmt: skip

    for _ in range(3):
        np.testing.assert_allclose(update(before), before, atol=1e-9)  # a constant wrench, from the first tick on
    beta = math.exp(-2.0 * math.pi * cutoff * DT)
    expected = beta * before + (1.0 - beta) * 0.5 * (before + after)
    for _ in range(5):
        out = update(after)
        np.testing.assert_allclose(out, expected, atol=1e-9)
        np.testing.assert_allclose(estimate.contact_forces, expected[:, 0:3], atol=1e-9)  # one filter for both
        expected = beta * expected + (1.0 - beta) * after


class HangingLegs(FreeLegs):
    """:class:`FreeLegs` hanging from a base that accelerates: ``M q'' + K f = tau + J^T F``, ``f`` the base's
    specific force (gravity included), ``K`` a fixed coupling of each leg's joints to it."""

    def __init__(self) -> None:
        super().__init__()
        self.coupling = np.random.default_rng(13).normal(size=(2, 6, 3)) * 0.5  # kg m

    def leg_dynamics(self, angular_velocity, acceleration, joint_accelerations):
        jacobians, inertial = super().leg_dynamics(angular_velocity, acceleration, joint_accelerations)
        return jacobians, inertial + self.coupling @ np.asarray(acceleration[:3])


def _jolt_run(estimate: TorqueWrenches, legs: HangingLegs, jolt: float = 50.0, ticks: int = 12) -> float:
    """The feet free, the drives hold the legs against gravity (``tau = K g``) and the base jolts by ``jolt`` (m/s^2)
    along x for one period: the joints accelerate relative to the base, ``q'' = -M^-1 K (f - g)``, as a free foot
    does when its hip jerks. Returns the contact forces' largest magnitude."""
    gravity = np.array([0.0, 0.0, G])
    torques = np.concatenate([legs.coupling[i] @ gravity for i in (0, 1)])
    velocities = np.zeros(legs.joint_count)
    largest = 0.0
    for k in range(ticks):
        specific = gravity + (np.array([jolt, 0.0, 0.0]) if k == 4 else 0.0)
        relative = np.concatenate([np.linalg.solve(legs.inertia[i], -legs.coupling[i] @ (specific - gravity))
                                   for i in (0, 1)])  # fmt: skip
        velocities = velocities + DT * relative
        estimate.update(DT, velocities, torques, (0.0, 0.0, 0.0), tuple(specific), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        largest = max(largest, float(np.abs(estimate.contact_forces).max()))
    return largest


def test_a_jolt_of_the_base_reads_no_contact_force_on_a_free_leg():
    # The accelerometer's specific force and the joints' accelerations pass the same low-pass: the leg's balance
    # holds between the filtered terms as between the raw ones (a jolt of the base, e.g. the stance foot slapping
    # the floor, is no ground force on the swinging foot).
    legs = HangingLegs()
    assert _jolt_run(TorqueWrenches(legs, momentum=False), legs) < 1e-9
    assert _jolt_run(TorqueWrenches(legs, momentum=True), legs) < 1e-9
    # Without a low-pass on the accelerations it holds too; one on the joints' alone would read tens of newtons.
    assert _jolt_run(TorqueWrenches(legs, acceleration_cutoff=math.inf, momentum=False), legs) < 1e-9
