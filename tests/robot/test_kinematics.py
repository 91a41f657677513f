"""The estimator's Pinocchio kinematics against Pinocchio's own algorithms on the whole floating-base model: frames,
COM, their velocities, the sensors' mounts, and the legs' dynamics against the recursive Newton-Euler algorithm with
an external wrench on the sole."""

from __future__ import annotations

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

from rtgait.estimation.kinematics import RobotKinematics  # noqa: E402
from rtgait.estimation.sole_wrenches import torque_wrenches  # noqa: E402
from rtgait.interface.sensor_spec import SensorFrame  # noqa: E402
from rtgait.robot.description import RobotError  # noqa: E402
from rtgait.robot.drives import joint_drives  # noqa: E402
from rtgait.robot.kinematics import PinocchioKinematics  # noqa: E402

OFFSET = np.array([0.01, -0.02, 0.03])


def _whole(robot, joints, velocities):
    """Pinocchio's data of the full free-flyer model with the base at the origin, at rest."""
    model, data = robot.model, robot.model.createData()
    q = np.concatenate([[0, 0, 0, 0, 0, 0, 1], joints])
    v = np.concatenate([np.zeros(6), velocities])
    pin.forwardKinematics(model, data, q, v)
    pin.updateFramePlacements(model, data)
    com = pin.centerOfMass(model, data, q, v)
    return model, data, q, com


@pytest.mark.parametrize("name, imu", [("talos", "imu_link"), ("g1", "imu_in_pelvis"), ("g1", "imu_in_torso")])
def test_the_frames_are_pinocchios(request, name, imu):
    robot = request.getfixturevalue(name)
    kinematics = PinocchioKinematics(robot, SensorFrame(imu, tuple(OFFSET)))
    assert isinstance(kinematics, RobotKinematics)
    rng = np.random.default_rng(1)
    for _ in range(3):
        joints = robot.q_half_sitting[7:] + rng.normal(0.0, 0.1, robot.model.nv - 6)
        velocities = rng.normal(0.0, 1.0, robot.model.nv - 6)
        out = kinematics.update(joints, velocities)
        model, data, _, com = _whole(robot, joints, velocities)
        np.testing.assert_allclose(out.com, com, atol=1e-12)
        np.testing.assert_allclose(out.com_velocity, data.vcom[0], atol=1e-12)
        frames = ((robot.left_sole_id, out.left_sole, 0.0), (robot.right_sole_id, out.right_sole, 0.0),
                  (model.getFrameId(imu), out.imu, 1.0))  # fmt: skip
        for frame, motion, offset in frames:
            placement = data.oMf[frame]
            velocity = pin.getFrameVelocity(model, data, frame, pin.LOCAL_WORLD_ALIGNED)
            lever = placement.rotation @ OFFSET * offset
            np.testing.assert_allclose(motion.position, placement.translation + lever, atol=1e-12)
            np.testing.assert_allclose(np.reshape(motion.rotation, (3, 3)), placement.rotation, atol=1e-12)
            np.testing.assert_allclose(motion.velocity, velocity.linear + np.cross(velocity.angular, lever), atol=1e-12)
            np.testing.assert_allclose(motion.angular_velocity, velocity.angular, atol=1e-12)


def test_the_ankle_sensors_mount_and_the_foot_below_it(talos):
    feet = talos.description.sensors.feet
    kinematics = PinocchioKinematics(talos, None, (feet.left, feet.right))
    left, right = kinematics.foot_sensors
    # talos_reduced.urdf: the sole frame 0.107 m below the ankle roll axis, the same axes.
    np.testing.assert_allclose(left.position, (0.0, 0.0, 0.107), atol=1e-9)
    np.testing.assert_allclose(np.reshape(left.rotation, (3, 3)), np.eye(3), atol=1e-9)
    # The foot below the sensor: the ankle roll link's inertia, its centre in the sole frame.
    model = talos.model
    joint = model.frames[talos.left_sole_id].parentJoint
    assert left.mass == pytest.approx(model.inertias[joint].mass) == pytest.approx(right.mass)
    centre = model.frames[talos.left_sole_id].placement.actInv(model.inertias[joint].lever)
    np.testing.assert_allclose(left.com, centre, atol=1e-12)
    assert 0.0 < left.com[2] < 0.107  # above the sole, below the ankle


