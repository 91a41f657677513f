"""What a sample offers besides its values: the names other libraries use and poses as homogeneous transforms."""

from __future__ import annotations

import math

import numpy as np

from rtgait.core import OnlinePlanner, PlannerConfig, Stride, Timing
from rtgait.core.planner.sample import foot_transform


def test_com_names_are_the_cog_values():
    cfg = PlannerConfig()
    p = OnlinePlanner(cfg, [Stride(0.1, 0.19)] * 3)
    p.start(0.0)
    s = p.sample(2.3)
    assert np.array_equal(s.com, s.cog) and np.array_equal(s.com_vel, s.cog_vel)
    assert np.array_equal(s.com_acc, s.cog_acc)


def test_foot_transforms_map_the_foot_frame_to_the_world():
    cfg = PlannerConfig(timing=Timing(0.8, 0.2))
    p = OnlinePlanner(cfg, [Stride(0.1, 0.2, 0.3), Stride(0.1, 0.2, 0.3), Stride(0.0, 0.2)])
    p.start(0.0)
    s = p.sample(p.phase_start(4) + 0.05)  # after a turning step: yaw != 0
    for pose, transform in ((s.left_foot, s.left_foot_transform()), (s.right_foot, s.right_foot_transform())):
        x, y, z, yaw = pose
        assert np.allclose(transform[:3, 3], [x, y, z])
        # The foot's forward axis in the world is (cos yaw, sin yaw); the matrix is a rotation.
        assert np.allclose(transform[:3, 0], [math.cos(yaw), math.sin(yaw), 0.0])
        assert np.allclose(transform[:3, :3] @ transform[:3, :3].T, np.eye(3))
        assert np.allclose(transform[3], [0, 0, 0, 1])
    assert abs(s.left_foot[3]) > 0.1
    point = foot_transform(np.array([1.0, 2.0, 0.0, math.pi / 2])) @ [1.0, 0.0, 0.0, 1.0]
    assert np.allclose(point, [1.0, 3.0, 0.0, 1.0])


def test_configs_take_the_com_height_under_either_name():
    from dataclasses import replace

    import pytest

    assert PlannerConfig(com_height=0.9).cog_height == 0.9
    assert PlannerConfig(com_height=0.9) == PlannerConfig(cog_height=0.9)
    assert replace(PlannerConfig(com_height=0.9), horizon_steps=2).cog_height == 0.9
    with pytest.raises(ValueError, match="disagree"):
        PlannerConfig(cog_height=0.7, com_height=0.9)
    with pytest.raises(ValueError, match="cog_height must be within"):
        PlannerConfig(com_height=1e-6)
