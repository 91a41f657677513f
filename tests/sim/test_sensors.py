"""The simulated sensors (rtgait.sim.sensors, rtgait.sim.sensor_sites) against MuJoCo's state and the noise model.

Noise-free readings are checked against truth computed independently of the sensors (body poses and velocities,
the state before the step, the contact forces); the noise against its definition: white noise of density ``N``
sampled every ``dt`` has the standard deviation ``N / sqrt(dt)``, a bias walk of density ``N_b`` moves by
``N_b sqrt(dt)`` a tick.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from typing import Any

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from rtgait.interface.sensor_spec import FootSensorSpec, ImuSpec, SensorSpec  # noqa: E402
from rtgait.sim.config import SensorSettings  # noqa: E402
from rtgait.sim.contact_reading import ContactReader  # noqa: E402
from rtgait.sim.robot import SimRobot  # noqa: E402
from rtgait.sim.sensors import SensorModel  # noqa: E402
from rtgait.sim.step_snapshot import read_snapshot  # noqa: E402

GRAVITY = 9.81
STAND = 0.2  # s of standing recorded
EXACT = SensorSettings(noise=0.0)


def _site(sim: Any, name: str) -> int:
    return int(mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_SITE, name))


@pytest.fixture(scope="module")
def standing(talos_sim: Any) -> dict[str, Any]:
    """Talos standing for 0.2 s: each tick's sensordata, noise-free readings and the truth they should match."""
    sim = talos_sim
    model, data = sim.model, sim.new_data()
    robot = SimRobot(sim, data, data.ctrl.copy())  # the references the servos held while settling
    exact = SensorModel(sim, EXACT)
    imu, feet = _site(sim, "imu"), [_site(sim, f"{side}_foot_sensor") for side in ("left", "right")]
    contacts = ContactReader.for_sim(sim)
    keys = (
        "raw",
        "readings",
        "qpos",
        "qvel",
        "quat",
        "gyro",
        "tau",
        "contacts",
        "foot_rotations",
        "rotation",
        "linear",
        "foot_points",
    )
    record: dict[str, list[Any]] = {key: [] for key in keys}
    for _ in range(round(STAND / sim.control_dt)):
        qpos, qvel = data.qpos[sim.qpos_index].copy(), data.qvel[sim.dof_index].copy()
        robot.first_substep()  # one physics step a period for Talos: the arrays now describe the state it started from
        record["qpos"].append(qpos)
        record["qvel"].append(qvel)
        record["raw"].append(data.sensordata.copy())
        record["readings"].append(exact.read(data.sensordata, float(data.time)))
        body = model.site_bodyid[imu]
        quat = np.empty(4)
        mujoco.mju_mulQuat(quat, data.xquat[body], model.site_quat[imu])
        record["quat"].append(quat)
        velocity = np.empty(6)
        mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_SITE, imu, velocity, 1)  # rotation, then translation
        record["gyro"].append(velocity[:3].copy())
        record["rotation"].append(data.site_xmat[imu].reshape(3, 3).copy())
        mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_SITE, imu, velocity, 0)  # world axes, at the site
        record["linear"].append(velocity[3:].copy())
        record["tau"].append(data.actuator_force.copy())
        record["contacts"].append(contacts.read(data, read_snapshot(data)))
        record["foot_rotations"].append([data.site_xmat[site].reshape(3, 3).copy() for site in feet])
        # Each foot sensor's origin and the centre of mass of the foot below it (m, world).
        record["foot_points"].append([(data.site_xpos[site].copy(), data.xipos[model.site_bodyid[site]].copy())
                                      for site in feet])  # fmt: skip
    foot_mass = [float(model.body_subtreemass[model.site_bodyid[site]]) for site in feet]
    return {"sim": sim, "foot_mass": foot_mass, **record}


