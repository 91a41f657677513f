"""Whole-body inverse dynamics and the feet's wrenches, against Pinocchio's own algorithms and Newton-Euler."""

from __future__ import annotations

import math

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

from scipy.optimize import nnls  # noqa: E402

from rtgait.core.geometry.footsteps import SoleRect  # noqa: E402
from rtgait.interface.task_targets import IKTargets  # noqa: E402
from rtgait.robot.contact_wrenches import SoleCone, WrenchDistributor, force_transform  # noqa: E402
from rtgait.robot.controller_info import robot_info  # noqa: E402
from rtgait.robot.drives import joint_drives  # noqa: E402
from rtgait.robot.ik import WholeBodyIK  # noqa: E402
from rtgait.robot.inverse_dynamics import InverseDynamics  # noqa: E402
from rtgait.robot.motion_rates import MotionRates  # noqa: E402

SOLE = SoleRect(front=0.1, back=0.08, inner=0.05, outer=0.07)


def _state(robot, seed: int, speed: float = 1.0):
    """A configuration near half-sitting with a moved, turned base, and a velocity and an acceleration."""
    rng = np.random.default_rng(seed)
    q = robot.q_half_sitting.copy()
    q[7:] += rng.normal(scale=0.1, size=robot.model.nq - 7)
    turn = pin.exp3(rng.normal(scale=0.1, size=3))
    q[:3] += rng.normal(scale=0.2, size=3)
    q[3:7] = pin.Quaternion(turn).coeffs()
    v = rng.normal(scale=speed, size=robot.model.nv)
    a = rng.normal(scale=3.0 * speed, size=robot.model.nv)
    return q, v, a


def _total(dynamics: InverseDynamics, wrenches: np.ndarray) -> np.ndarray:
    """The feet's wrenches summed in world axes about the origin."""
    return sum(force_transform(frame) @ wrench for frame, wrench in zip(dynamics.sole_frames, wrenches, strict=True))


@pytest.fixture(scope="module")
def dynamics(talos):
    return InverseDynamics(talos, robot_info(talos).sole)


# ----- inverse dynamics --------------------------------------------------------------------------------------------
@pytest.mark.parametrize(("name", "seed"), [("talos", 0), ("talos", 1), ("g1", 2)])
def test_torques_are_pinocchio_rnea_with_the_wrenches_as_external_forces(request, name, seed):
    # tau = RNEA - J^T w against Pinocchio's RNEA with the wrenches applied to the soles' joints: both the joints'
    # rows (the torques) and the base's (what the wrenches leave unbalanced).
    robot = request.getfixturevalue(name)
    dynamics = InverseDynamics(robot, robot_info(robot).sole)
    q, v, a = _state(robot, seed)
    wrenches = np.random.default_rng(seed + 10).normal(scale=100.0, size=(2, 6))
    dynamics.update(q, v, a)
    model = pin.Model(robot.model)
    model.armature[6:] = joint_drives(robot)[1]
    forces = pin.StdVec_Force()
    for _ in range(model.njoints):
        forces.append(pin.Force.Zero())
    for frame_id, wrench in zip((robot.left_sole_id, robot.right_sole_id), wrenches, strict=True):
        frame = model.frames[frame_id]
        forces[frame.parentJoint] += frame.placement.act(pin.Force(wrench))
    expected = pin.rnea(model, model.createData(), q, v, a, forces)
    np.testing.assert_allclose(dynamics.torques(wrenches), expected[6:], atol=1e-9)
    np.testing.assert_allclose(dynamics.base_residual(wrenches), expected[:6], atol=1e-9)


@pytest.mark.parametrize("seed", [0, 1])
def test_the_required_wrench_is_the_whole_robot_s_newton_euler(talos, dynamics, seed):
    # M (c'' - g) and L' + c x M (c'' - g) from Pinocchio's centroidal dynamics, an independent path.
    q, v, a = _state(talos, seed)
    required = dynamics.update(q, v, a)
    data = talos.model.createData()
    pin.computeCentroidalMomentumTimeVariation(talos.model, data, q, v, a)
    force = data.dhg.linear - talos.mass * talos.model.gravity.linear
    moment = data.dhg.angular + np.cross(data.com[0], force)
    np.testing.assert_allclose(required.force, force, atol=1e-8)
    np.testing.assert_allclose(required.moment, moment, atol=1e-8)


