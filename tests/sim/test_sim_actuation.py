"""Joint actuation in physics: per-joint PD servos from the robot description, torque limits, armature, the
control period and the references interpolated over the physics substeps."""

from __future__ import annotations

import dataclasses
import math
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")

from rtgait.io.sim_run import simulate  # noqa: E402
from rtgait.robot.description import DEFAULT_NATURAL_FREQUENCY, ActuationSpec, RobotError, load_robot  # noqa: E402
from rtgait.robot.model import RobotModel  # noqa: E402
from rtgait.sim.actuation import resolve_actuation, substeps  # noqa: E402
from rtgait.sim.loop import LoopOptions  # noqa: E402
from rtgait.sim.model import SETTLE_TIME, SimConfig, build_sim_model  # noqa: E402

TALOS_TEXT = resources.files("rtgait").joinpath("robots", "talos.toml").read_text(encoding="utf-8")
BASE_TEXT = TALOS_TEXT[: TALOS_TEXT.index("[actuation]")]  # Talos without its own [actuation] table

ACTUATION = """
[actuation]
control_dt = 0.002
natural_frequency = 3.0
damping_ratio = 0.5

[[actuation.joints]]
match = ["leg_*_joint", "torso_*"]
rotor_inertia = 2e-5
gear_ratio = 50.0

[[actuation.joints]]
match = "leg_*_4_joint"
kp = 5000.0
kd = 40.0

[[actuation.joints]]
match = ["leg_left_5_joint", "leg_right_5_joint"]
armature = 0.2
effort_limit = 90.0
natural_frequency = 6.0
"""


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "robot.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_actuation_from_the_description(tmp_path: Path) -> None:
    robot = RobotModel.load(load_robot(write(tmp_path, BASE_TEXT + ACTUATION)))
    sim = build_sim_model(robot, SimConfig(meshes=False))
    actuation = sim.actuation
    names = list(sim.joint_names)
    assert sim.control_dt == 0.002 and sim.timestep == 0.001 and sim.substeps == 2
    knee, ankle, hip = (names.index(f"leg_{j}_joint") for j in ("left_4", "right_5", "left_3"))
    # Given values win, key by key, later groups over earlier ones.
    assert actuation.kp[knee] == 5000.0 and actuation.kd[knee] == 40.0
    assert actuation.armature[knee] == pytest.approx(2e-5 * 50.0**2)  # rotor_inertia * gear_ratio^2
    assert actuation.armature[ankle] == 0.2 and actuation.effort_limit[ankle] == 90.0
    # Derived gains: the group's or the table's natural frequency on the armature plus the carried inertia;
    # the damping ratio on the drive and the limb beyond the joint.
    for joint, frequency in ((ankle, 6.0), (hip, 3.0)):
        omega = 2.0 * math.pi * frequency
        inertia = actuation.armature[joint] + actuation.carried_inertia[joint]
        assert actuation.kp[joint] == pytest.approx(omega * omega * inertia)
        assert actuation.natural_frequency[joint] == pytest.approx(frequency)
    # What MuJoCo got: the gains, the torque limits (the URDF's where not given: 160 N m at the hip) and armature.
    model = sim.model
    np.testing.assert_allclose(model.actuator_gainprm[:, 0], actuation.kp)
    np.testing.assert_allclose(model.actuator_biasprm[:, 2], -actuation.kd)
    assert model.actuator_forcerange[ankle, 1] == 90.0 and model.actuator_forcerange[hip, 1] == 160.0
    np.testing.assert_allclose(model.dof_armature[sim.dof_index], actuation.armature)
    # [gains] still works, below [actuation]'s groups: it sets the knees' kp nowhere, the others' everywhere.
    with_gains = BASE_TEXT.replace("[posture]", "[gains]\nkp = 800.0\nkd = 8.0\n\n[posture]") + ACTUATION
    gains = build_sim_model(RobotModel.load(load_robot(write(tmp_path, with_gains))), SimConfig(meshes=False))
    assert gains.kp[knee] == 5000.0 and gains.kp[hip] == 800.0 and gains.kd[hip] == 8.0


