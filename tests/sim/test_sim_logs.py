"""``sim.parquet``: every documented column, its unit and length, and its values against ``sim.csv``, MuJoCo's own state
(the replay's configurations, the integrator's kinematics), the contact record and Pinocchio.

One short walk (one step of 0.08 m with short start and end phases, 5 N s pushed at 1 s) on Talos, about 5 s of
physics, the controller on the simulator's truth so that what it measured is MuJoCo's state; every test reads it.
The same walk on the estimate checks the truth the log keeps beside the estimate.
"""

from __future__ import annotations

import csv
import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")
pytest.importorskip("pyarrow")

import pyarrow.parquet as pq
from scenario_files import scenario_text

from rtgait.core.geometry.footsteps import Footstep, SoleRect
from rtgait.scenario.loading import load_scenario
from rtgait.sim.log_file import LOG_FORMAT, log_columns, read_sim_log
from rtgait.viz.sim_figure import sole_extent

DOCS = Path(__file__).resolve().parents[2] / "docs" / "logs.md"
PUSH_START, PUSH_DURATION, PUSH_FORCE = 1.0, 0.1, (50.0, 0.0, 0.0)


def _walk(talos: Any, sim: Any, folder: Path, state: str) -> tuple[Any, Path]:
    """The short walk on ``state`` in memory, and the folder its outputs were written to."""
    from rtgait.core.push import Push
    from rtgait.io.sim_run import simulate, write_sim_outputs
    from rtgait.sim.loop_options import LoopOptions

    path = folder / "short.toml"
    path.write_text(scenario_text(name="short", connection="quasi-real-time", single_support=0.7, double_support=0.1,
                                  dt=0.005, steps=1, step_length=0.08, short_ends=True), encoding="utf-8")  # fmt: skip
    scenario = load_scenario(str(path))
    push = Push(start=PUSH_START, duration=PUSH_DURATION, force=PUSH_FORCE)
    result = simulate(scenario, talos, sim=sim, push=push, options=LoopOptions(state=state))  # type: ignore[arg-type]
    out = folder / "out"
    extra = {"scenario": scenario.name, "connection": scenario.connection}
    write_sim_outputs(result, out, figure=False, title="short (quasi-real-time)", extra=extra)
    return result, out


@pytest.fixture(scope="module")
def logged(talos: Any, talos_sim: Any, tmp_path_factory: pytest.TempPathFactory) -> tuple[Any, Path]:
    """The short walk on the truth."""
    return _walk(talos, talos_sim, tmp_path_factory.mktemp("logged"), "truth")


@pytest.fixture(scope="module")
def log(logged: tuple[Any, Path]) -> Any:
    return read_sim_log(logged[1] / "sim.parquet")


def _documented() -> dict[str, str]:
    """Column name -> unit of every row of the column tables of docs/logs.md."""
    text = DOCS.read_text(encoding="utf-8").split("\n## Columns\n")[1].split("\n## ")[0]
    rows = re.findall(r"^\| `([a-z_<>]+)` \| ([^|]+) \|", text, flags=re.MULTILINE)
    return {name: "" if unit.strip() == "-" else unit.strip() for name, unit in rows}


# ----- the columns, as documented ------------------------------------------------------------------------------
def test_every_documented_column_is_in_the_file_with_its_unit_and_length(logged: tuple[Any, Path], log: Any) -> None:
    result, out = logged
    documented = _documented()
    expected = {}
    for name, unit in documented.items():
        for joint in result.joint_names if "<joint>" in name else [None]:
            expected[name.replace("<joint>", joint) if joint else name] = unit
    assert len(documented) > 90
    assert set(log.columns) == set(expected)  # nothing undocumented, nothing documented missing
    assert log.units == {name: expected[name] for name in log.columns}
    assert [c.name for c in log_columns(result.joint_names)] == list(log.columns)  # file order
    n = len(result.times)
    with open(out / "sim.csv", encoding="utf-8") as stream:
        rows = sum(1 for _ in stream) - 1
    assert rows == n and all(len(values) == n for values in log.columns.values())
    # The unit and meaning travel with each field of the file, not only in the docs.
    schema = pq.read_schema(out / "sim.parquet")
    assert schema.field("left_force_z").metadata[b"unit"] == b"N"
    assert b"joint" in schema.field(f"dq_{result.joint_names[0]}").metadata[b"description"]