def _spec(sim: Any, **changes: Any) -> SensorSpec:
    """The description's sensors with no noise at all but ``changes`` (``imu_*``/``feet_*`` keys go to those)."""
    spec = sim.robot.description.sensors
    imu = ImuSpec(spec.imu.frame, **{k[4:]: v for k, v in changes.items() if k.startswith("imu_")})
    feet = None
    if spec.feet is not None:
        feet_changes = {k[5:]: v for k, v in changes.items() if k.startswith("feet_")}
        feet = FootSensorSpec(spec.feet.left, spec.feet.right, **feet_changes)
    rest = {k: v for k, v in changes.items() if not k.startswith(("imu_", "feet_"))}
    return SensorSpec(imu=imu, feet=feet, **rest)


def _stream(sim: Any, raw: np.ndarray, spec: SensorSpec | None = None, **settings: Any) -> list[Any]:
    """Readings of one run over the sensordata rows ``raw`` (ticks of the control period)."""
    model = SensorModel(sim, SensorSettings(**settings), spec)
    return [model.read(row, k * sim.control_dt) for k, row in enumerate(raw)]


def _imu(readings: list[Any], field: str) -> np.ndarray:
    return np.array([getattr(r.imu, field) for r in readings])


# ----- noise-free: the truth ------------------------------------------------------------------------------------


def test_noise_free_encoders_and_torques_are_the_state_the_step_started_from(standing: dict[str, Any]) -> None:
    for readings, qpos, qvel, tau in zip(
        standing["readings"], standing["qpos"], standing["qvel"], standing["tau"], strict=True
    ):
        np.testing.assert_array_equal(readings.joint_positions, qpos)
        np.testing.assert_array_equal(readings.joint_velocities, qvel)
        np.testing.assert_array_equal(readings.joint_torques, tau)


def test_noise_free_imu_orientation_and_gyro_are_the_imu_frames(standing: dict[str, Any]) -> None:
    quat, gyro = _imu(standing["readings"], "orientation"), _imu(standing["readings"], "angular_velocity")
    truth = np.array(standing["quat"])
    sign = np.sign(np.sum(quat * truth, axis=1))[:, None]  # q and -q are one rotation
    np.testing.assert_allclose(quat, sign * truth, atol=1e-12)
    np.testing.assert_allclose(gyro, np.array(standing["gyro"]), atol=1e-12)


def _specific_forces(linear: np.ndarray, rotations: np.ndarray, dt: float) -> np.ndarray:
    """``R_k^T ((v_k - v_k-1) / dt - g)``: the mean specific force over each period, in the IMU frame at its end."""
    a = (linear[1:] - linear[:-1]) / dt + np.array([0.0, 0.0, GRAVITY])
    return np.einsum("kji,kj->ki", rotations[1:], a)


def test_accelerometer_reads_the_mean_specific_force_over_the_period(standing: dict[str, Any]) -> None:
    """``R^T (a - g)``, ``a`` the change of the IMU site's velocity since the last reading over the period, ``R`` the
    site's orientation at the reading; the first reading, without a period before it, is MuJoCo's accelerometer."""
    sim = standing["sim"]
    accel = _imu(standing["readings"], "linear_acceleration")
    expected = _specific_forces(np.array(standing["linear"]), np.array(standing["rotation"]), sim.control_dt)
    np.testing.assert_allclose(accel[1:], expected, atol=1e-9)
    k = sim.sensors.start + 3 * sim.sensors.joints + 7
    np.testing.assert_array_equal(accel[0], standing["raw"][0][k : k + 3])
    # Standing still, that is gravity alone, upward. Talos's IMU is mounted upside down (the URDF's imu_joint: roll
    # pi), so that is along its -z.
    np.testing.assert_allclose(np.linalg.norm(accel, axis=1), GRAVITY, rtol=0.002)
    assert accel[:, 2].mean() < -0.99 * GRAVITY