def test_the_armature_adds_its_inertia_times_the_acceleration(talos, dynamics):
    q, v, a = _state(talos, 3)
    dynamics.update(q, v, a)
    bare = InverseDynamics(talos, robot_info(talos).sole, armature=np.zeros(talos.model.nv - 6))
    bare.update(q, v, a)
    none = np.zeros((2, 6))
    np.testing.assert_allclose(dynamics.torques(none) - bare.torques(none), joint_drives(talos)[1] * a[6:], atol=1e-9)
    assert (joint_drives(talos)[1] > 0.0).all()


@pytest.mark.parametrize("seed", [3, 4])
def test_the_soles_and_the_required_wrench_are_pinocchio_s_placements_and_the_base_s_rnea(talos, dynamics, seed):
    """The soles' placements the distribution takes are Pinocchio's own at that configuration, and the wrench as
    floats is the base's RNEA carried to the world: each against Pinocchio's algorithms run here."""
    q, v, a = _state(talos, seed)
    values = dynamics.compute(q, v, a)
    model = dynamics.model
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    for side, sole in enumerate((talos.left_sole_id, talos.right_sole_id)):
        expected = data.oMf[sole].homogeneous
        np.testing.assert_array_equal(dynamics.sole_frames[side], expected)
        np.testing.assert_array_equal(dynamics.sole_rows[side], expected[:3].tolist())
    base = pin.rnea(model, data, q, v, a)[:6]
    np.testing.assert_allclose(values, data.oMi[1].act(pin.Force(base)).vector, rtol=1e-12, atol=1e-9)
    required = dynamics.required
    np.testing.assert_array_equal(np.r_[required.force, required.moment], values)
    # From now on distribute shares out a weight of 900 N through the soles' midpoint.
    middle = 0.5 * (dynamics.sole_frames[0][:3, 3] + dynamics.sole_frames[1][:3, 3])
    weight = np.array([0.0, 0.0, 900.0])
    dynamics.require_values([*weight, *np.cross(middle, weight)])
    np.testing.assert_array_equal(dynamics.required.force, weight)
    result = dynamics.distribute((True, True), 0.5)
    np.testing.assert_allclose(_total(dynamics, result.wrenches), np.r_[weight, np.cross(middle, weight)], atol=1e-8)


def test_the_distribution_of_rows_is_the_distribution_of_frames(talos, dynamics):
    """Given as rows of Python floats or as homogeneous matrices, the same frames give the same wrenches to the bit,
    in double support (closed form), single support and when the QP runs."""
    q, v, a = _state(talos, 6, speed=0.1)
    dynamics.update(q, v, a)
    distributor, frames, rows = dynamics.distributor, dynamics.sole_frames, dynamics.sole_rows
    required = dynamics.required
    force, moment = required.force.tolist(), required.moment.tolist()
    for contact, ratio in (((True, True), 0.4), ((True, False), 1.0), ((False, True), 0.0), ((True, True), 1.0)):
        by_frames = distributor.distribute(force, moment, frames, contact, ratio)
        by_rows = distributor.distribute_rows(force, moment, rows, contact, ratio)
        assert by_rows.method == by_frames.method and by_rows.residual == by_frames.residual
        np.testing.assert_array_equal(by_rows.wrenches, by_frames.wrenches)


def test_standing_still_the_zmp_is_under_the_com(talos, dynamics):
    q = talos.q_half_sitting
    zero = np.zeros(talos.model.nv)
    required = dynamics.update(q, zero, zero)
    np.testing.assert_allclose(required.force, [0.0, 0.0, talos.mass * 9.81], atol=1e-9)
    np.testing.assert_allclose(required.zmp(), talos.cog_half_sitting[:2], atol=1e-12)


