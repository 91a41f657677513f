"""The simulated drives against the laws they model, computed here independently: the PD law with feed-forward torques
and per-joint gains at every physics step (the encoders' offsets included), the motors' torque-speed envelopes, the
gears' Coulomb and viscous friction, the command's delay on the bus, and the robot's own gains."""

from __future__ import annotations

import math

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")

from rtgait.interface.command import JointCommand  # noqa: E402
from rtgait.robot.description import load_robot  # noqa: E402
from rtgait.sim.model import SimConfig, build_sim_model  # noqa: E402
from rtgait.sim.robot import SimRobot  # noqa: E402


@pytest.fixture(scope="module")
def talos_motors(talos):
    """Talos with its motors and a model error (encoder offsets, the joints' friction)."""
    return build_sim_model(talos, SimConfig(meshes=False, motor_model=True, model_error=3))


@pytest.fixture(scope="module")
def g1_motors():
    """G1 (four physics steps a control period) with its motors."""
    return build_sim_model("g1", SimConfig(meshes=False, motor_model=True))


def joints(sim, data):
    """The joints' true positions and velocities (rad, rad/s)."""
    return data.qpos[sim.qpos_index].copy(), data.qvel[sim.dof_index].copy()


def pd(sim, q_ref, dq_ref, tau, kp, kd, q, dq):
    """The drive's law at the state ``(q, dq)``: the encoders read ``q + offsets``."""
    offsets = np.zeros(len(q)) if sim.encoder_offsets is None else sim.encoder_offsets
    return tau + kp * (q_ref - (q + offsets)) + kd * (dq_ref - dq)


def random_command(sim, q, rng, servo=True):
    """A command near ``q`` with references, torques and gains of every joint its own; with ``servo`` false some
    joints damp (kp 0) and some take the torque alone (kp = kd = 0)."""
    n = len(q)
    kp = rng.uniform(0.2, 1.0, n) * sim.kp
    kd = rng.uniform(0.2, 1.0, n) * sim.kd
    if not servo:
        kp[::3] = 0.0
        kp[1::3], kd[1::3] = 0.0, 0.0
    return JointCommand(q + rng.uniform(-0.02, 0.02, n), rng.uniform(-0.5, 0.5, n), rng.uniform(-20.0, 20.0, n), kp, kd)


@pytest.mark.parametrize("servo", [True, False], ids=["servos", "damping-and-torque"])
def test_the_pd_law_with_torques_and_gains_at_one_physics_step(talos_sim, servo):
    """Talos (one physics step a control period, no delay): the step's actuator force is the law at the state it
    started from, clipped to the torque limit."""
    data = talos_sim.new_data()
    q0 = data.qpos[talos_sim.qpos_index].copy()
    body = SimRobot(talos_sim, data, q0)
    rng = np.random.default_rng(1)
    data.qvel[talos_sim.dof_index] = rng.uniform(-1.0, 1.0, len(q0))
    command = random_command(talos_sim, q0, rng, servo)
    q, dq = joints(talos_sim, data)
    body.write(command)
    body.first_substep()
    limit = talos_sim.actuation.effort_limit
    expected = np.clip(pd(talos_sim, *command, q, dq), -limit, limit)
    np.testing.assert_allclose(data.actuator_force, expected, rtol=1e-10, atol=1e-8)
    assert body.damping is False
    # The readings' joint torques (the drive's over the step, its damping implicit) are tests/sim/test_sensors.py's.


def test_the_pd_law_at_every_substep_on_interpolated_references(g1_motors):
    """G1 (four physics steps a control period): each step applies the law to references and torques on the line
    from the last command's to the new one's, at that step's state; the gains are the command's."""
    sim = g1_motors
    data = sim.new_data()
    q0 = data.qpos[sim.qpos_index].copy()
    body = SimRobot(sim, data, q0)
    rng = np.random.default_rng(2)
    first = random_command(sim, q0, rng)
    kp, kd = first.kp, first.kd
    second = JointCommand(first.positions + 0.01, -first.velocities, first.torques + 5.0, kp.copy(), kd.copy())
    body.write(first)
    body.first_substep()
    for i in range(1, body.substeps):
        body.substep(i)
    body.write(second)
    n = body.substeps
    for i in range(n):
        q, dq = joints(sim, data)
        if i == 0:
            body.first_substep()
        else:
            body.substep(i)
        s = (i + 1) / n
        references = [a + s * (b - a) for a, b in zip(first[:3], second[:3], strict=True)]
        law = pd(sim, *references, kp, kd, q, dq)
        low, high = sim.model.actuator_forcerange.T  # the envelope at this step's velocities, checked below
        np.testing.assert_allclose(data.actuator_force, np.clip(law, low, high), rtol=1e-9, atol=1e-7)


