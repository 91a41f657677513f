"""Model error (rtgait.sim.model_error): the draws, their effect on the MuJoCo model, the encoders and the drives.

The perturbed model is checked against the nominal one and against MuJoCo's own sums (subtree masses, the COM from
``mj_comPos``); the joint offsets against MuJoCo's ``qpos``: a drive holding ``q_ref`` holds its joint at
``q_ref - o`` (less the servo's static deflection) and its encoder reads the joint plus ``o``.
"""

from __future__ import annotations

import copy
import dataclasses
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from rtgait.interface.command import JointCommand  # noqa: E402
from rtgait.io.sim_files import MODEL_ERROR_FILE, write_sim_outputs  # noqa: E402
from rtgait.io.sim_run import simulate  # noqa: E402
from rtgait.sim.config import SensorSettings  # noqa: E402
from rtgait.sim.model import SimConfig, build_sim_model  # noqa: E402
from rtgait.sim.model_error import MODEL_ERROR_RANGES, ModelErrorRanges, apply_model_error, draw  # noqa: E402
from rtgait.sim.robot import SimRobot  # noqa: E402

SEED = 7
HOLD = 1.5  # s standing: the stance settles from the offsets within about a second


@pytest.fixture(scope="module")
def perturbed(talos: Any) -> Any:
    """Talos in MuJoCo with the model error of :data:`SEED`, noise-free sensors."""
    return build_sim_model(talos, SimConfig(meshes=False, model_error=SEED, sensors=SensorSettings(noise=0.0)))


def _draw(sim: Any, seed: int, ranges: ModelErrorRanges = MODEL_ERROR_RANGES) -> Any:
    return draw(seed, sim.model, sim.joint_names, ranges)


def test_a_seed_draws_the_same_error_and_other_seeds_others(talos_sim: Any) -> None:
    first, again, other = _draw(talos_sim, 3), _draw(talos_sim, 3), _draw(talos_sim, 4)
    for name in ("mass_factors", "com_shifts", "joint_offsets"):
        np.testing.assert_array_equal(getattr(first, name), getattr(again, name))
        assert not np.any(getattr(first, name) == getattr(other, name)), name
    # The sensors' seed and the model error's are separate streams: seed 0 of each does not draw the same numbers.
    rng = np.random.default_rng(0)
    assert not np.allclose(_draw(talos_sim, 0).joint_offsets / MODEL_ERROR_RANGES.joint_offset,
                           rng.uniform(-1.0, 1.0, len(talos_sim.joint_names)))  # fmt: skip


def test_the_draws_are_within_the_ranges_and_spread_over_them(talos_sim: Any) -> None:
    errors = [_draw(talos_sim, seed) for seed in range(40)]
    factors = np.concatenate([e.mass_factors for e in errors])
    shifts = np.concatenate([e.com_shifts.ravel() for e in errors])
    offsets = np.concatenate([e.joint_offsets for e in errors])
    for values, centre, half in (
        (factors, 1.0, 0.05),
        (shifts, 0.0, 0.010),
        (offsets, 0.0, math.radians(0.5)),
    ):
        assert np.all(np.abs(values - centre) <= half)
        # Uniform over the range: the extremes come close to its ends, the spread is half / sqrt(3).
        assert np.max(np.abs(values - centre)) > 0.95 * half
        assert np.std(values) == pytest.approx(half / math.sqrt(3.0), rel=0.15)
    # Every body with mass and every moving joint gets a value; nothing else.
    model = talos_sim.model
    assert errors[0].bodies == tuple(model.body(i).name for i in range(model.nbody) if model.body_mass[i] > 0.0)
    assert errors[0].joints == talos_sim.joint_names