@pytest.mark.parametrize(
    ("table", "words"),
    [
        ('[actuation]\ncontrol_dt = 0\n', "actuation.control_dt must be a number > 0 s"),
        ('[actuation]\nrate = 2\n', "unknown key actuation.rate"),
        ('[actuation]\ncontrol_dt = 0.002\nphysics_dt = 0.0015\n', "physics_dt = 0.0015 s must divide"),
        ('[[actuation.joints]]\nmatch = "knee_*"\nkp = 1.0\n', "'knee_*' matches no movable joint"),
        ('[[actuation.joints]]\nmatch = "leg_*"\nrotor_inertia = 1e-5\n', "rotor_inertia and gear_ratio go together"),
        ('[[actuation.joints]]\nmatch = "leg_*"\narmature = 0.1\nrotor_inertia = 1e-5\ngear_ratio = 9.0\n',
         "give armature or rotor_inertia and gear_ratio, not both"),
        ('[[actuation.joints]]\nmatch = "leg_*"\neffort_limit = -5\n', "effort_limit must be a number > 0 N m"),
        ('[[actuation.joints]]\nkp = 1.0\n', "missing required key actuation.joints[0].match"),
        ('[actuation]\ncommand_delay = 0.5\n', "actuation.command_delay must be a whole number of control periods"),
        ('[actuation.motors.m]\npeak_torque = 10\n', "missing required key actuation.motors.m.no_load_speed"),
        ('[actuation.motors.m]\npeak_torque = 10\nno_load_speed = 5\ncorner_speed = 6\n',
         "actuation.motors.m.corner_speed (6 rad/s) must be below actuation.motors.m.no_load_speed (5 rad/s)"),
        ('[actuation.motors.m]\npeak_torque = 10\nno_load_speed = 5\ncoulomb_friction = -1\n',
         "actuation.motors.m.coulomb_friction must be a number >= 0 N m"),
        ('[actuation.motors.m]\npeak_torque = 10\nno_load_speed = 5\nstall = 3\n',
         "unknown key actuation.motors.m.stall"),
        ('[[actuation.joints]]\nmatch = "leg_*"\nmotor = "m"\n', "no motor type 'm' in [actuation.motors]"),
        ('[[actuation.joints]]\nmatch = "leg_*"\nrobot_kp = -1\n', "robot_kp must be a number > 0 N m/rad"),
    ],
)  # fmt: skip
def test_bad_actuation_tables(tmp_path: Path, table: str, words: str) -> None:
    with pytest.raises(RobotError) as caught:
        load_robot(write(tmp_path, BASE_TEXT + "\n" + table))
    assert words in str(caught.value) and "\n" not in str(caught.value)


@pytest.mark.parametrize("name", ["talos", "g1"])
def test_defaults_derived_from_the_urdf_are_plausible(name: str) -> None:
    description = load_robot(name)
    bare = RobotModel.load(dataclasses.replace(description, actuation=ActuationSpec()))  # no [actuation] at all
    actuation = resolve_actuation(bare)
    model = bare.model
    names = bare.joint_names
    urdf = np.array([model.effortLimit[model.joints[model.getJointId(n)].idx_v] for n in names])
    np.testing.assert_allclose(actuation.effort_limit, urdf)  # the URDF's torque limits
    assert actuation.control_dt == 0.001
    # Armature: a geared motor's rotor, tens of grams-square-metres for a humanoid's leg (5e-4 s^2 per N m).
    assert np.all((actuation.armature > 0.005) & (actuation.armature < 0.5))
    # The inertia a stance ankle carries is the whole robot pivoting about it: at least m d^2 for the COG at
    # distance d above the ankle axis, at most 1.5 times that (the body's own rotational inertia about its COG).
    data = model.createData()
    import pinocchio as pin

    pin.forwardKinematics(model, data, bare.q_half_sitting)
    cog = pin.centerOfMass(model, data, bare.q_half_sitting)
    ankle = next(i for i, n in enumerate(names) if "ankle_pitch" in n or n == "leg_left_5_joint")
    axis_height = data.oMi[model.getJointId(names[ankle])].translation[2]
    m_d2 = bare.mass * (cog[2] - axis_height) ** 2
    assert m_d2 < actuation.carried_inertia[ankle] < 1.5 * m_d2
    # Gains: the target natural frequency and a critically damped drive; stiffer where the load is larger; a joint
    # at its torque limit deflects by a fraction of a degree, not by radians nor by micro-radians.
    np.testing.assert_allclose(actuation.natural_frequency, DEFAULT_NATURAL_FREQUENCY)
    drive = actuation.armature + np.array([_distal(bare, n) for n in names])
    np.testing.assert_allclose(actuation.kd, 2.0 * np.sqrt(actuation.kp * drive))
    knee = next(i for i, n in enumerate(names) if "knee" in n or n == "leg_left_4_joint")
    assert actuation.kp[ankle] > actuation.kp[knee]
    deflection = actuation.effort_limit / actuation.kp
    legs = [i for i, n in enumerate(names) if "leg" in n or "hip" in n or "knee" in n or "ankle" in n]
    assert np.all((deflection[legs] > 1e-4) & (deflection[legs] < 0.1))