# ----- the feet's wrenches from the motion ----------------------------------------------------------------------
def test_double_support_wrenches_sum_to_the_required_one_and_are_the_nearest_to_the_split(talos, dynamics):
    q, v, a = _state(talos, 4, speed=0.1)
    q[7:] = talos.q_half_sitting[7:]  # level soles on the floor, the base moved and turned
    q[:7] = talos.q_half_sitting[:7]
    required = dynamics.update(q, v, a)
    left, right = dynamics.sole_frames[0][:2, 3], dynamics.sole_frames[1][:2, 3]
    cops = (left + np.array([0.02, -0.01]), right + np.array([-0.03, 0.01]))
    result = dynamics.distribute((True, True), 0.3, tuple(cops[0]), tuple(cops[1]))
    assert result.method == "closed-form" and result.residual == 0.0
    W = np.concatenate([required.force, required.moment])
    np.testing.assert_allclose(_total(dynamics, result.wrenches), W, atol=1e-8)
    np.testing.assert_allclose(dynamics.base_residual(result.wrenches), 0.0, atol=1e-8)
    # The nearest wrenches to the desired ones that sum to W: the general weighted projection, with numpy's solver.
    desired = []
    for frame, share, cop in zip(dynamics.sole_frames, (0.3, 0.7), cops, strict=True):
        rotation, point = frame[:3, :3], frame[:3, 3]
        force = share * required.force
        arm = np.array([cop[0], cop[1], point[2]]) - point
        desired.append(np.concatenate([rotation.T @ force, rotation.T @ np.cross(arm, force)]))
    desired = np.concatenate(desired)
    A = np.hstack([force_transform(frame) for frame in dynamics.sole_frames])
    length = dynamics.distributor.cones[0].length
    inverse_weight = np.tile([1.0, 1.0, 1.0, length**2, length**2, length**2], 2)
    nearest = desired + inverse_weight * (A.T @ np.linalg.solve((A * inverse_weight) @ A.T, W - A @ desired))
    np.testing.assert_allclose(result.wrenches.reshape(12), nearest, atol=1e-8)


def test_a_static_split_at_the_motion_s_zmp_is_kept_as_it_is(talos, dynamics):
    # Standing still with the COM over a point between the feet: the split whose loads and CoPs make that ZMP sums to
    # the weight already, and the distribution does not change it.
    q = talos.q_half_sitting
    zero = np.zeros(talos.model.nv)
    required = dynamics.update(q, zero, zero)
    left, right = dynamics.sole_frames[0][:2, 3], dynamics.sole_frames[1][:2, 3]
    zmp = np.array(required.zmp())
    ratio = float((zmp - right) @ (left - right) / ((left - right) @ (left - right)))
    offset = zmp - (right + ratio * (left - right))
    result = dynamics.distribute((True, True), ratio, tuple(left + offset), tuple(right + offset))
    weight = talos.mass * 9.81
    np.testing.assert_allclose(result.wrenches[:, 2], [ratio * weight, (1.0 - ratio) * weight], rtol=1e-9)
    for cone, wrench, frame in zip(dynamics.distributor.cones, result.wrenches, dynamics.sole_frames, strict=True):
        np.testing.assert_allclose(cone.cop(wrench), frame[:2, :2].T @ offset, atol=1e-9)


def test_single_support_puts_it_all_on_the_stance_foot(talos, dynamics):
    half = 0.5 * talos.step_width
    targets = IKTargets((0.01, half, talos.description.cog_height), (0.0, half, 0.0, 0.0), (0.0, -half, 0.05, 0.0))
    q, _ = WholeBodyIK(talos).solve(targets, talos.q_half_sitting, 100, 1e-9)  # the COM over the left sole
    _, v, a = _state(talos, 5, speed=0.1)
    required = dynamics.update(q, v, a)
    result = dynamics.distribute((True, False))
    assert result.method == "single"
    np.testing.assert_array_equal(result.wrenches[1], 0.0)
    np.testing.assert_allclose(_total(dynamics, result.wrenches), np.r_[required.force, required.moment], atol=1e-8)
    np.testing.assert_allclose(dynamics.base_residual(result.wrenches), 0.0, atol=1e-8)
    cop = dynamics.distributor.cones[0].cop(result.wrenches[0])
    assert abs(cop[0]) < 0.05 and abs(cop[1]) < 0.05