def test_a_sensor_off_the_foot_is_refused(talos):
    with pytest.raises(RobotError, match="not on the body"):
        PinocchioKinematics(talos, None, (SensorFrame("leg_left_4_link"), SensorFrame("leg_right_4_link")))
    with pytest.raises(RobotError, match="no frame"):
        PinocchioKinematics(talos, SensorFrame("no_such_link"))


@pytest.mark.parametrize("name", ["talos", "g1"])
def test_the_legs_dynamics_turn_joint_torques_into_the_sole_wrench(request, name):
    # The torques of a robot moving under given sole wrenches, by the recursive Newton-Euler algorithm with external
    # forces on the whole floating-base model (a tilted base moving, turning and accelerating, every joint moving and
    # accelerating, gravity along the world's z, the drives' rotors): the legs' dynamics give the wrenches back.
    robot = request.getfixturevalue(name)
    kinematics = PinocchioKinematics(robot)
    rng = np.random.default_rng(4)
    n = robot.model.nv - 6
    joints = robot.q_half_sitting[7:] + rng.normal(0.0, 0.05, n)
    velocities, accelerations = rng.normal(0.0, 1.0, n), rng.normal(0.0, 20.0, n)
    kinematics.update(joints, velocities)
    model = pin.Model(robot.model)
    armature = joint_drives(robot)[1]
    assert np.all(armature > 0.0)
    model.armature[6:] = armature
    data = model.createData()
    tilt = pin.rpy.rpyToMatrix(0.05, -0.1, 0.3)
    q = np.concatenate([[0.1, -0.2, 0.8], pin.Quaternion(tilt).coeffs(), joints])
    # The base's velocity and spatial acceleration in its own frame (Pinocchio's free flyer): linear, angular.
    base_velocity, base_acceleration = np.array([0.3, -0.1, 0.05, 0.2, -0.4, 0.6]), rng.normal(0.0, 2.0, 6)
    v, a = np.concatenate([base_velocity, velocities]), np.concatenate([base_acceleration, accelerations])
    wrenches = np.array([[10.0, -5.0, 400.0, 3.0, -8.0, 0.5], [-4.0, 6.0, 250.0, -2.0, 5.0, -0.3]])
    forces = pin.StdVec_Force()
    for _ in range(model.njoints):
        forces.append(pin.Force.Zero())
    pin.framesForwardKinematics(model, data, q)
    for sole, wrench in zip((robot.left_sole_id, robot.right_sole_id), wrenches, strict=True):
        frame = model.frames[sole]
        # The wrench in the sole frame, expressed in its joint's frame (Pinocchio's external forces are local).
        forces[frame.parentJoint] += frame.placement.act(pin.Force(wrench[:3], wrench[3:]))
    torques = pin.rnea(model, data, q, v, a, forces)[6:]
    # What an IMU on the base would give: the angular velocity and acceleration, and the specific force of the base
    # origin, its classical acceleration less the gravity, in the base frame.
    angular, linear = base_velocity[3:], base_velocity[:3]
    specific = base_acceleration[:3] + np.cross(angular, linear) - tilt.T @ np.array([0.0, 0.0, -9.81])
    jacobians, needed = kinematics.leg_dynamics(tuple(angular), (*specific, *base_acceleration[3:]), accelerations)
    legs = np.array(kinematics.leg_joints)
    np.testing.assert_allclose(torque_wrenches(jacobians, needed, torques[legs]), wrenches, atol=1e-6)
    # At rest the legs' dynamics are their statics: the torques that hold each leg against gravity.
    kinematics.update(joints, np.zeros(n))
    upright = (0.0, 0.0, 9.81, 0.0, 0.0, 0.0)  # standing still, the specific force is g upward
    _, holding = kinematics.leg_dynamics((0.0, 0.0, 0.0), upright, np.zeros(n))
    gravity = pin.computeGeneralizedGravity(model, data, np.concatenate([[0, 0, 0, 0, 0, 0, 1], joints]))[6:]
    np.testing.assert_allclose(holding, gravity[legs], atol=1e-9)