def test_accelerometer_of_a_pushed_g1_is_its_velocity_change_over_the_period() -> None:
    """G1's control period spans four physics steps: the reading is the mean over them, which is what integrates to
    the IMU's velocity; MuJoCo's accelerometer, the acceleration of one instant before the step's implicit damping,
    is not."""
    from rtgait.sim.model import SimConfig, build_sim_model

    sim = build_sim_model("g1", SimConfig(meshes=False, sensors=EXACT))
    assert sim.substeps > 1
    model, data = sim.model, sim.new_data()
    robot = SimRobot(sim, data, data.ctrl.copy())
    imu = _site(sim, "imu")
    data.xfrc_applied[sim.base_body, :3] = (40.0, -60.0, 0.0)  # pushed: the pelvis sways
    accel, instant, linear, rotations = [], [], [], []
    k = sim.sensors.start + 3 * sim.sensors.joints + 7
    for _ in range(100):
        robot.first_substep()
        for j in range(1, sim.substeps):
            robot.substep(j)
        accel.append(robot.read().imu.linear_acceleration)
        instant.append(data.sensordata[k : k + 3].copy())
        velocity = np.empty(6)
        mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_SITE, imu, velocity, 0)  # world axes, at the site
        linear.append(velocity[3:].copy())
        rotations.append(data.site_xmat[imu].reshape(3, 3).copy())
    expected = _specific_forces(np.array(linear), np.array(rotations), sim.control_dt)
    np.testing.assert_allclose(np.array(accel)[1:], expected, atol=1e-9)
    assert np.ptp(expected, axis=0).max() > 1.0  # it moves
    assert np.sqrt(np.mean(np.square(np.array(instant)[1:] - expected))) > 0.01


def test_ankle_sensors_carry_the_weight_above_them(standing: dict[str, Any]) -> None:
    sim = standing["sim"]
    mass = float(sim.model.body_subtreemass[sim.base_body])
    readings = standing["readings"][-1]
    vertical = readings.left_foot.force[2] + readings.right_foot.force[2]
    assert vertical == pytest.approx((mass - sum(standing["foot_mass"])) * GRAVITY, rel=1e-3)
    # Each foot: the floor's push on the sole and the foot's own weight, passed on to the leg (the foot's accelerations
    # are negligible standing), in the sensor frame, the moment about the sensor's origin.
    sums, rotations = standing["contacts"][-1], standing["foot_rotations"][-1]
    floors = ((sums.left_force, sums.left_moment), (sums.right_force, sums.right_moment))  # moments about the origin
    for wrench, (force, moment), foot_mass, rotation, (origin, com) in zip(
        (readings.left_foot, readings.right_foot), floors, standing["foot_mass"], rotations,
        standing["foot_points"][-1], strict=True,
    ):  # fmt: skip
        weight = np.array([0.0, 0.0, -foot_mass * GRAVITY])
        total = np.asarray(force) + weight
        about_origin = np.asarray(moment) - np.cross(origin, force) + np.cross(com - origin, weight)
        np.testing.assert_allclose(wrench.force, rotation.T @ total, atol=0.5)
        np.testing.assert_allclose(wrench.torque, rotation.T @ about_origin, atol=0.05)


def test_g1_has_a_pelvis_imu_and_no_foot_sensor() -> None:
    from rtgait.sim.model import SimConfig, build_sim_model

    sim = build_sim_model("g1", SimConfig(meshes=False))
    assert sim.robot.description.sensors.feet is None
    data = sim.new_data(settle=0.0)
    readings = SimRobot(sim, data, data.qpos[sim.qpos_index].copy()).read()
    assert readings.left_foot is None and readings.right_foot is None
    assert readings.imu is not None and readings.joint_torques is not None  # tau_est
    assert sim.model.site_bodyid[_site(sim, "imu")] == sim.base_body  # the pelvis


# ----- noise ------------------------------------------------------------------------------------------------------