def test_a_single_support_the_sole_cannot_give_gets_the_nearest_it_can(talos, dynamics):
    q = talos.q_half_sitting  # the COM between the feet, standing on the right one alone
    zero = np.zeros(talos.model.nv)
    dynamics.update(q, zero, zero)
    result = dynamics.distribute((False, True))
    assert result.method == "qp" and result.residual > 100.0  # N: the weight's moment about a sole 8 cm away
    assert (dynamics.distributor.cones[1].faces @ result.wrenches[1]).max() <= 1e-6
    np.testing.assert_array_equal(result.wrenches[0], 0.0)


# ----- the distributor's cones and QP ------------------------------------------------------------------------------
@pytest.mark.parametrize("side", ["left", "right"])
def test_the_cone_s_faces_are_its_generators_cone(side):
    # Caron et al.'s faces against the cone the 16 corner forces span (non-negative least squares: a wrench is in it
    # when nnls reproduces it), on random wrenches about the sole point.
    cone = SoleCone(SOLE, side, 0.6)
    assert (cone.faces @ cone.generators).max() <= 1e-12
    rng = np.random.default_rng(7)
    inside = 0
    for _ in range(3000):
        wrench = rng.normal(size=6) * (0.5, 0.5, 1.0, 0.06, 0.09, 0.05)
        wrench[2] = abs(wrench[2]) + 0.1
        spanned = nnls(cone.generators, wrench)[1] < 1e-9
        assert cone.contains(wrench) == spanned
        inside += spanned
    assert 500 < inside < 2500, "both sides of the cone are tried"


def _level_frames(yaw: float = 0.3, width: float = 0.2) -> list[np.ndarray]:
    """Two level sole frames turned by ``yaw``, ``width`` apart."""
    frames = []
    for side in (1.0, -1.0):
        frame = np.eye(4)
        frame[:3, :3] = pin.rpy.rpyToMatrix(0.0, 0.0, yaw)
        frame[:3, 3] = frame[:3, :3] @ (0.0, side * 0.5 * width, 0.0) + (0.3, 0.1, 0.0)
        frames.append(frame)
    return frames


def _sum(frames, wrenches):
    return sum(force_transform(frame) @ wrench for frame, wrench in zip(frames, wrenches, strict=True))


def test_the_qp_keeps_each_cop_within_its_sole():
    # The COM over the right foot and all the load asked of the left: the closed form moves the load, but leaves the
    # left CoP far off its sole; the QP gives wrenches in both cones that still sum to the required one.
    distributor = WrenchDistributor(SOLE)
    frames = _level_frames()
    weight = 800.0
    com = frames[1][:3, 3] + (0.02, 0.0, 0.0)
    force, moment = np.array([0.0, 0.0, weight]), np.cross(com, [0.0, 0.0, weight])
    result = distributor.distribute(force, moment, frames, (True, True), 1.0)
    assert result.method == "qp" and result.residual < 1e-3
    np.testing.assert_allclose(_sum(frames, result.wrenches), np.r_[force, moment], atol=1e-2)
    for cone, wrench, (low, high) in zip(
        distributor.cones, result.wrenches, ((-SOLE.inner, SOLE.outer), (-SOLE.outer, SOLE.inner)), strict=True
    ):
        assert (cone.faces @ wrench).max() <= 1e-6
        cx, cy = cone.cop(wrench)
        assert -SOLE.back - 1e-9 <= cx <= SOLE.front + 1e-9 and low - 1e-9 <= cy <= high + 1e-9
    assert distributor.qp_count == 1


def test_all_asked_of_one_foot_that_holds_it_is_given_to_that_foot():
    # The COM 1 cm outside the left sole point, all the load asked of the left foot: the closed form would pull the
    # right foot down; the left foot alone holds the wrench (its CoP 1 cm from its sole point), so it takes it all.
    distributor = WrenchDistributor(SOLE)
    frames = _level_frames()
    com = frames[0][:3, 3] + frames[0][:3, :3] @ np.array([0.0, 0.01, 0.0])
    force = np.array([0.0, 0.0, 800.0])
    moment = np.cross(com, force)
    result = distributor.distribute(force, moment, frames, (True, True), 1.0)
    assert result.method == "single" and distributor.qp_count == 0
    np.testing.assert_array_equal(result.wrenches[1], 0.0)
    np.testing.assert_allclose(distributor.cones[0].cop(result.wrenches[0]), (0.0, 0.01), atol=1e-12)
    np.testing.assert_allclose(_sum(frames, result.wrenches), np.r_[force, moment], atol=1e-9)