def test_the_metadata_says_what_ran(logged: tuple[Any, Path], log: Any) -> None:
    from rtgait import __version__

    result, out = logged
    meta = log.metadata
    assert meta["format"] == LOG_FORMAT and meta["rtgait_version"] == __version__
    assert (meta["robot"], meta["controller"], meta["scenario"], meta["connection"]) == (
        "talos", "adaptive", "short", "quasi-real-time")  # fmt: skip
    assert meta["control_dt"] == result.control_dt and meta["physics_dt"] == result.physics_dt == meta["contact_lag"]
    assert meta["joint_names"] == list(result.joint_names) and meta["sole"]["front"] > 0.0
    assert meta["omega"] == pytest.approx(math.sqrt(result.gravity / 0.84), rel=1e-3)  # Talos walks at 0.84 m
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["files"] == ["sim.csv", "sim.parquet", "summary.json"]
    assert set(np.unique(log.columns["controller"])) == {"adaptive"}


# ----- the same values as sim.csv ---------------------------------------------------------------------------------
def test_the_columns_of_sim_csv_hold_the_same_values(logged: tuple[Any, Path], log: Any) -> None:
    _, out = logged
    with open(out / "sim.csv", encoding="utf-8") as stream:
        reader = csv.reader(stream)
        header = next(reader)
        table = np.array(list(reader), dtype=float)
    for index, name in enumerate(header):
        csv_values = table[:, index]
        values = log.columns[name].astype(float)
        rtol = 1e-5 if name.startswith("tau_") else 1e-9  # sim.csv's 6 and 10 significant digits
        np.testing.assert_allclose(values, csv_values, rtol=rtol, atol=1e-12, equal_nan=True, err_msg=name)


# ----- against MuJoCo's state and an independent computation ---------------------------------------------------------
def test_measured_joints_and_base_are_the_states_the_replay_recorded(
    logged: tuple[Any, Path], log: Any, talos: Any
) -> None:
    """The replay stores MuJoCo's whole qpos before a tick's physics (the state at t): the log's measured joint
    positions, read from the actuators after the step, and base pose are that state."""
    result, _ = logged
    ticks = result.replay_index
    model = talos.full_model
    for name in result.joint_names:
        column = model.joints[model.getJointId(name)].idx_q
        np.testing.assert_allclose(log.columns[f"q_{name}"][ticks], result.replay_q[:, column], rtol=0, atol=1e-12)
    base = np.column_stack([log.columns[f"base_{a}"] for a in ("x", "y", "z")] +
                           [log.columns[f"base_q{a}"] for a in ("x", "y", "z", "w")])  # fmt: skip
    np.testing.assert_allclose(base[ticks], result.replay_q[:, 0:7], rtol=0, atol=1e-12)


def _quaternion_log(q_from: np.ndarray, q_to: np.ndarray) -> np.ndarray:
    """Rotation vectors (rad) of ``q_to q_from^-1``, rows of unit quaternions ``(x, y, z, w)``: the world-frame
    rotation from one orientation to the next."""
    x1, y1, z1, w1 = (-q_from[:, i] if i < 3 else q_from[:, i] for i in range(4))  # the inverse: conjugate
    x2, y2, z2, w2 = (q_to[:, i] for i in range(4))
    w = w2 * w1 - x2 * x1 - y2 * y1 - z2 * z1
    v = np.column_stack([w2 * x1 + x2 * w1 + y2 * z1 - z2 * y1,
                         w2 * y1 - x2 * z1 + y2 * w1 + z2 * x1,
                         w2 * z1 + x2 * y1 - y2 * x1 + z2 * w1])  # fmt: skip
    norm = np.linalg.norm(v, axis=1)
    angle = 2.0 * np.arctan2(norm, w)
    return v * np.where(norm > 0, angle / np.where(norm > 0, norm, 1.0), 2.0)[:, None]