def test_white_noise_has_the_standard_deviation_of_its_density(talos_sim: Any, standing: dict[str, Any]) -> None:
    sim = talos_sim
    dt = sim.control_dt
    density = {"imu_gyro_noise_density": 1e-3, "imu_accel_noise_density": 2e-3}
    spec = _spec(sim, velocity_noise=0.01, torque_noise=0.5, feet_force_noise=2.0, feet_torque_noise=0.2, **density)
    raw = np.repeat(standing["raw"][-1][None, :], 20000, axis=0)  # one state, many samples: the spread is the noise
    readings = _stream(sim, raw, spec, seed=3)
    # sigma = N / sqrt(dt); 20000 samples estimate it within about 0.5 % (3 % allowed).
    expected = {"angular_velocity": 1e-3 / math.sqrt(dt), "linear_acceleration": 2e-3 / math.sqrt(dt)}
    for field, sigma in expected.items():
        np.testing.assert_allclose(_imu(readings, field).std(axis=0), sigma, rtol=0.03)
    velocities = np.array([r.joint_velocities for r in readings])
    np.testing.assert_allclose(velocities.std(axis=0), 0.01, rtol=0.03)
    np.testing.assert_allclose(np.array([r.joint_torques for r in readings]).std(axis=0), 0.5, rtol=0.03)
    np.testing.assert_allclose(np.array([r.left_foot.force for r in readings]).std(axis=0), 2.0, rtol=0.03)
    np.testing.assert_allclose(np.array([r.right_foot.torque for r in readings]).std(axis=0), 0.2, rtol=0.03)
    # Zero mean: the noise is centred on the truth (the exact reading of the same state).
    truth = standing["readings"][-1]
    np.testing.assert_allclose(velocities.mean(axis=0), truth.joint_velocities, atol=4 * 0.01 / math.sqrt(20000))


def test_biases_walk_by_their_density_and_start_spread(talos_sim: Any, standing: dict[str, Any]) -> None:
    sim = talos_sim
    dt = sim.control_dt
    raw = np.repeat(standing["raw"][-1][None, :], 5000, axis=0)
    walk = _imu(_stream(sim, raw, _spec(sim, imu_gyro_bias_walk=0.01), seed=5), "angular_velocity")
    np.testing.assert_allclose(np.diff(walk, axis=0).std(axis=0), 0.01 * math.sqrt(dt), rtol=0.05)
    # Initial biases and offsets: one draw per run, so their spread shows across seeds.
    spec = _spec(sim, imu_accel_bias=0.05, feet_force_offset=3.0)
    first = [_stream(sim, raw[:2], spec, seed=seed) for seed in range(400)]
    truth = standing["readings"][-1]
    accel = np.array([run[1].imu.linear_acceleration for run in first]) - truth.imu.linear_acceleration
    force = np.array([run[1].left_foot.force for run in first]) - truth.left_foot.force
    np.testing.assert_allclose(accel.std(axis=0), 0.05, rtol=0.15)
    np.testing.assert_allclose(force.std(axis=0), 3.0, rtol=0.15)
    # A constant offset: the same in the run's two readings.
    np.testing.assert_allclose([run[1].left_foot.force for run in first], [run[0].left_foot.force for run in first])


def _rotation_between(a: tuple[float, ...], b: tuple[float, ...]) -> np.ndarray:
    """The rotation vector of ``q_a q_b^-1`` (world frame)."""
    inverse, error, vector = np.empty(4), np.empty(4), np.empty(3)
    mujoco.mju_negQuat(inverse, np.asarray(b))
    mujoco.mju_mulQuat(error, np.asarray(a), inverse)
    mujoco.mju_quat2Vel(vector, error, 1.0)
    return vector


def test_the_imu_filter_tilts_by_white_roll_pitch_and_drifts_in_yaw(talos_sim: Any, standing: dict[str, Any]) -> None:
    sim = talos_sim
    raw = np.repeat(standing["raw"][-1][None, :], 4000, axis=0)
    truth = standing["readings"][-1].imu.orientation
    tilted = _stream(sim, raw, _spec(sim, imu_orientation_noise=0.01), seed=1)
    errors = np.array([_rotation_between(r.imu.orientation, truth) for r in tilted])
    np.testing.assert_allclose(errors[:, :2].std(axis=0), 0.01, rtol=0.05)  # about the world's x and y
    np.testing.assert_allclose(errors[:, 2], 0.0, atol=1e-12)
    drifting = _stream(sim, raw[:1001], _spec(sim, imu_yaw_drift=0.01), seed=1)
    yaw = np.array([_rotation_between(r.imu.orientation, truth) for r in drifting])
    np.testing.assert_allclose(yaw[:, :2], 0.0, atol=1e-12)
    rate = yaw[1000, 2] / (1000 * sim.control_dt)  # a drift at a constant rate, from zero at the first reading
    np.testing.assert_allclose(yaw[:, 2], rate * sim.control_dt * np.arange(1001), atol=1e-12)
    assert abs(rate) > 0.0