def test_the_model_has_exactly_the_drawn_masses_inertias_and_coms(talos_sim: Any, perturbed: Any) -> None:
    nominal, model, error = talos_sim.model, perturbed.model, perturbed.model_error
    assert error.seed == SEED
    ids = error.body_ids
    np.testing.assert_array_equal(model.body_mass[ids], nominal.body_mass[ids] * error.mass_factors)
    np.testing.assert_array_equal(model.body_inertia[ids], nominal.body_inertia[ids] * error.mass_factors[:, None])
    np.testing.assert_array_equal(model.body_ipos[ids], nominal.body_ipos[ids] + error.com_shifts)
    # The COM moves, the inertia's axes and the bodies' frames do not.
    np.testing.assert_array_equal(model.body_iquat, nominal.body_iquat)
    np.testing.assert_array_equal(model.body_pos, nominal.body_pos)
    np.testing.assert_array_equal(model.body_quat, nominal.body_quat)
    # The total mass as drawn, in MuJoCo's own sums (mj_setConst ran), not the controller's model's.
    model_mass, simulated = error.total_mass
    assert model_mass == pytest.approx(talos_sim.robot.mass, rel=1e-12)
    assert simulated == pytest.approx(float(np.sum(nominal.body_mass[ids] * error.mass_factors)), rel=1e-12)
    assert float(model.body_subtreemass[perturbed.base_body]) == pytest.approx(simulated, rel=1e-12)
    assert abs(simulated - model_mass) > 1e-3


def test_the_whole_robots_com_error_is_mujocos(talos_sim: Any, perturbed: Any) -> None:
    """The summary's COM error at half-sitting against MuJoCo's COM of the two models at that configuration."""

    def com(sim: Any) -> np.ndarray:
        data = mujoco.MjData(sim.model)
        data.qpos[:] = sim.qpos_half_sitting
        mujoco.mj_forward(sim.model, data)
        return data.subtree_com[sim.base_body].copy()

    shift = com(perturbed) - com(talos_sim)
    np.testing.assert_allclose(perturbed.model_error.com_error, shift, atol=1e-12)
    assert np.linalg.norm(shift) > 1e-4  # a few millimetres, not nothing


def test_apply_refuses_a_model_it_was_not_drawn_for(talos_sim: Any) -> None:
    model = copy.deepcopy(talos_sim.model)
    error = _draw(talos_sim, 1)
    apply_model_error(model, error)
    with pytest.raises(ValueError, match="another model"):
        apply_model_error(model, error)
    np.testing.assert_array_equal(talos_sim.model.body_mass[error.body_ids], error.masses)  # the nominal untouched


def test_a_held_joint_reads_the_reference_and_sits_at_it_less_the_offset(perturbed: Any) -> None:
    """The drive servos its encoder (reading = joint + offset) to ``q_ref``: standing still, the joint is at
    ``q_ref - offset - tau / kp`` (the servo's static deflection under the load ``tau``) and reads that + offset."""
    sim = perturbed
    offsets = sim.encoder_offsets
    assert offsets is not None and np.all(offsets != 0.0)
    data = sim.new_data()
    q_ref = sim.qpos_half_sitting[sim.qpos_index]
    np.testing.assert_allclose(data.ctrl, q_ref - offsets, rtol=0.0, atol=1e-15)  # the settle held the same
    robot = SimRobot(sim, data, q_ref.copy())
    still = np.zeros_like(q_ref)
    for _ in range(round(HOLD / sim.control_dt)):
        robot.write(JointCommand(q_ref.copy(), still))
        q_true = data.qpos[sim.qpos_index].copy()
        robot.first_substep()  # Talos: one physics step a period; the reading is of the state it started from
        reading = robot.read().joint_positions
        np.testing.assert_allclose(reading - q_true, offsets, rtol=0.0, atol=1e-15)
    np.testing.assert_allclose(data.ctrl, q_ref - offsets, rtol=0.0, atol=1e-15)
    deflection = data.actuator_force / sim.kp
    assert np.max(np.abs(data.qvel)) < 5e-3
    np.testing.assert_allclose(q_true + deflection, q_ref - offsets, rtol=0.0, atol=2e-5)
    np.testing.assert_allclose(reading + deflection, q_ref, rtol=0.0, atol=2e-5)
    # The offsets are what moved the joints: up to 0.5 deg, far beyond the tolerance above.
    assert np.max(np.abs(offsets)) > 100 * 2e-5