def _distal(robot: RobotModel, joint: str) -> float:
    """Inertia of the subtree beyond ``joint`` about its axis, by Pinocchio's joint-space inertia matrix."""
    import pinocchio as pin

    model = robot.model
    mass_matrix = pin.crba(model, model.createData(), robot.q_half_sitting)
    v = model.joints[model.getJointId(joint)].idx_v
    return float(mass_matrix[v, v])


def test_torques_stay_within_the_limits(tmp_path: Path, shorten) -> None:
    # Knees limited to 100 N m, a third of the URDF's: a walk needs more, so the servos saturate.
    text = TALOS_TEXT + '\n[[actuation.joints]]\nmatch = "leg_*_4_joint"\neffort_limit = 100.0\n'
    robot = RobotModel.load(load_robot(write(tmp_path, text)))
    sim = build_sim_model(robot, SimConfig(meshes=False))
    result = simulate(shorten("fig8", 1), robot, sim=sim, options=LoopOptions(start_ramp=0.5, start_hold=0.2))
    assert result.torque.shape == (len(result.times), len(sim.joint_names))
    limits = sim.actuation.effort_limit
    assert np.all(np.abs(result.torque) <= limits * (1.0 + 1e-9))
    knees = [sim.joint_names.index(n) for n in ("leg_left_4_joint", "leg_right_4_joint")]
    assert np.isclose(np.abs(result.torque[:, knees]), 100.0).any(), "the knee servos reached their limit"


def test_references_are_interpolated_over_the_physics_substeps(talos, shorten, monkeypatch) -> None:
    # Control every 2 ms, physics every 0.5 ms: 4 substeps, each with its own reference, on a line between two
    # control ticks' references; the torque of each substep is the clipped PD at that substep's state.
    sim = build_sim_model(talos, SimConfig(meshes=False, control_dt=0.002, physics_dt=0.0005))
    assert sim.substeps == 4
    kp, kd, limit = sim.kp, sim.kd, sim.actuation.effort_limit
    calls: list[np.ndarray] = []
    step = mujoco.mj_step

    def recording_step(model, data):
        ctrl = data.ctrl.copy()
        q, qd = data.qpos[sim.qpos_index].copy(), data.qvel[sim.dof_index].copy()
        step(model, data)
        expected = np.clip(kp * (ctrl - q) - kd * qd, -limit, limit)  # = kp (q_ref - q) + kd (qd_ref - qd)
        np.testing.assert_allclose(data.actuator_force, expected, rtol=1e-9, atol=1e-9)
        calls.append(ctrl)

    scenario = shorten("fig8", 1)
    options = LoopOptions(start_ramp=0.3, start_hold=0.0, after=0.0)
    monkeypatch.setattr(mujoco, "mj_step", recording_step)
    result = simulate(scenario, talos, sim=sim, options=options)
    monkeypatch.undo()
    assert not result.fell
    np.testing.assert_allclose(np.diff(result.times), 0.002)
    assert result.control_dt == 0.002 and result.physics_dt == 0.0005
    settle = round(SETTLE_TIME / 0.0005)  # the model's settling steps before the run (references held)
    ctrl = np.array(calls[settle:])
    assert len(ctrl) == 4 * len(result.times)
    periods = ctrl.reshape(len(result.times), 4, -1)
    moving = np.abs(periods[1:, -1] - periods[:-1, -1]).max(axis=1) > 1e-7  # control periods whose reference moved
    assert moving.sum() > 0.9 * len(moving)
    # Within every moving period the reference changes at every substep, by equal increments (a line) that start
    # from the previous period's last reference.
    increments = np.diff(np.concatenate([periods[:-1, -1:], periods[1:]], axis=1), axis=1)[moving]
    assert np.all(np.abs(increments).max(axis=2) > 0.0)
    np.testing.assert_allclose(increments, np.repeat(increments[:, :1], 4, axis=1), atol=1e-12)


def test_periods_that_do_not_fit_are_refused(talos, shorten) -> None:
    scenario = shorten("fig8", 1)
    with pytest.raises(ValueError, match="longer than the control period"):
        simulate(scenario, talos, control_dt=0.001, physics_dt=0.002)
    with pytest.raises(ValueError, match="must divide the control period"):
        simulate(scenario, talos, control_dt=0.002, physics_dt=0.0007)
    with pytest.raises(ValueError, match="longer than the control period"):
        build_sim_model(talos, SimConfig(meshes=False, physics_dt=0.002))  # Talos's control period is 1 ms
    assert substeps(0.002, 0.0005) == 4 and substeps(0.001, 0.001) == 1