def test_encoders_report_whole_steps_of_their_resolution(talos_sim: Any, standing: dict[str, Any]) -> None:
    sim = talos_sim
    step = 2 * math.pi / 2**12
    readings = _stream(sim, np.array(standing["raw"]), _spec(sim, encoder_resolution=step), seed=0)
    for reading, qpos in zip(readings, standing["qpos"], strict=True):
        counts = reading.joint_positions / step
        np.testing.assert_allclose(counts, np.round(counts), atol=1e-6)
        assert np.max(np.abs(reading.joint_positions - qpos)) <= step / 2 + 1e-12


def test_a_seed_fixes_the_readings(talos_sim: Any, standing: dict[str, Any]) -> None:
    raw = np.array(standing["raw"][:50])
    runs = [_stream(talos_sim, raw, seed=seed) for seed in (7, 7, 8)]
    flat = [np.concatenate([np.concatenate([r.joint_positions, r.imu.angular_velocity, r.left_foot.force])
                            for r in run]) for run in runs]  # fmt: skip
    np.testing.assert_array_equal(flat[0], flat[1])
    assert not np.array_equal(flat[0], flat[2])


def test_latency_delivers_the_reading_of_n_ticks_before(talos_sim: Any, standing: dict[str, Any]) -> None:
    raw = np.array(standing["raw"][:40])
    now, late = _stream(talos_sim, raw, seed=2), _stream(talos_sim, raw, seed=2, latency=3)
    for k, reading in enumerate(late):
        sampled = now[max(k - 3, 0)]
        assert reading.t == sampled.t
        np.testing.assert_array_equal(reading.joint_positions, sampled.joint_positions)
        assert reading.imu == sampled.imu and reading.right_foot == sampled.right_foot


def test_the_run_settings_reach_the_simulated_robot(talos_sim: Any) -> None:
    from rtgait.sim.model import build_sim_model

    config = dataclasses.replace(talos_sim.config, sensors=SensorSettings(noise=0.0, latency=2, seed=4))
    sim = build_sim_model(talos_sim.robot, config)
    joints = talos_sim.qpos_half_sitting[talos_sim.qpos_index]
    robot = SimRobot(sim, sim.new_data(settle=0.0), joints)
    assert (robot.sensors.noise, robot.sensors.latency) == (0.0, 2)
    assert SimRobot(talos_sim, talos_sim.new_data(settle=0.0), joints).sensors.noise == 1.0


def test_sensor_settings_refuse_nonsense() -> None:
    for bad in ({"noise": -1.0}, {"noise": math.nan}, {"latency": -1}, {"latency": 1.5}, {"seed": -2}):
        with pytest.raises(ValueError, match="SensorSettings"):
            SensorSettings(**bad)


def test_g1_joint_torques_are_the_ones_its_drives_applied_over_the_step() -> None:
    """The drives' law ``g ctrl - kp q - kd dq`` at the sampled state's position and the step's end velocity: the
    torque the implicit integration applied, not MuJoCo's actuator force of the sampled state alone."""
    from rtgait.sim.model import SimConfig, build_sim_model

    sim = build_sim_model("g1", SimConfig(meshes=False, sensors=EXACT))
    model, data = sim.model, sim.new_data()
    robot = SimRobot(sim, data, data.ctrl.copy())
    data.xfrc_applied[sim.base_body, :3] = (40.0, -60.0, 0.0)  # pushed: the legs move
    errors, instants = [], []
    for _ in range(60):
        robot.first_substep()
        for j in range(1, sim.substeps - 1):
            robot.substep(j)
        q = data.qpos[sim.qpos_index].copy()
        robot.substep(sim.substeps - 1)
        law = model.actuator_gainprm[:, 0] * data.ctrl + model.actuator_biasprm[:, 1] * q
        law += model.actuator_biasprm[:, 2] * data.qvel[sim.dof_index]
        low, high = model.actuator_forcerange[:, 0], model.actuator_forcerange[:, 1]
        free = (law > low) & (law < high)
        tau = robot.read().joint_torques
        errors.append(np.abs(tau - law)[free].max())
        instants.append(np.abs(data.actuator_force - law)[free].max())
    assert max(errors) < 1e-9
    assert max(instants) > 0.05  # MuJoCo's force of the instant differs from it: the test can tell them apart