def test_velocities_are_those_the_integrator_moved_the_positions_with(logged: tuple[Any, Path], log: Any) -> None:
    """MuJoCo's implicitfast step updates the velocity first, then the position with the new velocity:
    ``q_k = q_{k-1} + h v_k`` for the joints and the base's origin, ``R_k = exp(h w_k) R_{k-1}`` for its orientation,
    with ``v_k`` the velocity of the state at tick ``k``. With one physics step per tick (Talos), the log's velocities
    at ``t`` must be the backward differences of its positions, to round-off."""
    result, _ = logged
    h = result.physics_dt
    assert result.control_dt == h
    c = log.columns
    for name in result.joint_names:
        np.testing.assert_allclose(np.diff(c[f"q_{name}"]) / h, c[f"dq_{name}"][1:], rtol=0, atol=1e-8, err_msg=name)
    for axis in "xyz":
        np.testing.assert_allclose(np.diff(c[f"base_{axis}"]) / h, c[f"base_v{axis}"][1:], rtol=0, atol=1e-8)
    quaternion = np.column_stack([c[f"base_q{a}"] for a in "xyzw"])
    rotation = _quaternion_log(quaternion[:-1], quaternion[1:]) / h
    omega = np.column_stack([c[f"base_w{a}"] for a in "xyz"])[1:]
    np.testing.assert_allclose(rotation, omega, rtol=0, atol=1e-6)
    assert np.abs(omega).max() > 0.02  # the base sways and pitches while walking: a test of something
    # The commanded joint velocity is the servo's reference: the finite difference of the commanded positions.
    name = result.joint_names[0]
    np.testing.assert_allclose(np.diff(c[f"q_command_{name}"]) / result.control_dt, c[f"dq_command_{name}"][1:],
                               rtol=0, atol=1e-8)  # fmt: skip


def test_com_velocity_is_pinocchios_of_the_measured_state(logged: tuple[Any, Path], log: Any, talos: Any) -> None:
    """Pinocchio's centre of mass and its velocity for the measured joint and base state equal MuJoCo's (the model
    builder gives both the URDF's inertias)."""
    import pinocchio as pin

    result, _ = logged
    c = log.columns
    model = talos.model
    data = model.createData()
    assert [model.names[i] for i in range(2, model.njoints)] == list(result.joint_names)
    for k in np.linspace(10, len(result.times) - 10, 25).astype(int):
        quat = np.array([c[f"base_q{a}"][k] for a in "xyzw"])
        q = np.r_[[c[f"base_{a}"][k] for a in "xyz"], quat, [c[f"q_{n}"][k] for n in result.joint_names]]
        rotation = pin.Quaternion(quat[3], *quat[0:3]).toRotationMatrix()
        linear = rotation.T @ np.array([c[f"base_v{a}"][k] for a in "xyz"])
        angular = rotation.T @ np.array([c[f"base_w{a}"][k] for a in "xyz"])
        v = np.r_[linear, angular, [c[f"dq_{n}"][k] for n in result.joint_names]]
        com = pin.centerOfMass(model, data, q, v)
        np.testing.assert_allclose(com, [c[f"cog_{a}"][k] for a in "xyz"], rtol=0, atol=1e-9)
        np.testing.assert_allclose(data.vcom[0], [c[f"cog_vel_{a}"][k] for a in "xyz"], rtol=0, atol=1e-7)
    dcm = np.array([c["cog_x"], c["cog_y"]]).T + np.array([c["cog_vel_x"], c["cog_vel_y"]]).T / log.metadata["omega"]
    np.testing.assert_allclose(dcm, np.array([c["dcm_x"], c["dcm_y"]]).T, rtol=0, atol=1e-12)


