"""The sensed state torque drive computes its feed-forward at (no physics): the base placed on the measured stance sole,
its twist holding that sole still, the tracking torques; and the reference jumps the motion's rates leave out."""

from __future__ import annotations

import math

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

from rtgait.estimation.state import FootState, Measurement  # noqa: E402
from rtgait.robot.model import RobotModel  # noqa: E402
from rtgait.robot.motion_rates import JUMP_ACCELERATION, MotionRates  # noqa: E402
from rtgait.stack.measured_motion import TRACKING_FREQUENCY, MeasuredMotion  # noqa: E402


@pytest.fixture(scope="module")
def talos() -> RobotModel:
    return RobotModel.load("talos")


def _foot(placement: pin.SE3, normal_force: float) -> FootState:
    """A foot whose sole frame is at ``placement`` (its roll, pitch, yaw as FootState reads them)."""
    roll, pitch, yaw = pin.rpy.matrixToRpy(placement.rotation)
    x, y, z = placement.translation
    return FootState((0.0, 0.0, normal_force), (0.0, 0.0, 0.0), normal_force, (x, y), (0.0, 0.0), (x, y, z, yaw),
                     roll, pitch, 0.0, True, 4)  # fmt: skip


def _measurement(left: FootState, right: FootState) -> Measurement:
    nan2 = (math.nan, math.nan)
    return Measurement(0.0, (0.0, 0.0, 0.9), (0.0, 0.0, 0.0), nan2, nan2, 900.0, left, right, (), 0)


def _soles(talos, q: np.ndarray) -> tuple[pin.SE3, pin.SE3]:
    model = talos.model
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    return data.oMf[talos.left_sole_id].copy(), data.oMf[talos.right_sole_id].copy()


def test_the_base_is_placed_on_the_measured_stance_sole(talos):
    tracking = MeasuredMotion(talos)
    q_ref = talos.q_half_sitting.copy()
    nv = talos.model.nv
    zeros = np.zeros(nv)
    joints = q_ref[7:].copy()
    joints[3] += 0.05  # the left knee bent further than the reference
    q_true = q_ref.copy()
    q_true[7:] = joints
    # The robot truly stands tilted by 20 mrad about x and moved, its left sole where the measurement has it.
    tilt = pin.SE3(pin.rpy.rpyToMatrix(0.02, 0.0, 0.1), np.array([0.3, -0.2, 0.01]))
    q_true[:7] = pin.SE3ToXYZQUAT(tilt * pin.XYZQUATToSE3(q_ref[:7]))
    left, right = _soles(talos, q_true)
    sensed = _measurement(_foot(left, 600.0), _foot(right, 300.0))  # the left foot carries more
    q, _, _ = tracking.update(q_ref, zeros, zeros, q_ref[7:], joints, np.zeros(nv - 6), sensed)
    base, truth = pin.XYZQUATToSE3(q[:7]), pin.XYZQUATToSE3(q_true[:7])
    np.testing.assert_allclose(base.translation, truth.translation, atol=1e-9)
    np.testing.assert_allclose(base.rotation, truth.rotation, atol=1e-9)
    np.testing.assert_array_equal(q[7:], joints)
    # The tracking torques: the knee's error times its stiffness (I w^2), the other joints none.
    w = 2.0 * math.pi * TRACKING_FREQUENCY
    expected = np.zeros(nv - 6)
    expected[3] = -0.05 * w * w * tracking.inertia[3]
    np.testing.assert_allclose(tracking.feedback, expected, atol=1e-12)
    np.testing.assert_allclose(tracking.damping, 2.0 * w * tracking.inertia)


def test_the_base_twist_holds_the_stance_sole_still(talos):
    tracking = MeasuredMotion(talos)
    q_ref = talos.q_half_sitting.copy()
    nv = talos.model.nv
    left, right = _soles(talos, q_ref)
    sensed = _measurement(_foot(left, 100.0), _foot(right, 800.0))  # the right foot carries more
    dq = np.random.default_rng(3).normal(0.0, 0.3, nv - 6)
    q, v, _ = tracking.update(q_ref, np.zeros(nv), np.zeros(nv), q_ref[7:], q_ref[7:], dq, sensed)
    model = talos.model
    data = model.createData()
    pin.forwardKinematics(model, data, q, v)
    still = pin.getFrameVelocity(model, data, talos.right_sole_id, pin.LOCAL).vector
    moving = pin.getFrameVelocity(model, data, talos.left_sole_id, pin.LOCAL).vector
    np.testing.assert_allclose(still, 0.0, atol=1e-9)
    assert np.linalg.norm(moving) > 0.01, "the other foot moves with the joints"
    np.testing.assert_array_equal(v[6:], dq)
    # Level and still, the base's task adds nothing to the reference's acceleration.
    q, v, a = tracking.update(q_ref, np.zeros(nv), np.zeros(nv), q_ref[7:], q_ref[7:], np.zeros(nv - 6), sensed)
    np.testing.assert_allclose(a, 0.0, atol=1e-9)


