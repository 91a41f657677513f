"""The simulator's ground truth: the channel that only evaluation and ``--state truth`` read, never a robot's.

A simulator knows what a robot can only estimate: the centre of mass (COM) and its velocity, the contact forces on
each sole and the soles' poses. They reach a controller only through an estimator that says it reads them
(:class:`rtgait.estimation.ground_truth.GroundTruthEstimator`), so a controller fed from sensors cannot read them by
accident. World frame, z up, SI units.
"""

from __future__ import annotations

from typing import NamedTuple

__all__ = ["FootContact", "GroundTruth"]


class FootContact(NamedTuple):
    """The contact forces on one foot, summed over its contact points, and its sole frame's pose.

    Attributes:
        force: ``(fx, fy, fz)``, the sum of the contact forces on the foot (N).
        moment: their moment about the world origin, ``sum p_i x f_i`` plus the contacts' own torques (N m).
        contacts: how many contact points carry them.
        sole_position: the sole frame's origin (m).
        sole_rotation: the sole frame's orientation, a row-major 3x3 matrix (x forward, y left, z out of the sole).
    """

    force: tuple[float, float, float]
    moment: tuple[float, float, float]
    contacts: int
    sole_position: list[float]
    sole_rotation: list[float]


class GroundTruth(NamedTuple):
    """The simulator's truth at one tick.

    Attributes:
        t: the tick's time (s).
        com: the centre of mass ``(x, y, z)`` (m).
        com_vel: its velocity (m/s).
        left, right: the feet's contacts.
        other_contacts: contacts of the robot with the environment that are not on a sole (a knee, a hand).
    """

    t: float
    com: tuple[float, float, float]
    com_vel: tuple[float, float, float]
    left: FootContact
    right: FootContact
    other_contacts: int