def test_gains_left_out_are_the_drives_own(talos_sim):
    """A command without gains nor torques moves the robot exactly as one that gives the drives' own gains and zero
    torques."""
    runs = []
    for explicit in (False, True):
        data = talos_sim.new_data()
        q0 = data.qpos[talos_sim.qpos_index].copy()
        body = SimRobot(talos_sim, data, q0)
        n = len(q0)
        for k in range(20):
            q_ref = q0 + 0.05 * math.sin(0.3 * k) * np.ones(n)
            dq_ref = np.full(n, 0.015 * math.cos(0.3 * k))
            if explicit:
                body.write(JointCommand(q_ref, dq_ref, np.zeros(n), talos_sim.kp.copy(), talos_sim.kd.copy()))
            else:
                body.write(JointCommand(q_ref, dq_ref))
            body.first_substep()
        runs.append(data.qpos.copy())
    np.testing.assert_array_equal(runs[0], runs[1])


def test_a_command_with_a_value_not_finite_or_a_negative_gain_is_refused_and_changes_nothing(talos_sim):
    """Each array of a command is checked value by value: a NaN or an infinity anywhere is refused, values whose sum
    overflows are finite and taken, and a gain below zero is refused."""
    data = talos_sim.new_data()
    q0 = data.qpos[talos_sim.qpos_index].copy()
    body = SimRobot(talos_sim, data, q0)
    n = len(q0)
    kp, kd = talos_sim.kp.copy(), talos_sim.kd.copy()
    big = np.full(n, 1e308)  # finite, its sum is not
    body.write(JointCommand(q0, np.zeros(n), big, kp, kd))
    np.testing.assert_array_equal(body.drives.tau, big)
    cases = (("positions", math.nan, "rad"), ("velocities", -math.inf, "rad/s"), ("torques", math.inf, "N m"),
             ("kp", -1.0, "N m/rad"), ("kd", math.nan, "N m s/rad"))  # fmt: skip
    for field, bad, unit in cases:
        arrays = {"positions": q0.copy(), "velocities": np.zeros(n), "torques": np.zeros(n), "kp": kp, "kd": kd}
        arrays[field] = arrays[field].copy()
        arrays[field][n // 2] = bad
        with pytest.raises(ValueError, match=rf"JointCommand\.{field} must be {n} .*\({unit}\)"):
            body.write(JointCommand(**arrays))
        np.testing.assert_array_equal(body.drives.tau, big)  # the last command stays


@pytest.mark.parametrize("robot", ["talos", "g1"])
def test_the_torque_speed_envelope(robot, talos_motors, g1_motors):
    """Joints spun near their no-load speed get at most their motor's driving torque along the motion, and their
    braking torque against it; at standstill the peak torque, within the URDF's limit."""
    sim = talos_motors if robot == "talos" else g1_motors
    description = load_robot(robot)
    types = [description.joint_actuation(name).motor for name in sim.joint_names]
    limit = sim.actuation.effort_limit
    n = len(types)
    rng = np.random.default_rng(5)
    for fraction in (0.0, 0.5, 0.9, 1.2):
        data = sim.new_data()
        body = SimRobot(sim, data, data.qpos[sim.qpos_index].copy())
        signs = rng.choice([-1.0, 1.0], n)
        no_load = np.array([m.no_load_speed for m in types])
        velocity = signs * fraction * no_load
        data.qvel[sim.dof_index] = velocity
        pushed = rng.choice([-1.0, 1.0], n) * 1e4  # a torque beyond any envelope, along or against the motion
        body.write(JointCommand(data.qpos[sim.qpos_index].copy(), velocity, pushed, np.zeros(n), np.zeros(n)))
        body.first_substep()
        expected = []
        for m, v, tau, cap in zip(types, velocity, pushed, limit, strict=True):
            speed = abs(v)
            drive = m.peak_torque * min(1.0, max(0.0, (m.no_load_speed - speed) / (m.no_load_speed - m.corner_speed)))
            braking = m.braking_torque if m.braking_torque is not None else m.peak_torque
            along = v == 0.0 or (v > 0.0) == (tau > 0.0)
            expected.append(math.copysign(min(cap, drive if along else braking), tau))
        np.testing.assert_allclose(data.actuator_force, expected, rtol=1e-12, atol=1e-9)
        if fraction == 0.9:  # the envelope matters: some joints get a fraction of their limit along the motion
            assert np.any(np.abs(expected) < 0.5 * limit)


def test_friction_decelerates_a_free_joint_as_coulomb_and_viscous_predict(talos_motors):
    """Talos in free fall (no contact, no gravity torque on its joints): the left ankle roll turning at 1 rad/s with
    its drive limp and the other joints held, slows as ``I dv/dt = -F_c sign(v) - b v`` on the inertia it turns
    (armature + foot, the rest of the robot held rigid), and stops when that predicts."""
    sim = talos_motors
    data = sim.new_data(settle=0.0)
    data.qpos[2] += 1.0  # a metre above the floor: 0.2 s of free fall without contact
    mujoco.mj_forward(sim.model, data)
    j = list(sim.joint_names).index("leg_left_6_joint")
    dof = sim.dof_index[j]
    q0 = data.qpos[sim.qpos_index] + sim.encoder_offsets  # the encoders' readings: the drives hold the joints there
    body = SimRobot(sim, data, q0)
    n = len(q0)
    kp, kd = sim.kp.copy(), sim.kd.copy()
    kp[j] = kd[j] = 0.0
    mass = np.zeros((sim.model.nv, sim.model.nv))
    mujoco.mj_fullM(sim.model, data, mass)
    rigid = [*range(6), dof]  # the base and the joint: the other joints held
    inertia = 1.0 / np.linalg.inv(mass[np.ix_(rigid, rigid)])[-1, -1]
    # The motor type's friction times the model error's factor for the joint (the simulated robot's, not identified).
    factor = sim.model_error.friction_factors[j]
    assert sim.model_error.friction_applied and factor != 1.0
    coulomb, viscous = factor * sim.motors.coulomb_friction[j], factor * sim.motors.viscous_friction[j]
    assert coulomb > 0.0 and viscous > 0.0
    v0 = 1.0
    stop = inertia / viscous * math.log(1.0 + viscous * v0 / coulomb)
    # With a command delay the first periods apply the hold command: the same gains, which hold the joint; write the
    # limp command until it applies and measure from then on.
    command = JointCommand(q0, np.zeros(n), np.zeros(n), kp, kd)
    for _ in range(sim.command_delay):
        body.write(command)
    data.qvel[dof] = v0
    dt = sim.control_dt
    for k in range(1, round(0.2 / dt) + 1):
        body.write(JointCommand(q0.copy(), np.zeros(n), np.zeros(n), kp.copy(), kd.copy()))
        body.first_substep()
        t = k * dt
        v = data.qvel[dof]
        assert data.ncon == 0
        if t < 0.8 * stop:
            predicted = (v0 + coulomb / viscous) * math.exp(-viscous * t / inertia) - coulomb / viscous
            assert v == pytest.approx(predicted, abs=0.01 * v0)
        elif t > 2.0 * stop:
            assert abs(v) < 1e-3 * v0  # stopped, held by the Coulomb friction
    assert 0.05 < stop < 0.1  # the test's window sees the joint slow and stop


def test_the_command_shows_in_the_torque_one_period_later(talos):
    """Talos's bus delivers a command one control period after it is written (its description's command_delay):
    each period's torque is the law of the command written the period before, the first period's the hold."""
    sim = build_sim_model(talos, SimConfig(meshes=False, motor_model=True, model_error=3, command_delay=None))
    assert sim.command_delay == load_robot("talos").actuation.command_delay == 1
    data = sim.new_data()
    q0 = data.qpos[sim.qpos_index].copy()
    body = SimRobot(sim, data, q0)
    n = len(q0)
    rng = np.random.default_rng(7)
    hold = JointCommand(q0, np.zeros(n), np.zeros(n), sim.kp, sim.kd)
    written = [hold]
    for _ in range(5):
        command = JointCommand(q0 + rng.uniform(-0.01, 0.01, n), np.zeros(n), rng.uniform(-30.0, 30.0, n))
        q, dq = joints(sim, data)
        body.write(command)
        body.first_substep()
        applied = written[-1]
        expected = pd(sim, applied.positions, applied.velocities, applied.torques, sim.kp, sim.kd, q, dq)
        low, high = sim.model.actuator_forcerange.T
        np.testing.assert_allclose(data.actuator_force, np.clip(expected, low, high), rtol=1e-9, atol=1e-7)
        written.append(command._replace(kp=sim.kp, kd=sim.kd))
        np.testing.assert_array_equal(body.drives.q, applied.positions)  # the drives' reference is the last one


def test_the_robot_gains_are_the_published_ones(talos):
    """gains "robot": G1's are Unitree's low-level example's (unitree_sdk2 g1_ankle_swing_example.cpp), Talos's
    PAL's simulated drives' (talos_simulation's pids.yaml); the default stays the stiff derived gains."""
    g1 = build_sim_model("g1", SimConfig(meshes=False, gains="robot"))
    assert g1.actuation.gains == "robot"
    leg_kp, leg_kd = [60, 60, 60, 100, 40, 40], [1, 1, 1, 2, 1, 1]
    np.testing.assert_array_equal(g1.kp, [*leg_kp, *leg_kp, 60, 40, 40])
    np.testing.assert_array_equal(g1.kd, [*leg_kd, *leg_kd, 1, 1, 1])
    np.testing.assert_array_equal(g1.model.actuator_gainprm[:, 0], g1.kp)
    robot = build_sim_model(talos, SimConfig(meshes=False, gains="robot"))
    np.testing.assert_array_equal(robot.kp, [*[5000] * 12, 10000, 10000])
    np.testing.assert_array_equal(robot.kd, [*[20] * 12, 10, 10])
    stiff = build_sim_model(talos, SimConfig(meshes=False))
    assert stiff.actuation.gains == "stiff" and np.all(stiff.kp > 8000.0)


def test_the_motor_model_needs_a_motor_for_every_joint_and_robot_gains_need_gains(talos, tmp_path):
    from importlib import resources

    from rtgait.robot.model import RobotModel

    text = resources.files("rtgait").joinpath("robots", "talos.toml").read_text(encoding="utf-8")
    bare = text[: text.index("[actuation]")] + "[actuation]\ncontrol_dt = 0.001\n"
    path = tmp_path / "bare.toml"
    path.write_text(bare, encoding="utf-8")
    robot = RobotModel.load(load_robot(path))
    with pytest.raises(ValueError, match="needs a motor type for every moving joint"):
        build_sim_model(robot, SimConfig(meshes=False, motor_model=True))
    with pytest.raises(ValueError, match="gives no robot_kp and robot_kd for joint"):
        build_sim_model(robot, SimConfig(meshes=False, gains="robot"))
    with pytest.raises(ValueError, match=r"SimConfig\.gains must be one of"):
        SimConfig(gains="soft")
    with pytest.raises(ValueError, match=r"SimConfig\.command_delay must be"):
        SimConfig(command_delay=-1)


def test_the_default_drives_compute_the_position_servos_controls_bit_for_bit(shorten, monkeypatch):
    """The default settings (stiff gains, no motor model, no delay) keep the runs' outputs: the model's actuators are
    the position servos as built (gain kp, bias -kp q - kd dq, the torque limits, the URDF's joint friction), and
    every physics step's control is the servos' arithmetic, replayed here bit for bit: ``c = q_ref + (kd / kp) dq_ref
    - o`` per command, ``c_prev + (i + 1) ((c - c_prev) / n)`` at substep ``i < n - 1``, ``c`` at the last. G1: four
    substeps; a model error: encoder offsets."""
    from rtgait.io.sim_run import simulate
    from rtgait.robot.model import RobotModel
    from rtgait.sim.loop import LoopOptions
    from rtgait.sim.model import SETTLE_TIME

    robot = RobotModel.load("g1")
    sim = build_sim_model(robot, SimConfig(meshes=False, model_error=5))
    model, actuation = sim.model, sim.actuation
    assert sim.motors is None and sim.command_delay == 0 and actuation.gains == "stiff"
    np.testing.assert_array_equal(model.actuator_gainprm[:, 0], actuation.kp)
    np.testing.assert_array_equal(model.actuator_biasprm[:, 1:3], np.column_stack([-actuation.kp, -actuation.kd]))
    np.testing.assert_array_equal(model.actuator_forcerange[:, 1], actuation.effort_limit)
    assert not model.dof_frictionloss[sim.dof_index].any() and not model.dof_damping[sim.dof_index].any()
    written, controls = [], []
    write, step = SimRobot.write, mujoco.mj_step

    def recording_write(robot_, command):
        written.append((command.positions.copy(), command.velocities.copy()))
        write(robot_, command)

    def recording_step(model_, data):
        controls.append(data.ctrl.copy())
        step(model_, data)

    monkeypatch.setattr(SimRobot, "write", recording_write)
    monkeypatch.setattr(mujoco, "mj_step", recording_step)
    result = simulate(
        shorten("fig8", 1), robot, sim=sim, options=LoopOptions(start_ramp=0.3, start_hold=0.0, after=0.0)
    )
    monkeypatch.undo()
    n = sim.substeps
    periods = np.array(controls[round(SETTLE_TIME / sim.timestep) :]).reshape(len(written), n, -1)
    assert len(written) == len(result.times) and n == 4
    lead, offsets = actuation.kd / actuation.kp, sim.encoder_offsets
    previous = None
    for (q_ref, dq_ref), period in zip(written, periods, strict=True):
        control = q_ref + lead * dq_ref
        control -= offsets
        if previous is not None:
            increment = (control - previous) * (1.0 / n)
            for i in range(n - 1):
                np.testing.assert_array_equal(period[i], previous + (i + 1) * increment)
        np.testing.assert_array_equal(period[-1], control)
        previous = control


@pytest.mark.parametrize(("kp", "kd"), [(5000.0, 20.0), (10000.0, 0.0)])
def test_a_swinging_ankle_rings_down_as_its_gains_predict(talos, kp, kd):
    """Talos in free fall (no contact, no gravity torque on its joints), the left ankle roll 20 mrad off its reference
    and the other joints held by their drives: the joint rings as the damped oscillator ``I x'' + kd x' + kp x = 0`` on
    the inertia it turns (armature + foot, the rest held rigid), its extremes on the envelope ``x0 exp(-kd t / 2 I)``
    at multiples of ``pi / w_d``. At PAL's gains (kp 5000, kd 20, the description's robot gains) it is under 1 % of
    its offset within 0.2 s; at Menagerie's undamped kp 10000 it keeps its amplitude: the ringing that tipped the swing
    foot at Talos's former robot gains (docs/robots.md, "The robots' gains")."""
    sim = build_sim_model(talos, SimConfig(meshes=False, gains="robot"))
    data = sim.new_data(settle=0.0)
    data.qpos[2] += 1.0  # a metre above the floor: 0.2 s of free fall without contact
    mujoco.mj_forward(sim.model, data)
    j = list(sim.joint_names).index("leg_left_6_joint")
    dof = sim.dof_index[j]
    q0 = data.qpos[sim.qpos_index].copy()
    body = SimRobot(sim, data, q0)
    n = len(q0)
    gains_p, gains_d = sim.kp.copy(), sim.kd.copy()
    assert (gains_p[j], gains_d[j]) == (5000.0, 20.0)  # the description's
    gains_p[j], gains_d[j] = kp, kd
    mass = np.zeros((sim.model.nv, sim.model.nv))
    mujoco.mj_fullM(sim.model, data, mass)
    rigid = [*range(6), dof]
    inertia = 1.0 / np.linalg.inv(mass[np.ix_(rigid, rigid)])[-1, -1]
    x0 = 0.02
    data.qpos[sim.qpos_index[j]] += x0
    mujoco.mj_forward(sim.model, data)
    dt = sim.control_dt
    errors = []
    for _ in range(round(0.2 / dt)):
        body.write(JointCommand(q0.copy(), np.zeros(n), np.zeros(n), gains_p.copy(), gains_d.copy()))
        body.first_substep()
        assert data.ncon == 0
        errors.append(data.qpos[sim.qpos_index[j]] - q0[j])
    # The oscillator's extremes (its velocity zero, at multiples of pi / w_d) lie on its envelope x0 exp(-rate t).
    rate = kd / (2.0 * inertia)  # 1/s
    e = np.array(errors)
    turns = [k for k in range(1, len(e) - 1) if abs(e[k]) >= abs(e[k - 1]) and abs(e[k]) > abs(e[k + 1])]
    for k in turns[:2]:
        assert abs(e[k]) == pytest.approx(x0 * math.exp(-rate * (k + 1) * dt), rel=0.2)
    if kd > 0.0:
        damped = math.sqrt(kp / inertia - rate**2)  # rad/s
        assert (turns[0] + 1) * dt == pytest.approx(math.pi / damped, abs=1.5 * dt)
        assert np.abs(e[-40:]).max() < 0.01 * x0  # rung down within 0.2 s
    else:
        # Undamped, the 10000 N m/rad ankle rings at 38 Hz, below the 48 Hz of the leg held rigid (the hip and knee
        # at their 5000 give), and still has its amplitude after 0.2 s: nothing damps it.
        assert np.abs(e[-40:]).max() > 0.9 * x0