def _replayed(log: Any, result: Any, sim: Any, rows: np.ndarray) -> Any:
    """MuJoCo's state at each of the log's ``rows``, rebuilt from its measured positions and velocities (base pose
    and velocity, joints) in a fresh ``MjData`` and run through ``mj_forward`` and ``mj_subtreeVel``: yields
    ``(row, data)``. Free joint: ``qpos = (p, qw, qx, qy, qz)``, ``qvel = (v_p in the world, w in the base frame)``."""
    import mujoco

    c = log.columns
    data = mujoco.MjData(sim.model)
    joints_q = np.column_stack([c[f"q_{n}"] for n in result.joint_names])
    joints_v = np.column_stack([c[f"dq_{n}"] for n in result.joint_names])
    for k in rows:
        quat = np.array([c[f"base_q{a}"][k] for a in "wxyz"])
        rotation = np.empty(9)
        mujoco.mju_quat2Mat(rotation, quat)
        data.qpos[0:3] = [c[f"base_{a}"][k] for a in "xyz"]
        data.qpos[3:7] = quat
        data.qpos[sim.qpos_index] = joints_q[k]
        data.qvel[0:3] = [c[f"base_v{a}"][k] for a in "xyz"]
        data.qvel[3:6] = rotation.reshape(3, 3).T @ np.array([c[f"base_w{a}"][k] for a in "xyz"])
        data.qvel[sim.dof_index] = joints_v[k]
        mujoco.mj_forward(sim.model, data)
        mujoco.mj_subtreeVel(sim.model, data)
        yield k, data


def test_the_dcm_the_controller_acted_on_is_that_of_mujoco_s_state(
    logged: tuple[Any, Path], log: Any, talos: Any, talos_sim: Any
) -> None:
    """``dcm_control`` at tick k is ``c + c'/w`` of the state the controller measured, one physics step before t:
    with one step a tick, tick k - 1's state. Its COM and COM velocity are MuJoCo's ``subtree_com`` and
    ``subtree_linvel`` of that state rebuilt from the log, and ``w = sqrt(g / z_c)`` with the robot's walking
    height: a DCM made with a wrong sign, frequency or instant fails here."""
    result, _ = logged
    c = log.columns
    assert result.physics_dt == result.control_dt
    w = math.sqrt(result.gravity / talos.description.cog_height)
    assert log.metadata["omega"] == w
    walking = np.flatnonzero(result.times >= 0.0)
    assert walking[0] > 0 and np.isnan(c["dcm_control_x"][: walking[0]]).all()  # no controller in the transition
    base = talos_sim.base_body
    truth = np.array([
        data.subtree_com[base, 0:2] + data.subtree_linvel[base, 0:2] / w
        for _, data in _replayed(log, result, talos_sim, walking - 1)
    ])  # fmt: skip
    logged_dcm = np.column_stack([c["dcm_control_x"], c["dcm_control_y"]])[walking]
    np.testing.assert_allclose(logged_dcm, truth, rtol=0, atol=1e-9)
    # The walk moves the DCM both ways sideways and forward: a test of both components and their signs.
    assert truth[:, 1].min() < -0.02 < 0.02 < truth[:, 1].max() and np.ptp(truth[:, 0]) > 0.05
    # On the truth, the COM the controller acted on and the truth kept beside it are the same values.
    for what in ("cog_control", "cog_vel_control", "dcm_true"):
        other = what.replace("control", "true") if what != "dcm_true" else "dcm_control"
        for axis in "xy" if what.startswith("dcm") else "xyz":
            assert np.array_equal(c[f"{what}_{axis}"], c[f"{other}_{axis}"], equal_nan=True), (what, axis)
    assert log.metadata["state"] == "truth" and result.summary()["estimation"] is None


@pytest.fixture(scope="module")
def estimated(talos: Any, talos_sim: Any, tmp_path_factory: pytest.TempPathFactory) -> tuple[Any, Any, Path]:
    """The short walk on the estimate, its log and its outputs' folder."""
    result, out = _walk(talos, talos_sim, tmp_path_factory.mktemp("estimated"), "estimated")
    return result, read_sim_log(out / "sim.parquet"), out


