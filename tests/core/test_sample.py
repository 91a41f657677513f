"""What a sample holds, by name: each field against the quantity it names, computed apart from the sampling code;
and what a sample offers besides its values: the names other libraries use and poses as homogeneous transforms."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.core import SAMPLE_FIELDS, OnlinePlanner, PlannerConfig, Stride, Timing
from rtgait.core.planner.sample import SampleColumns, SampleValues, foot_transform

TURNING_WALK = [Stride(0.1, 0.2, 0.2), Stride(0.15, 0.2, 0.2), Stride(0.1, 0.2), Stride(0.0, 0.2)]
"""Turning steps: the feet's yaws differ from zero and from each other, so no two foot fields coincide."""


def _pose(foot) -> tuple[float, float, float, float]:
    return (foot.x, foot.y, 0.0, foot.yaw)


def test_a_samples_fields_are_the_plans_quantities_by_name():
    """COG, ZMP and DCM from the plan's closed form (CogTrajectory, its ZMP spline, c + c'/w), the reference ZMP as
    the footsteps' transfer (a cubic with zero end velocities between the ZMP where a double support begins and where
    it ends), the feet from the footprints: a field filled or read under another name fails here."""
    cfg = PlannerConfig(timing=Timing(0.8, 0.2))
    planner = OnlinePlanner(cfg, TURNING_WALK)
    planner.start(0.0)
    w, last_phase = planner.w, 2 * len(TURNING_WALK)
    references_differ = False
    for q in range(last_phase + 1):
        start, duration = planner.phase_start(q), planner.timeline.duration(q)
        begins, _, _ = planner.sample_values(start)
        inside = [(s, *planner.sample_values(start + s * duration), planner.current_plan) for s in (0.25, 0.5, 0.75)]
        ends, _, _ = planner.sample_values(start + duration)  # after the interior: it may replan
        for s, values, support, phase, plan in inside:
            assert phase == q
            t = start + s * duration
            (cog, vel, acc), zmp = (a[0] for a in plan.evaluate(t)), plan.zmp.evaluate(t)[0]
            assert (values.cog_x, values.cog_y, values.cog_z) == pytest.approx((*cog, cfg.cog_height), abs=1e-9)
            assert (values.cog_vx, values.cog_vy, values.cog_vz) == pytest.approx((*vel, 0.0), abs=1e-9)
            assert (values.cog_ax, values.cog_ay, values.cog_az) == pytest.approx((*acc, 0.0), abs=1e-9)
            assert (values.zmp_x, values.zmp_y) == pytest.approx(zmp, abs=1e-9)
            assert (values.dcm_x, values.dcm_y) == pytest.approx(cog + vel / w, abs=1e-9)
            zmp_ref = (values.zmp_ref_x, values.zmp_ref_y)
            feet = {foot.side: _pose(foot) for foot in planner.contact_feet(q)}
            if support == "double":
                assert values.left_foot == pytest.approx(feet["left"], abs=1e-12)
                assert values.right_foot == pytest.approx(feet["right"], abs=1e-12)
                if q < last_phase:
                    share = 3.0 * s**2 - 2.0 * s**3
                    ends_at = ((begins.zmp_x, ends.zmp_x), (begins.zmp_y, ends.zmp_y))
                    transfer = [a + (b - a) * share for a, b in ends_at]
                    assert zmp_ref == pytest.approx(transfer, abs=1e-12)
                references_differ |= math.dist((values.zmp_x, values.zmp_y), zmp_ref) > 1e-5
            else:
                stance, swing = (values.left_foot, values.right_foot) if support == "left" else (
                    values.right_foot, values.left_foot
                )  # fmt: skip
                assert stance == pytest.approx(feet[support], abs=1e-12)
                if s == 0.5:  # mid-swing: at the step height
                    assert swing[2] == pytest.approx(cfg.step_height, abs=1e-12)
                assert zmp_ref == (values.zmp_x, values.zmp_y), "no transfer in a single support"
    assert references_differ, "the walk tells the planned ZMP from the reference ZMP"


def test_the_sample_forms_agree_by_name():
    """The per-tick values, the sample's arrays and a table's columns name the same quantities."""
    assert SampleValues._fields == SAMPLE_FIELDS and len(SAMPLE_FIELDS) == 23
    groups = {
        "cog": ("cog_x", "cog_y", "cog_z"),
        "cog_vel": ("cog_vx", "cog_vy", "cog_vz"),
        "cog_acc": ("cog_ax", "cog_ay", "cog_az"),
        "zmp": ("zmp_x", "zmp_y"),
        "zmp_reference": ("zmp_ref_x", "zmp_ref_y"),
        "left_foot": ("lfoot_x", "lfoot_y", "lfoot_z", "lfoot_yaw"),
        "right_foot": ("rfoot_x", "rfoot_y", "rfoot_z", "rfoot_yaw"),
        "dcm": ("dcm_x", "dcm_y"),
    }
    for group, names in groups.items():
        assert SAMPLE_FIELDS[getattr(SampleColumns, group)] == names
    planner = OnlinePlanner(PlannerConfig(timing=Timing(0.8, 0.2)), TURNING_WALK)
    planner.start(0.0)
    t = planner.phase_start(3) + 0.3
    sample = planner.sample(t)
    values, support, phase = planner.sample_values(t)
    assert (sample.support, sample.phase) == (support, phase)
    for group, names in groups.items():
        assert getattr(sample, group).tolist() == [getattr(values, name) for name in names], group
    assert (values.cog, values.left_foot, values.right_foot) == (
        tuple(sample.cog), tuple(sample.left_foot), tuple(sample.right_foot)
    )  # fmt: skip


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
