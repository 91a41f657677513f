"""The simulator's ground truth of a walking robot, read off MuJoCo once per control tick: the contact forces summed
on each sole with the soles' poses, the centre of mass (COM) and its velocity (:class:`~rtgait.interface.truth.
GroundTruth`); the ground-truth estimator (:mod:`rtgait.estimation.ground_truth`) turns it into the walking state.

The contacts are decoded by :mod:`rtgait.sim.contact_reading` (the force and moment summed over each foot).

**COM and its velocity** come from MuJoCo, not Pinocchio: ``data.subtree_com`` of the floating base (the robot is
the base's subtree; the world body holds only the floor) is computed by every ``mj_step`` for free, and
``mujoco.mj_subtreeVel`` (a fraction of a microsecond) fills ``subtree_linvel`` from the same kinematics. Both then
belong to exactly the state whose contact forces are read, which a Pinocchio evaluation would only reproduce after
converting ``qpos``/``qvel`` (the model builder takes the inertias from the URDF for both, so they agree to
round-off; the tests check it). A real robot has neither: it estimates them from its sensors.

**Which state.** ``mj_step`` computes kinematics, contacts and forces at the state it starts from, then integrates.
Read right after ``mj_step``, every quantity here belongs to that starting state (time ``data.time - timestep``);
after ``mj_forward`` to ``data.time``. The caller stamps the truth with its tick time ``t``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from rtgait.interface.truth import FootContact, GroundTruth
from rtgait.sim.contact_reading import ContactReader, ContactSums
from rtgait.sim.step_snapshot import StepSnapshot, read_snapshot

if TYPE_CHECKING:
    from rtgait.sim.model import SimModel

__all__ = ["GroundTruthReader"]

_new_tuple = tuple.__new__  # a NamedTuple made from a tuple at once, without its generated __new__'s argument parsing


class GroundTruthReader:
    """The ground truth of a simulated humanoid at each tick (module docstring).

    Args:
        contacts: the reader of its contacts; its base body and sole sites are the robot's.

    Stateless but for views of the last ``MjData`` read; :meth:`read` allocates tuples of Python floats and no numpy
    array.
    """

    def __init__(self, contacts: ContactReader) -> None:
        self.contacts = contacts
        self.model = contacts.model
        self.base_body, self.left_site, self.right_site = contacts.base_body, contacts.left_site, contacts.right_site
        self._rows_of: mujoco.MjData | None = None
        self._base_rows: tuple[np.ndarray, np.ndarray] = (np.zeros(3), np.zeros(3))

    @classmethod
    def for_sim(cls, sim: SimModel) -> GroundTruthReader:
        """The reader of a :class:`~rtgait.sim.model.SimModel`."""
        return cls(ContactReader.for_sim(sim))

    def read(
        self,
        data: mujoco.MjData,
        t: float | None = None,
        snapshot: StepSnapshot | None = None,
        velocities: bool = False,
        sums: ContactSums | None = None,
    ) -> GroundTruth:
        """The truth of ``data`` (see the module docstring for which state that is), stamped ``t`` (s; default
        ``data.time``); ``snapshot``: its contact and site arrays already read
        (:func:`~rtgait.sim.step_snapshot.read_snapshot`, of this same state); ``velocities``: whether
        ``mj_subtreeVel`` has already been run on this state (it is not run again); ``sums``: its contacts already
        decoded (:class:`~rtgait.sim.contact_reading.ContactReader`)."""
        t = float(data.time) if t is None else float(t)
        if snapshot is None:
            snapshot = read_snapshot(data)
        if sums is None:
            sums = self.contacts.read(data, snapshot)
        sites_position, sites_rotation = snapshot.site_positions, snapshot.site_rotations
        if not velocities:
            mujoco.mj_subtreeVel(self.model, data)
        if data is not self._rows_of:  # the base's rows of this data's fixed-size arrays, as views kept
            base = self.base_body
            self._rows_of, self._base_rows = data, (data.subtree_com[base], data.subtree_linvel[base])
        com_row, linvel_row = self._base_rows
        cx, cy, cz = com_row.tolist()
        vx, vy, vz = linvel_row.tolist()
        left = _new_tuple(FootContact, (
            sums.left_force, sums.left_moment, sums.left_contacts, sites_position[self.left_site],
            sites_rotation[self.left_site],
        ))  # fmt: skip
        right = _new_tuple(FootContact, (
            sums.right_force, sums.right_moment, sums.right_contacts, sites_position[self.right_site],
            sites_rotation[self.right_site],
        ))  # fmt: skip
        return _new_tuple(GroundTruth, (t, (cx, cy, cz), (vx, vy, vz), left, right, sums.other_contacts))