def test_a_sunk_base_is_pushed_up_and_a_tilted_one_left_to_the_joints(talos):
    tracking = MeasuredMotion(talos)
    q_ref = talos.q_half_sitting.copy()
    nv = talos.model.nv
    left, right = _soles(talos, q_ref)
    joints = q_ref[7:].copy()
    for side in (0, 6):  # both knees 50 mrad deeper, the hips and ankles as they were: the base sinks over the soles
        joints[side + 3] += 0.05
    q_sunk = q_ref.copy()
    q_sunk[7:] = joints
    sunk_left, _ = _soles(talos, q_sunk)
    # Standing on the left sole where it is, the bent robot's base is lower over it by `drop` and pitched.
    base_sunk = left * sunk_left.inverse() * pin.XYZQUATToSE3(q_ref[:7])
    drop = (q_ref[2] - left.translation[2]) - (base_sunk.translation[2] - left.translation[2])
    assert drop > 0.005
    sensed = _measurement(_foot(left, 500.0), _foot(right, 400.0))
    _, _, a = tracking.update(q_ref, np.zeros(nv), np.zeros(nv), joints, joints, np.zeros(nv - 6), sensed)
    w = 2.0 * math.pi * TRACKING_FREQUENCY
    base_z = base_sunk.rotation[2]  # world z in the sensed base's axes
    np.testing.assert_allclose(a[:3], w * w * drop * base_z, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(a[3:6], 0.0, atol=1e-12)
    # A tilt of the whole robot (the soles measured pitched by 10 mrad) asks no rotation of the base.
    tilt = pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.01, 0.0), np.zeros(3))
    sensed = _measurement(_foot(tilt * left, 500.0), _foot(tilt * right, 400.0))
    _, _, a = tracking.update(q_ref, np.zeros(nv), np.zeros(nv), q_ref[7:], q_ref[7:], np.zeros(nv - 6), sensed)
    np.testing.assert_allclose(a[3:6], 0.0, atol=1e-12)


def test_a_jump_of_the_reference_is_not_differenced(talos):
    model, dt = talos.model, 0.002
    limits = np.full(model.nv - 6, 10.0)
    plain, guarded = MotionRates(model, dt, 0.0), MotionRates(model, dt, 0.0, limits)
    q = talos.q_half_sitting.copy()
    for rates in (plain, guarded):
        rates.update(q)
    moved = q.copy()
    moved[7 + 3] += 0.001  # 0.5 rad/s: a motion
    for rates in (plain, guarded):
        v, _ = rates.update(moved)
        assert v[6 + 3] == pytest.approx(0.5)
    before = guarded.acceleration.copy()
    jumped = moved.copy()
    jumped[7 + 3] += 0.1  # 50 rad/s, beyond the 10 rad/s limit: a jump
    v_plain, a_plain = plain.update(jumped)
    v_guarded, a_guarded = guarded.update(jumped)
    assert v_plain[6 + 3] == pytest.approx(50.0) and a_plain[6 + 3] == pytest.approx(49.5 / dt)
    assert guarded.jumps == 1 and v_guarded[6 + 3] == pytest.approx(0.5)
    np.testing.assert_array_equal(a_guarded, before)  # the rates kept
    # The next tick differences from the jumped configuration.
    after = jumped.copy()
    after[7 + 3] += 0.001
    assert guarded.update(after)[0][6 + 3] == pytest.approx(0.5)
    # The base moved at once by a millimetre: 250 m/s^2 at 2 ms, beyond JUMP_ACCELERATION.
    base = after.copy()
    base[0] += 0.001
    assert 0.001 / dt / dt > JUMP_ACCELERATION
    guarded.update(base)
    assert guarded.jumps == 2