def test_the_qp_respects_friction():
    # A yaw moment the feet make by opposite horizontal forces, asked of a nearly unloaded foot: the closed form's
    # horizontal force on that foot is beyond its friction; the QP's are within it, and the sum is kept.
    distributor = WrenchDistributor(SOLE, friction=0.5)
    frames = _level_frames(yaw=0.0)
    middle = 0.5 * (frames[0][:3, 3] + frames[1][:3, 3])
    force = np.array([0.0, 0.0, 800.0])
    moment = np.cross(middle, force) + np.array([0.0, 0.0, 30.0])
    closed = distributor.distribute(force, moment, frames, (True, True), 0.97)
    assert closed.method == "qp" and closed.residual < 1e-3
    mu = 0.5 / math.sqrt(2.0)
    for wrench in closed.wrenches:
        assert max(abs(wrench[0]), abs(wrench[1])) <= mu * wrench[2] + 1e-6
    np.testing.assert_allclose(_sum(frames, closed.wrenches), np.r_[force, moment], atol=1e-2)


def test_bad_inputs_are_refused(talos, dynamics):
    with pytest.raises(ValueError, match="friction"):
        WrenchDistributor(SOLE, friction=0.0)
    with pytest.raises(ValueError, match="side"):
        SoleCone(SOLE, "middle", 0.5)
    with pytest.raises(ValueError, match="armature"):
        InverseDynamics(talos, SOLE, armature=np.ones(3))
    dynamics.update(talos.q_half_sitting, np.zeros(talos.model.nv), np.zeros(talos.model.nv))
    with pytest.raises(ValueError, match="left_ratio"):
        dynamics.distribute((True, True), 1.5)
    with pytest.raises(ValueError, match="at least one foot"):
        dynamics.distribute((False, False))


# ----- velocity and acceleration of the IK's configurations -------------------------------------------------------
def test_motion_rates_of_a_constant_acceleration(talos):
    # q(t) = q0 + v0 t + a t^2 / 2 on the joints and the base's position: the raw differences give a exactly (after
    # two ticks) and v at the half tick; the filtered ones reach a and lag v by the filter's time constant.
    dt, model = 0.002, talos.model
    v0, acc = np.linspace(-0.5, 0.5, model.nv), np.linspace(1.0, -2.0, model.nv)
    v0[3:6] = acc[3:6] = 0.0  # the base does not turn: its velocity in its own frame is then the world's

    def q_at(t):
        return pin.integrate(model, talos.q_half_sitting, v0 * t + 0.5 * acc * t * t)

    raw, smooth = MotionRates(model, dt, 0.0), MotionRates(model, dt, 0.01)
    v, a = raw.update(q_at(0.0))
    assert not v.any() and not a.any(), "the first configuration is at rest"
    smooth.update(q_at(0.0))
    for k in range(1, 400):
        t = k * dt
        v, a = raw.update(q_at(t))
        vs, as_ = smooth.update(q_at(t))
        if k >= 2:
            np.testing.assert_allclose(a, acc, atol=1e-6)
            np.testing.assert_allclose(v, v0 + acc * (t - 0.5 * dt), atol=1e-8)
    np.testing.assert_allclose(as_, acc, atol=1e-6)
    decay = math.exp(-dt / 0.01)
    lag = 0.5 * dt + dt * decay / (1.0 - decay)  # the half tick of the difference, the discrete low-pass's lag
    np.testing.assert_allclose(vs, v0 + acc * (t - lag), atol=2e-3 * np.abs(acc).max())
    with pytest.raises(ValueError, match="dt"):
        MotionRates(model, 0.0)
    with pytest.raises(ValueError, match="time constant"):
        MotionRates(model, dt, -1.0)