def test_ankle_sensors_read_the_wrench_that_moves_the_foot(talos_sim: Any) -> None:
    """Talos in the air, its legs swinging on the stiff servos: each foot sensor reads the Newton-Euler wrench
    of the foot below it, ``f = m (a - g)`` and ``t = I w' + w x I w + (c - p) x f`` about the sensor, with ``a`` and
    ``w'`` the foot's mean accelerations over the physics step (its velocities at consecutive ticks), not MuJoCo's
    wrench of the forward dynamics' acceleration (:mod:`rtgait.sim.implicit_wrench`)."""
    from rtgait.interface.command import JointCommand

    sim = talos_sim
    model, data = sim.model, sim.new_data()
    data.qpos[2] += 1.0  # no contact for the ticks below
    mujoco.mj_forward(model, data)
    start = data.ctrl.copy()
    robot = SimRobot(sim, data, start)
    robot.sensors = SensorModel(sim, SensorSettings(noise=0.0, latency=0))
    feet = [_site(sim, f"{side}_foot_sensor") for side in ("left", "right")]
    legs = np.array([name.startswith("leg_") for name in robot.joint_names])
    h, gravity, n = model.opt.timestep, model.opt.gravity, len(robot.joint_names)
    frames, errors, raw_errors = [], [], []
    for k in range(40):
        swing = np.where(legs, 0.05 * math.sin(2.0 * math.pi * 2.0 * k * sim.control_dt), 0.0)
        robot.write(JointCommand(start + swing, np.zeros(n)))
        robot.first_substep()
        reading = robot.read()
        frame = []
        for site, wrench in zip(feet, (reading.left_foot, reading.right_foot), strict=True):
            body = model.site_bodyid[site]
            velocity = np.empty(6)
            mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_BODY, body, velocity, 0)  # at the COM, world
            axes = data.ximat[body].reshape(3, 3)  # the body's principal axes of inertia
            inertia = axes @ np.diag(model.body_inertia[body]) @ axes.T
            at = sim.sensors.stop - 12 + 6 * feet.index(site)  # MuJoCo's force reading of this foot
            raw = -data.sensordata[at : at + 3]
            frame.append((velocity[:3].copy(), velocity[3:].copy(), inertia, data.xipos[body].copy(),
                          data.site_xpos[site].copy(), data.site_xmat[site].reshape(3, 3).copy(),
                          np.concatenate([wrench.force, wrench.torque]), raw.copy()))  # fmt: skip
        frames.append(frame)
        assert data.ncon == 0
    mass = model.body_mass[model.site_bodyid[feet[0]]]
    for before, after in itertools.pairwise(frames[1:]):
        for (w, v, inertia, com, origin, rotation, reading, raw), (w_end, v_end, *_) in zip(before, after, strict=True):
            force = mass * ((v_end - v) / h - gravity)
            torque = inertia @ ((w_end - w) / h) + np.cross(w, inertia @ w) + np.cross(com - origin, force)
            # The reading's sign: the wrench on the leg from the foot, the opposite of the parent's on the foot.
            expected = -np.concatenate([rotation.T @ force, rotation.T @ torque])
            errors.append(np.abs(reading - expected))
            raw_errors.append(np.abs(raw - expected[:3]))
    errors = np.array(errors)
    # The finite differences' acceleration is the step's mean, the correction's that of its start: O(h) apart.
    assert errors[:, :3].max() < 0.5 and errors[:, 3:].max() < 0.02
    assert np.array(raw_errors).max() > 20.0  # MuJoCo's own reading is off by more: the test tells them apart