def test_without_tracking_only_the_state_is_sensed(talos):
    # Position drive: the base still sits on the measured sole, but nothing is added to the IK's motion.
    tracking = MeasuredMotion(talos, track=False)
    q_ref = talos.q_half_sitting.copy()
    nv = talos.model.nv
    joints = q_ref[7:] + 0.02
    left, right = _soles(talos, q_ref)
    tilt = pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.01, 0.0), np.zeros(3))
    sensed = _measurement(_foot(tilt * left, 500.0), _foot(tilt * right, 400.0))
    a_ref = np.linspace(-1.0, 1.0, nv)
    q, _, a = tracking.update(q_ref, np.zeros(nv), a_ref, q_ref[7:], joints, np.zeros(nv - 6), sensed)
    np.testing.assert_array_equal(a, a_ref)
    np.testing.assert_array_equal(tracking.feedback, 0.0)
    np.testing.assert_array_equal(tracking.damping, 0.0)
    np.testing.assert_array_equal(q[7:], joints)
    assert not np.allclose(q[3:7], q_ref[3:7]), "the base is the sensed one, tilted"


@pytest.mark.parametrize("heavier", ["left", "right"])
def test_the_estimators_kinematics_give_the_same_sensed_state(talos, heavier):
    """The soles relative to the base from the estimator's kinematics place the base and give its twist as the
    sensed state's own kinematics pass does (its Jacobian), for a bent, moving robot standing tilted."""
    from rtgait.robot.kinematics import PinocchioKinematics

    rng = np.random.default_rng(7)
    nv = talos.model.nv
    q_ref = talos.q_half_sitting.copy()
    joints = q_ref[7:] + rng.normal(0.0, 0.05, nv - 6)
    dq = rng.normal(0.0, 0.5, nv - 6)
    q_true = q_ref.copy()
    q_true[7:] = joints
    tilt = pin.SE3(pin.rpy.rpyToMatrix(0.03, -0.02, 0.4), np.array([0.2, 0.1, 0.02]))
    q_true[:7] = pin.SE3ToXYZQUAT(tilt * pin.XYZQUATToSE3(q_ref[:7]))
    left, right = _soles(talos, q_true)
    loads = (700.0, 200.0) if heavier == "left" else (200.0, 700.0)
    sensed = _measurement(_foot(left, loads[0]), _foot(right, loads[1]))
    body = PinocchioKinematics(talos).update(joints, dq)
    zeros = np.zeros(nv)
    own = [x.copy() for x in MeasuredMotion(talos).update(q_ref, zeros, zeros, q_ref[7:], joints, dq, sensed)]
    shared = MeasuredMotion(talos).update(q_ref, zeros, zeros, q_ref[7:], joints, dq, sensed, body)
    np.testing.assert_allclose(shared[0], own[0], atol=1e-12)
    np.testing.assert_allclose(shared[1], own[1], atol=1e-10)
    np.testing.assert_allclose(shared[2], own[2], atol=1e-9)


def test_after_a_jump_the_rates_follow_the_new_references_velocity(talos):
    """A replan from a pushed state moves the reference at once and changes its velocity: the base runs at 0.05 m/s,
    jumps by 5 mm and runs on at 0.3 m/s (0.25 m/s more than the old velocity, 125 m/s^2 over a 2 ms tick, beyond
    JUMP_ACCELERATION). The rates must take the new velocity from the ticks after the jump, with no acceleration
    burst, not stay at the old one (every later tick read as a jump against it)."""
    model, dt, tau = talos.model, 0.002, 0.005
    limits = np.full(model.nv - 6, 10.0)
    rates = MotionRates(model, dt, tau, limits)
    v0, v1 = np.zeros(model.nv), np.zeros(model.nv)
    v0[0], v1[0] = 0.05, 0.3
    v0[6 + 3] = v1[6 + 3] = 0.5  # a joint moving through it all
    assert (v1[0] - v0[0]) / dt > JUMP_ACCELERATION
    q = talos.q_half_sitting.copy()
    for _ in range(100):  # the old reference, long enough for the low-pass to settle on v0
        rates.update(q)
        q = pin.integrate(model, q, v0 * dt)
    np.testing.assert_allclose(rates.velocity, v0, atol=1e-9)
    jump = np.zeros(model.nv)
    jump[0] = 0.005
    q = pin.integrate(model, q, jump)
    peak = 0.0
    for _ in range(50):  # 0.1 s of the new reference: 20 time constants
        q = pin.integrate(model, q, v1 * dt)
        _, a = rates.update(q)
        peak = max(peak, float(np.abs(a).max()))
    # The jump's tick, and the next (its difference compared with the jump's own); the motion after it is a motion.
    assert rates.jumps == 2
    np.testing.assert_allclose(rates.velocity, v1, atol=1e-9)
    np.testing.assert_allclose(rates.acceleration, 0.0, atol=1e-6)
    assert peak < 1e-6, "the new velocity is taken at once, not filtered in as an acceleration"
