"""The contacts and sites one physics step left in ``mujoco.MjData``, read once as Python numbers.

A control tick reads the arrays of the state its first physics step started from: the contact record
(:class:`~rtgait.sim.contact.ContactMonitor`) right after that step and, when the period has that one step only, the
simulator's truth at the start of the next tick (:class:`~rtgait.sim.ground_truth.GroundTruthReader`). Reading
MuJoCo's arrays is much of what either costs (each field of the contact list is a new numpy view, and a few dozen
numbers become Python floats), so :func:`read_snapshot` reads them once for both
(:meth:`rtgait.sim.robot.SimRobot.first_substep`).

A snapshot describes the state the step started from (MuJoCo computes the contacts, their forces and the site
poses before it integrates); it stays true only while nothing steps, resets or re-runs the forward dynamics of that
``MjData``.
"""

from __future__ import annotations

from typing import NamedTuple

import mujoco

__all__ = ["StepSnapshot", "read_snapshot"]


class StepSnapshot(NamedTuple):
    """The arrays of one state, as lists (one row per active contact, per site).

    Attributes:
        efc_force: the constraint forces (N, or N m), ``data.efc_force``.
        addresses: each contact's first row in ``efc_force`` (-1: within the margin, not active).
        positions: each contact's point ``(x, y, z)`` (m, world frame).
        geoms: each contact's two geom ids.
        frames: each contact's frame, row-major 3x3 (its first row the normal).
        dims: each contact's dimension (1: frictionless, 3: sliding friction, 4 or 6: torsional or rolling).
        frictions: each contact's five friction coefficients.
        site_positions: every site's position (m, world frame), ``data.site_xpos``.
        site_rotations: every site's row-major orientation, ``data.site_xmat``.
    """

    efc_force: list[float]
    addresses: list[int]
    positions: list[list[float]]
    geoms: list[list[int]]
    frames: list[list[float]]
    dims: list[int]
    frictions: list[list[float]]
    site_positions: list[list[float]]
    site_rotations: list[list[float]]


def read_snapshot(data: mujoco.MjData) -> StepSnapshot:
    """The contact and site arrays of ``data`` now (after a step: of the state that step started from)."""
    sites = data.site_xpos.tolist(), data.site_xmat.tolist()
    if not data.ncon:
        return StepSnapshot([], [], [], [], [], [], [], *sites)
    contacts = data.contact  # its arrays have the ncon active contacts' rows; every step reallocates them
    return StepSnapshot(
        data.efc_force.tolist(), contacts.efc_address.tolist(), contacts.pos.tolist(), contacts.geom.tolist(),
        contacts.frame.tolist(), contacts.dim.tolist(), contacts.friction.tolist(), *sites,
    )  # fmt: skip
