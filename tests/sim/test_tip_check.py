"""The tip check compares a loaded sole's tilt with the tilt it was commanded (rtgait.sim.contact): a sole rolled onto
its toe as its toe-off commands, or lagging behind it, has not tipped; one rolled beyond it, or sideways, has.

Independent truth: the soles' orientations are built here from elementary rotations, ``Rz(yaw) Ry(pitch) Rx(roll)``
(the IK's convention for a tilted foot target), and the angles between them are known by construction.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

pytest.importorskip("mujoco")

from rtgait.sim.contact import ContactMonitor, FallLimits, commanded_normal, tip_cosine
from rtgait.sim.contact_reading import ContactSums

TIP = FallLimits().tip_angle
TOE_OFF = 0.3  # rad, heel up


def _rotation(yaw: float = 0.0, pitch: float = 0.0, roll: float = 0.0) -> np.ndarray:
    cy, sy = math.cos(yaw), math.sin(yaw)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cr, sr = math.cos(roll), math.sin(roll)
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    return rz @ ry @ rx


@pytest.mark.parametrize("yaw, pitch, roll", [(0.0, 0.0, 0.0), (0.4, 0.3, 0.0), (-1.2, -0.17, 0.05)])
def test_the_commanded_normal_is_the_third_column_of_the_target_s_rotation(yaw, pitch, roll) -> None:
    want = _rotation(yaw, pitch, roll)[:, 2]
    assert commanded_normal((0.1, 0.2, 0.0, yaw, pitch, roll)) == pytest.approx(want, abs=1e-12)
    assert commanded_normal((0.1, 0.2, 0.0, yaw)) == (0.0, 0.0, 1.0), "a 4-element target is a level sole"


def _monitor() -> ContactMonitor:
    data = SimpleNamespace(qpos=np.array([0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0]))
    return ContactMonitor(data, 0, 1, 4, 1.0, FallLimits(), 0.001)  # type: ignore[arg-type]


def _tipped(target: tuple[float, ...], toe_off: float, sole: np.ndarray) -> bool:
    """Whether a left sole of orientation ``sole`` carrying all the load tips, commanded ``target`` with its toe-off
    pitch ``toe_off`` (the right foot level and unloaded)."""
    monitor = _monitor()
    monitor.command(target, (0.0, -0.2, 0.0, 0.0), (toe_off, 0.0))
    sums = ContactSums((0.0, 0.0, 800.0), (0.0, 0.0, 0.0), 4, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0, 0,
                       0.0, 0.0, 800.0, 0.0, 2, 0, 0)  # fmt: skip
    positions = [[0.0, 0.1, 0.0], [0.0, -0.1, 0.0]]
    snapshot = SimpleNamespace(
        site_positions=positions, site_rotations=[sole.ravel().tolist(), [1, 0, 0, 0, 1, 0, 0, 0, 1]]
    )
    monitor.record(0, 0.0, sums, snapshot)  # type: ignore[arg-type]
    return monitor.tip_time is not None


def test_a_sole_rolled_onto_its_toe_as_commanded_has_not_tipped() -> None:
    toe_off = (0.0, 0.1, 0.0, 0.3, TOE_OFF, 0.0)  # heading 0.3 rad, the heel up by the toe-off's pitch
    assert not _tipped(toe_off, TOE_OFF, _rotation(0.3, TOE_OFF))
    assert not _tipped(toe_off, TOE_OFF, _rotation(0.3, 0.5 * TOE_OFF)), "behind its toe-off (servo lag)"
    assert not _tipped(toe_off, TOE_OFF, _rotation(0.3, 0.0)), "still flat on its foothold"


def test_a_sole_rolled_beyond_its_commanded_toe_off_or_sideways_has_tipped() -> None:
    toe_off = (0.0, 0.1, 0.0, 0.3, TOE_OFF, 0.0)
    assert _tipped(toe_off, TOE_OFF, _rotation(0.3, TOE_OFF + 1.5 * TIP)), "beyond the commanded heel lift"
    assert _tipped(toe_off, TOE_OFF, _rotation(0.3, -1.5 * TIP)), "onto its heel instead"
    assert _tipped(toe_off, TOE_OFF, _rotation(0.3, 0.5 * TOE_OFF, 1.5 * TIP)), "onto its outer edge"
    assert not _tipped(toe_off, TOE_OFF, _rotation(0.3, TOE_OFF + 0.5 * TIP)), "within the tip angle of it"


def test_without_a_toe_off_the_tilt_is_measured_from_the_commanded_tilt() -> None:
    level = (0.0, 0.1, 0.0, 0.0)
    assert not _tipped(level, 0.0, _rotation(0.0, 0.5 * TIP))
    assert _tipped(level, 0.0, _rotation(0.0, 1.5 * TIP)), "a level command: the tilt from level, as before"
    assert _tipped(level, 0.0, _rotation(0.0, TOE_OFF)), "a roll onto the toe nobody planned"
    ramp = (0.0, 0.1, 0.0, 0.0, -math.radians(10.0), 0.0)  # a sloped foothold's surface, no toe-off
    assert not _tipped(ramp, 0.0, _rotation(0.0, -math.radians(10.0)))
    assert _tipped(ramp, 0.0, _rotation(0.0, -math.radians(10.0) + 1.5 * TIP)), "onto its heel on the ramp"
    assert _tipped(ramp, 0.0, _rotation(0.0, 0.0)), "level on a ramp: on an edge"


def test_the_cosine_is_the_angle_to_the_nearest_tilt_between_the_foothold_and_the_toe_off() -> None:
    start, end = _rotation(0.0, 0.0)[:, 2], _rotation(0.0, TOE_OFF)[:, 2]
    sideways = _rotation(0.0, 0.1, 0.04)  # 0.04 rad of roll off the arc of pitches
    assert math.acos(tip_cosine(sideways.ravel(), end, start)) == pytest.approx(0.04, abs=1e-9)
    beyond = _rotation(0.0, TOE_OFF + 0.07)
    assert math.acos(tip_cosine(beyond.ravel(), end, start)) == pytest.approx(0.07, abs=1e-9)
    assert tip_cosine(beyond.ravel(), end) == pytest.approx(math.cos(0.07), abs=1e-12)