def test_the_truth_beside_the_estimate_is_that_of_mujoco_s_state(
    estimated: tuple[Any, Any, Path], talos_sim: Any
) -> None:
    """On the estimate, ``cog_true``, ``cog_vel_true`` and ``dcm_true`` at tick k are MuJoCo's COM, COM velocity and
    ``c + c'/w`` of the state the estimator measured (tick k - 1's, one physics step a tick), rebuilt from the log;
    the estimate differs from them by millimetres, and the summary's errors are those of these columns."""
    result, log, out = estimated
    c = log.columns
    walking = np.flatnonzero(result.times >= 0.0)
    base = talos_sim.base_body
    w = log.metadata["omega"]
    rebuilt = np.array([
        np.r_[data.subtree_com[base], data.subtree_linvel[base]]
        for _, data in _replayed(log, result, talos_sim, walking - 1)
    ])  # fmt: skip
    true = np.column_stack([c[f"cog_true_{a}"] for a in "xyz"] + [c[f"cog_vel_true_{a}"] for a in "xyz"])[walking]
    np.testing.assert_allclose(true, rebuilt, rtol=0, atol=1e-9)
    dcm_true = np.column_stack([c["dcm_true_x"], c["dcm_true_y"]])[walking]
    np.testing.assert_allclose(dcm_true, rebuilt[:, 0:2] + rebuilt[:, 3:5] / w, rtol=0, atol=1e-12)
    estimate = np.column_stack([c[f"cog_control_{a}"] for a in "xyz"])[walking]
    error = np.linalg.norm(estimate - true[:, 0:3], axis=1)
    assert 0.0 < error.max() < 0.01  # an estimate: not the truth, millimetres from it
    dcm_error = np.column_stack([c["dcm_control_x"], c["dcm_control_y"]])[walking] - dcm_true
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["state"] == log.metadata["state"] == "estimated"
    assert summary["sensors"] == log.metadata["sensors"] == {"noise": 1.0, "latency": 0, "seed": 0}
    estimation = summary["estimation"]
    assert estimation["ticks"] == len(walking)
    assert estimation["com_rms"] == pytest.approx(math.sqrt(np.mean(error**2)), rel=1e-12)
    assert estimation["dcm_rms"] == pytest.approx(math.sqrt(np.mean(np.sum(dcm_error**2, axis=1))), rel=1e-12)
    assert np.isnan(c["cog_true_x"][: walking[0]]).all() and np.isnan(c["cog_control_x"][: walking[0]]).all()


def test_the_soles_orientation_columns_are_mujoco_s_sole_frames(
    logged: tuple[Any, Path], log: Any, talos_sim: Any
) -> None:
    """Each sole's ``yaw``, ``pitch`` and ``roll`` columns make ``Rz(yaw) Ry(pitch) Rx(roll)``, MuJoCo's sole site
    frame (``site_xmat``) of the state rebuilt from the log; the ``tilt`` column is its normal's angle from the
    vertical. The swing foot pitches and rolls by different amounts: angles swapped or of a wrong sign fail."""
    result, _ = logged
    c = log.columns

    def rz(a: float) -> np.ndarray:
        return np.array([[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0], [0.0, 0.0, 1.0]])

    def ry(a: float) -> np.ndarray:
        return np.array([[math.cos(a), 0.0, math.sin(a)], [0.0, 1.0, 0.0], [-math.sin(a), 0.0, math.cos(a)]])

    def rx(a: float) -> np.ndarray:
        return np.array([[1.0, 0.0, 0.0], [0.0, math.cos(a), -math.sin(a)], [0.0, math.sin(a), math.cos(a)]])

    rows = np.arange(0, len(result.times), 7)
    sites = {"left": talos_sim.left_sole_site, "right": talos_sim.right_sole_site}
    for k, data in _replayed(log, result, talos_sim, rows):
        for side, site in sites.items():
            frame = data.site_xmat[site].reshape(3, 3)
            yaw, pitch, roll = (float(c[f"{side}_sole_{a}"][k]) for a in ("yaw", "pitch", "roll"))
            np.testing.assert_allclose(rz(yaw) @ ry(pitch) @ rx(roll), frame, rtol=0, atol=1e-9, err_msg=(side, k))
            assert c[f"{side}_tilt"][k] == pytest.approx(math.acos(min(frame[2, 2], 1.0)), abs=1e-6)
    # The soles tilt by a milliradian or so (the right one most: it swings), and pitch and roll differently: far
    # beyond the 1e-9 above, so a swap or a sign is seen.
    pitch, roll = c["right_sole_pitch"], c["right_sole_roll"]
    assert np.abs(pitch).max() > 5e-4 and np.abs(roll).max() > 5e-4 and np.abs(pitch - roll).max() > 5e-4