def test_without_a_model_error_a_run_is_the_same_as_with_a_zero_one(
    talos: Any, talos_sim: Any, shorten: Any, tmp_path: Path
) -> None:
    """A model error of zero ranges goes through every step of a perturbed run (the model's constants recomputed,
    the drives and encoders offset by zeros) and must give the bytes of a run without one: the perturbation adds
    nothing but the drawn values. The run with model error 0 of the default ranges writes its values."""
    zero = draw(0, talos_sim.model, talos_sim.joint_names, ModelErrorRanges(0.0, 0.0, 0.0))
    model = copy.deepcopy(talos_sim.model)
    apply_model_error(model, zero)
    zero_sim = dataclasses.replace(talos_sim, model=model, model_error=zero)
    scenario = shorten("fig8", 2)
    outputs = {}
    for name, sim in (("none", talos_sim), ("zero", zero_sim)):
        result = simulate(scenario, talos, sim=sim)
        outputs[name] = write_sim_outputs(result, tmp_path / name, figure=False, log=False)
    assert (tmp_path / "none" / "sim.csv").read_bytes() == (tmp_path / "zero" / "sim.csv").read_bytes()
    assert "model_error" not in outputs["none"] and MODEL_ERROR_FILE not in outputs["none"]["files"]
    assert not (tmp_path / "none" / MODEL_ERROR_FILE).exists()
    # The perturbed run's records: the compact one in summary.json, every value in model_error.json.
    summary = json.loads((tmp_path / "zero" / "summary.json").read_text())
    assert summary["model_error"]["seed"] == 0
    assert summary["model_error"]["total_mass_kg"]["simulated"] == pytest.approx(talos.mass, rel=1e-12)
    values = json.loads((tmp_path / "zero" / MODEL_ERROR_FILE).read_text())
    assert set(values["mass_factors"]) == set(zero.bodies)
    assert set(values["joint_offsets_deg"]) == set(talos.joint_names)


def test_model_error_files_hold_the_drawn_values_in_their_units(perturbed: Any) -> None:
    error = perturbed.model_error
    values = error.values()
    assert values["ranges"] == {"mass_percent": 5.0, "com_mm": 10.0, "joint_offset_deg": 0.5}
    for i, body in enumerate(error.bodies):
        assert values["mass_factors"][body] == error.mass_factors[i]
        np.testing.assert_allclose(values["com_shifts_mm"][body], 1e3 * error.com_shifts[i], rtol=1e-15)
    for i, joint in enumerate(error.joints):
        assert values["joint_offsets_deg"][joint] == pytest.approx(math.degrees(error.joint_offsets[i]), rel=1e-15)
    largest = error.summary()["largest"]
    assert largest["joint_offset_deg"] == pytest.approx(max(abs(v) for v in values["joint_offsets_deg"].values()))
    assert largest["mass_percent"] <= 5.0 and largest["com_shift_mm"] <= 10.0


@pytest.mark.parametrize("seed", [-1, 1.5, True, "1"])
def test_sim_config_refuses_a_seed_that_is_not_a_whole_number(seed: Any) -> None:
    with pytest.raises(ValueError, match=r"SimConfig\.model_error"):
        SimConfig(model_error=seed)


def test_with_the_motor_model_the_joints_friction_is_drawn_too(talos: Any, perturbed: Any) -> None:
    """With the motor model each joint's Coulomb and viscous friction is the motor type's times its drawn factor
    (within +-30 %, one factor for both), the other draws unchanged; without it the friction is not drawn into the
    model nor reported."""
    motors = build_sim_model(talos, SimConfig(meshes=False, model_error=SEED, motor_model=True))
    error, nominal = motors.model_error, motors.motors
    assert error.friction_applied and not perturbed.model_error.friction_applied
    for name in ("mass_factors", "com_shifts", "joint_offsets", "friction_factors"):
        np.testing.assert_array_equal(getattr(error, name), getattr(perturbed.model_error, name))
    factors = error.friction_factors
    assert np.all(np.abs(factors - 1.0) <= MODEL_ERROR_RANGES.friction) and np.ptp(factors) > 0.2
    dofs = motors.dof_index
    np.testing.assert_allclose(motors.model.dof_frictionloss[dofs], nominal.coulomb_friction * factors, rtol=1e-12)
    np.testing.assert_allclose(motors.model.dof_damping[dofs], nominal.viscous_friction * factors, rtol=1e-12)
    values, summary = error.values(), error.summary()
    assert values["friction_factors"] == dict(zip(talos.joint_names, factors.tolist(), strict=True))
    assert summary["ranges"]["friction_percent"] == 30.0
    assert summary["largest"]["friction_percent"] == pytest.approx(100.0 * np.max(np.abs(factors - 1.0)))
    assert "friction_factors" not in perturbed.model_error.values()
    assert "friction_percent" not in perturbed.model_error.summary()["largest"]
