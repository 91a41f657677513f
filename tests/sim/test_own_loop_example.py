"""examples/own_loop.py, the README's loop of one's own, walks: the robot stays up and goes where the plan goes."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "own_loop.py"


def test_the_example_loop_walks_its_first_steps(capsys):
    spec = importlib.util.spec_from_file_location("own_loop", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    body = module.walk(4.0)
    truth = body.ground_truth()
    assert truth.com[2] > 0.8  # Talos walks with its COM at 0.84 m: it has not fallen or crouched
    # Four seconds of fig8 is five steps of 0.05 m: the COM has come about 0.1 m forward, between the feet.
    assert 0.05 < truth.com[0] < 0.2
    assert truth.left.force[2] + truth.right.force[2] > 0.8 * 9.81 * 90
    assert capsys.readouterr().out.count("COM") == 4


def test_the_example_loop_walks_g1_on_its_joint_torques(capsys):
    """G1 has no foot force sensor: the stack finds its contacts from the joint torques; three seconds is four
    steps."""
    spec = importlib.util.spec_from_file_location("own_loop", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    body = module.walk(3.0, "g1")
    truth = body.ground_truth()
    assert truth.com[2] > 0.6  # G1 walks with its COM at 0.64 m
    assert 0.02 < truth.com[0] < 0.15
    assert "damping" not in capsys.readouterr().out