def test_per_foot_wrench_sums_to_the_contact_record(logged: tuple[Any, Path], log: Any) -> None:
    """The controller's per-foot wrench (mj_contactForce, the contacts of the last physics step) against the
    contact record's vertical forces (the constraint forces' pyramid edges), which at tick k - 1 read the same
    contacts; and at rest the feet carry the robot's weight, its centre of pressure under the COM."""
    result, _ = logged
    c = log.columns
    walking = result.times >= 0.0
    vertical = c["left_force_z"] + c["right_force_z"]
    recorded = c["left_normal_force"] + c["right_normal_force"]
    index = np.flatnonzero(walking)
    np.testing.assert_allclose(vertical[index], recorded[index - 1], rtol=1e-9, atol=1e-6)
    for side in ("left", "right"):  # a foot's own force, not only the sum
        np.testing.assert_allclose(c[f"{side}_force_z"][index], c[f"{side}_normal_force"][index - 1], rtol=1e-9,
                                   atol=1e-6)  # fmt: skip
    assert np.isnan(vertical[~walking]).all()  # the controller does not measure during the transition
    weight = result.mass * result.gravity
    end = slice(-100, None)  # the last 0.1 s, at rest
    assert result.ended_at_rest
    assert vertical[end].mean() == pytest.approx(weight, rel=0.01)
    # The moment of the two feet's forces about the ZMP vanishes: the force-weighted mean of their CoPs is the ZMP.
    for axis in "xy":
        cop = (c[f"left_cop_{axis}"] * c["left_force_z"] + c[f"right_cop_{axis}"] * c["right_force_z"]) / vertical
        np.testing.assert_allclose(cop[end], c[f"zmp_{axis}"][np.arange(len(vertical))[end] - 1], atol=1e-6)
        assert abs(np.mean(cop[end]) - np.mean(c[f"cog_{axis}"][end])) < 0.01


def test_planned_com_velocity_is_the_derivative_of_the_planned_com(logged: tuple[Any, Path], log: Any) -> None:
    """``cog_vel_planned`` comes from the plan's DCM (``w (xi - c)``): it must be the time derivative of the plan's
    COM (the IK target minus the controller's correction), except at the ticks where a replan moved the plan."""
    result, _ = logged
    c = log.columns
    walking = np.flatnonzero(result.times >= 0.0)[1:-1]
    for axis in "xy":
        plan = c[f"cog_planned_{axis}"] - c[f"cog_offset_{axis}"]
        derivative = (plan[walking + 1] - plan[walking - 1]) / (2.0 * result.control_dt)
        error = np.abs(derivative - c[f"cog_vel_planned_{axis}"][walking])
        assert np.median(error) < 1e-5 and np.percentile(error, 99) < 1e-3, axis
    assert np.isnan(c["cog_vel_planned_x"][result.times < 0.0]).all()


def test_feet_targets_and_measured_soles(logged: tuple[Any, Path], log: Any) -> None:
    """The IK's sole targets start where the soles stand and the measured soles follow them: the stance foot stays
    within a few millimetres of its target, and the swinging foot is lifted by its target."""
    result, _ = logged
    c = log.columns
    for side, code in (("left", 1), ("right", 2)):
        stance = (result.support == code) | (result.support == 0)
        for axis in "xy":
            gap = np.abs(c[f"{side}_sole_{axis}"] - c[f"{side}_target_{axis}"])[stance]
            assert np.percentile(gap, 95) < 0.005, (side, axis)
        np.testing.assert_allclose(c[f"{side}_sole_yaw"], result.sole_pose[:, 0 if side == "left" else 1, 2],
                                   atol=1e-12)  # fmt: skip
    swing = result.support == 1  # left support: the right foot swings
    assert c["right_target_z"][swing].max() > 0.03 and c["right_sole_z"][swing].max() > 0.02


