"""Swing-foot placement feedback on a synthetic robot: a stance leg that gives by a known angle turns the whole body
about the stance sole, the swinging foot with it, and a swing leg that lags its command; the feedback brings the
measured foot onto its target, by the offset the geometry says."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.control.swing_feedback import SwingFeedback, SwingFeedbackSettings
from rtgait.estimation.state import FootState

DT = 0.002  # s, G1's control period
LAG = 0.02  # s, the swing leg's servo lag (first order)


def foot(position, loaded: bool) -> FootState:
    """A measured foot at ``position`` (x, y, z), m."""
    fz = 300.0 if loaded else 0.0
    x, y, z = position
    return FootState((0.0, 0.0, fz), (0.0, 0.0, 0.0), fz, (0.0, 0.0), (0.0, 0.0), (x, y, z, 0.0), 0.0, 0.0, 0.0,
                     loaded, 4 if loaded else 0)  # fmt: skip


def rot_x(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def swing(deflection: float, seconds: float, feedback: SwingFeedback | None, target=(0.1, 0.2, 0.03)):
    """The left foot in the air for ``seconds`` over the right, standing at the origin, whose leg gives by
    ``deflection`` (rad, a roll about the stance sole): the real foot is the rotated, lagged command. Returns the
    real foot's last position (m) and the target."""
    target = np.array(target)
    right = (0.0, 0.0, 0.0, 0.0)
    lagged = np.zeros(3)  # the swing leg's position in the stance leg's frame
    real = np.zeros(3)
    rotation, alpha = rot_x(deflection), -math.expm1(-DT / LAG)
    for _ in range(round(seconds / DT)):
        command = (*target, 0.0)
        if feedback is not None:
            command, _ = feedback.update(command, right, (foot(real, False), foot((0.0, 0.0, 0.0), True)), "right")
        lagged += alpha * (np.array(command[:3]) - lagged)
        real = rotation @ lagged
    return real, target


def test_the_swing_foot_of_a_deflected_stance_leg_lands_on_its_target():
    """A stance hip that gives 3 degrees in roll puts the swing foot ``|R p - p|`` (over 1 cm here) off its target
    without the feedback; with it the foot is on its target within 0.5 mm after 0.5 s, its offset ``R^-1 p - p``."""
    deflection = math.radians(3.0)
    open_loop, target = swing(deflection, 0.5, None)
    expected_miss = np.linalg.norm(rot_x(deflection) @ target - target)
    assert expected_miss > 0.01
    assert np.linalg.norm(open_loop - target) == pytest.approx(expected_miss, rel=1e-6)
    feedback = SwingFeedback(DT)
    closed, _ = swing(deflection, 0.5, feedback)
    assert np.linalg.norm(closed - target) < 5e-4
    offset = np.array(feedback.offsets[0])
    assert np.allclose(offset, rot_x(-deflection) @ target - target, atol=5e-4)
    assert feedback.offsets[1] == (0.0, 0.0, 0.0)  # the stance foot gets none


def test_the_offset_is_clamped_on_each_axis():
    """A deflection whose correction exceeds ``max_offset`` gets that much and no more."""
    feedback = SwingFeedback(DT, SwingFeedbackSettings(max_offset=0.01))
    swing(math.radians(10.0), 0.5, feedback)  # needs some 10 cm in z at 0.2 m out
    ox, oy, oz = feedback.offsets[0]
    assert max(abs(ox), abs(oy), abs(oz)) == pytest.approx(0.01)
    assert all(abs(v) <= 0.01 for v in (ox, oy, oz))


def test_a_loaded_foot_returns_its_offset_over_the_return_time():
    """Once the foot carries load, its offset decays as ``exp(-t / T_r)``; nothing is learnt in double support."""
    feedback = SwingFeedback(DT, SwingFeedbackSettings(return_time=0.5))
    swing(math.radians(3.0), 0.5, feedback)
    start = np.array(feedback.offsets[0])
    target = (0.1, 0.2, 0.0, 0.0)
    for _ in range(round(0.5 / DT)):  # standing 1 cm off its target: a loaded foot is not steered
        feedback.update(target, (0.0, 0.0, 0.0, 0.0), (foot((0.1, 0.21, 0.0), True), foot((0, 0, 0), True)), "double")
    assert np.allclose(feedback.offsets[0], start * math.exp(-1.0), rtol=1e-9, atol=1e-12)


def test_a_bad_measurement_holds_the_offset_and_settings_are_checked():
    feedback = SwingFeedback(DT)
    swing(math.radians(3.0), 0.2, feedback)
    held = feedback.offsets
    feedback.update(
        (0.1, 0.2, 0.03, 0.0), (0, 0, 0, 0), (foot((math.nan, 0, 0), False), foot((0, 0, 0), True)), "right"
    )
    assert feedback.offsets == held
    for bad in ({"time_constant": 0.0}, {"max_offset": -0.01}, {"return_time": math.inf}, {"max_offset": True}):
        with pytest.raises(ValueError, match="SwingFeedbackSettings"):
            SwingFeedbackSettings(**bad)
    with pytest.raises(ValueError, match="dt"):
        SwingFeedback(0.0)


def test_the_option_is_off_by_default_and_checked():
    """Off unless asked for (``[control] swing_feedback = T``); a negative time constant is refused."""
    from rtgait.control.settings import ControllerOptions

    assert ControllerOptions().swing_feedback == 0.0
    assert ControllerOptions(swing_feedback=0.05).swing_feedback == 0.05
    with pytest.raises(ValueError, match="swing_feedback"):
        ControllerOptions(swing_feedback=-1.0)
