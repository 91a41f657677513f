"""The 3D replay of a simulated walk: recorded configurations, their conversion to Pinocchio, the HTML file."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")
pytest.importorskip("meshcat")

import pinocchio as pin

from rtgait.cli.main import main
from rtgait.io.sim_run import replay_paths


def test_replay_configurations_put_the_soles_where_mujoco_had_them(talos, short_walk):
    """Pinocchio's forward kinematics of the converted full configuration vs MuJoCo's sole sites at the same
    tick: the conversion (quaternion order, joints by name, locked joints) is right only if they agree."""
    _, result = short_walk
    assert not result.fell
    m = len(result.replay_index)
    assert result.replay_q.shape == (m, talos.full_model.nq)
    assert result.replay_soles.shape == (m, 2, 3)
    # One configuration every 40 ms of the run.
    assert np.allclose(np.diff(result.replay_times), 0.04)
    assert m == pytest.approx(result.duration / 0.04, abs=1.0)
    data = talos.full_model.createData()
    # Samples in the start transition, mid-walk (a foot in the air) and at the end.
    lifted = 0
    for row in (0, m // 3, m // 2, 2 * m // 3, m - 1):
        q = result.replay_q[row]
        assert np.linalg.norm(q[3:7]) == pytest.approx(1.0, abs=1e-9)
        pin.framesForwardKinematics(talos.full_model, data, q)
        left = data.oMf[talos.full_left_sole_id].translation
        right = data.oMf[talos.full_right_sole_id].translation
        np.testing.assert_allclose(left, result.replay_soles[row, 0], atol=1e-9)
        np.testing.assert_allclose(right, result.replay_soles[row, 1], atol=1e-9)
        # The base is the one of the per-tick record (x, y, z; quaternion x, y, z, w).
        tick = result.replay_index[row]
        np.testing.assert_allclose(q[0:3], result.base_position[tick], atol=1e-12)
        np.testing.assert_allclose(q[3:7], result.base_quaternion[tick], atol=1e-12)
        lifted += max(left[2], right[2]) > 0.01
    assert lifted >= 1  # the samples are not all of a robot standing still
    # The walk moved the soles forward.
    assert result.replay_soles[-1, :, 0].mean() > result.replay_soles[0, :, 0].mean() + 0.1


def test_replay_paths_have_no_gaps(short_walk):
    _, result = short_walk
    cog, zmp = replay_paths(result)
    assert cog.shape == (len(result.replay_index), 3) and zmp.shape == (len(result.replay_index), 2)
    assert np.isfinite(zmp).all() and np.isfinite(cog).all()


def test_the_cli_writes_the_replay_of_the_simulated_motion(tmp_path: Path, write_scenario) -> None:
    # One step of 8 cm and the closing step, fig8's timing: a short run for the command line.
    scenario = write_scenario(
        name="short", connection="quasi-real-time", single_support=0.7, double_support=0.1, dt=0.005,
        steps=1, step_length=0.08, short_ends=True,
    )  # fmt: skip
    out = tmp_path / "sim"
    assert main(["simulate", str(scenario), "--out", str(out), "--html", "--no-figures", "--quiet"]) == 0
    page = (out / "replay.html").read_text(encoding="utf-8")
    assert page.lstrip().lower().startswith("<!doctype html") or "<html" in page[:500].lower()
    assert "in MuJoCo" in page  # the title names the simulated motion
    assert len(page) > 100_000  # meshes and the viewer inlined
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert "replay.html" in summary["files"]