def test_events_name_the_landings_and_the_push(logged: tuple[Any, Path], log: Any) -> None:
    result, _ = logged
    events = log.events
    c = log.columns
    times = result.times
    kinds = [e["kind"] for e in events]
    assert kinds.count("push") == 1 and kinds.count("push-end") == 1
    push = next(e for e in events if e["kind"] == "push")
    assert push["t"] == pytest.approx(PUSH_START, abs=1e-9) and times[push["tick"]] == pytest.approx(PUSH_START)
    landings = [e for e in events if e["kind"] == "landing"]
    assert len(landings) >= result.steps_completed >= 2  # the step and the closing step
    for event in events:
        label = event["kind"] + (f":{event['side']}" if event["side"] else "")
        assert label in c["events"][event["tick"]].split(";")
    assert (c["events"] != "").sum() == len({e["tick"] for e in events}) < len(times) / 100


# ----- the figure's sole edges -------------------------------------------------------------------------------------
@pytest.mark.parametrize("yaw", [0.0, 0.4, -2.0])
def test_sole_extent_is_that_of_the_soles_corners(yaw: float) -> None:
    sole = SoleRect(front=0.12, back=0.09, inner=0.05, outer=0.07)
    left, right = Footstep(0.3, 0.1, yaw, "left"), Footstep(0.5, -0.1, -yaw, "right")
    pose = np.array([[[left.x, left.y, left.yaw], [right.x, right.y, right.yaw]]] * 3)
    stance = np.array([[True, False], [True, True], [False, False]])
    extent = sole_extent(pose, stance, sole)
    alone = sole.corners(left)
    both = np.vstack([alone, sole.corners(right)])
    np.testing.assert_allclose(extent[0], np.column_stack([alone.min(axis=0), alone.max(axis=0)]), atol=1e-12)
    np.testing.assert_allclose(extent[1], np.column_stack([both.min(axis=0), both.max(axis=0)]), atol=1e-12)
    assert np.isnan(extent[2]).all()


# ----- the figure drawn again from the file ----------------------------------------------------------------------
def _drawing(figure: Any) -> list[tuple[str, np.ndarray]]:
    """Every line and band of every panel, the panels' limits and titles: what the figure shows, as numbers."""
    shown: list[tuple[str, np.ndarray]] = []
    for ax in figure.axes:
        shown += [(str(line.get_label()), np.asarray(line.get_xydata(), dtype=float)) for line in ax.get_lines()]
        shown += [("band", np.concatenate([p.vertices for p in band.get_paths()])) for band in ax.collections]
        shown.append((ax.get_title(), np.array([*ax.get_xlim(), *ax.get_ylim()])))
    return shown


def test_zmp_sim_drawn_from_sim_parquet_is_that_of_the_run(logged: tuple[Any, Path]) -> None:
    pytest.importorskip("matplotlib")
    from rtgait.viz.sim_figure import ZmpSimRun, draw_zmp_sim, read_zmp_sim_run

    result, out = logged
    in_memory = _drawing(draw_zmp_sim(ZmpSimRun.from_result(result, "short (quasi-real-time)")))
    from_file = _drawing(draw_zmp_sim(read_zmp_sim_run(out)))
    assert len(in_memory) == len(from_file) > 10
    labels = [label for label, _ in in_memory]
    assert "_sole low" in labels and "measured ZMP (contact CoP)" in labels  # the sole edges are drawn
    for (label_a, a), (label_b, b) in zip(in_memory, from_file, strict=True):
        assert label_a == label_b
        np.testing.assert_array_equal(a, b)  # full precision: the very same numbers


def test_without_pyarrow_simulate_says_so_in_one_line_and_writes_the_rest(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import rtgait.io.sim_files
    import rtgait.sim.log_file
    from rtgait.cli.main import main

    for module in (rtgait.sim.log_file, rtgait.io.sim_files):
        monkeypatch.setattr(module, "parquet_available", lambda: False)
    path = tmp_path / "tiny.toml"
    path.write_text(scenario_text(name="tiny", single_support=0.7, double_support=0.1, dt=0.005, steps=1,
                                  step_length=0.05, short_ends=True), encoding="utf-8")  # fmt: skip
    out = tmp_path / "out"
    assert main(["simulate", str(path), "--no-figures", "--quiet", "--out", str(out)]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "pyarrow" in err[0] and "sim.parquet" in err[0], err
    assert sorted(p.name for p in out.iterdir()) == ["sim.csv", "summary.json"]
