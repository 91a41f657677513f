"""One pass over the contacts one physics step left in MuJoCo, for everything a tick needs of them.

Two readers need the contacts of a step: the simulator's truth (:mod:`rtgait.sim.ground_truth`: the full contact
force and moment on each foot, for the ground-truth estimator) and the run's contact record
(:class:`~rtgait.sim.contact.ContactMonitor`: the sole boxes' normal forces, the centre of pressure of those
normal forces, how many corners of each box touch, and whether the legs touch each other). :class:`ContactReader`
decodes a step's contacts once for both (:class:`ContactSums`).

**Contact wrench of a foot.** For every active contact between a geom of the foot's body and a geom outside the
robot (the floor), ``mujoco.mj_contactForce`` gives the force in the contact frame, whose first axis is the normal
pointing from ``geom1`` to ``geom2``; rotated to the world by the contact frame it is the force on ``geom2``
(``f_world = frame^T f_contact``), and its negative the force on ``geom1``. With contact points ``p_i`` and forces
``f_i`` on the foot, the sums are

    F = sum f_i,        M = sum p_i x f_i + t_i                                           (N, N m)

(the moment about the world origin) with ``t_i`` a contact's torsional and rolling torque, rotated likewise (zero
for the condim 3 soles). With MuJoCo's default pyramidal cones, a condim 3 contact's force is decoded as
``mj_contactForce`` does, with the same operations in the same order (so to the bit): its four edge forces
``e_0..e_3`` in ``efc_force`` give the normal ``e_0 + e_1 + e_2 + e_3`` and the tangential components
``(e_0 - e_1) mu_0`` and ``(e_2 - e_3) mu_1``; other contacts are left to MuJoCo.

**The sole boxes' record.** The floor is flat, so a sole contact's normal force is its vertical force, the sum of
its four edge forces; the centre of pressure of the soles is ``(sum p_x f_n, sum p_y f_n) / sum f_n``.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, NamedTuple

import mujoco
import numpy as np

from rtgait.sim.step_snapshot import StepSnapshot

if TYPE_CHECKING:
    from rtgait.sim.model import SimModel

__all__ = ["ContactReader", "ContactSums"]

_new_tuple = tuple.__new__  # a NamedTuple made from a tuple at once, without its generated __new__'s argument parsing


class ContactSums(NamedTuple):
    """A step's contacts, summed (module docstring; world frame, SI units).

    Attributes:
        left_force, right_force: the contact force on each foot ``(fx, fy, fz)`` (N).
        left_moment, right_moment: its moment about the world origin (N m).
        left_contacts, right_contacts: the foot's active contacts with the environment.
        other_contacts: active contacts of the robot with the environment not through a foot.
        sole_moment_x, sole_moment_y: ``sum p_x f_n`` and ``sum p_y f_n`` over the sole boxes' contacts (N m).
        left_normal, right_normal: the normal force on each sole box (N).
        left_corners, right_corners: the sole box's active contacts (its corners touching).
        leg_contacts: active contacts that touch neither sole box (the legs against each other).
    """

    left_force: tuple[float, float, float]
    left_moment: tuple[float, float, float]
    left_contacts: int
    right_force: tuple[float, float, float]
    right_moment: tuple[float, float, float]
    right_contacts: int
    other_contacts: int
    sole_moment_x: float
    sole_moment_y: float
    left_normal: float
    right_normal: float
    left_corners: int
    right_corners: int
    leg_contacts: int


class ContactReader:
    """Decodes a step's contacts (module docstring).

    Args:
        model: the compiled MuJoCo model.
        base_body: body id of the floating base (the robot is its subtree).
        left_site, right_site: site ids at the sole frames; each foot is the body that carries its site.
        left_sole_geom, right_sole_geom: the sole boxes, for the record (-1: none).
        left_geoms, right_geoms: geoms of each foot that may touch the environment; default every geom of the body
            that carries the sole site.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        *,
        base_body: int,
        left_site: int,
        right_site: int,
        left_sole_geom: int = -1,
        right_sole_geom: int = -1,
        left_geoms: Iterable[int] | None = None,
        right_geoms: Iterable[int] | None = None,
    ) -> None:
        self.model = model
        self.base_body, self.left_site, self.right_site = int(base_body), int(left_site), int(right_site)
        # geom id -> 1 (left foot), 2 (right foot), -1 (another part of the robot), 0 (the environment).
        root = int(model.body_rootid[int(base_body)])
        owner = [-1 if int(model.body_rootid[b]) == root else 0 for b in model.geom_bodyid.tolist()]
        for code, site, geoms in ((1, int(left_site), left_geoms), (2, int(right_site), right_geoms)):
            if geoms is None:
                body = int(model.site_bodyid[site])
                geoms = [g for g, b in enumerate(model.geom_bodyid.tolist()) if b == body]
            for g in geoms:
                owner[int(g)] = code
        self._owner = owner
        self._sole_geoms = (int(left_sole_geom), int(right_sole_geom))
        self._force = np.zeros(6)  # the one buffer mj_contactForce writes into (contacts not decoded here)
        self._pyramidal = model.opt.cone == mujoco.mjtCone.mjCONE_PYRAMIDAL

    @classmethod
    def for_sim(cls, sim: SimModel) -> ContactReader:
        """The reader of a :class:`~rtgait.sim.model.SimModel`: its base body, sole sites and sole boxes."""
        return cls(
            sim.model, base_body=sim.base_body, left_site=sim.left_sole_site, right_site=sim.right_sole_site,
            left_sole_geom=sim.left_sole_geom, right_sole_geom=sim.right_sole_geom,
        )  # fmt: skip

    def read(self, data: mujoco.MjData, snapshot: StepSnapshot) -> ContactSums:
        """The sums of the contacts of ``snapshot`` (:func:`~rtgait.sim.step_snapshot.read_snapshot` of ``data``)."""
        model = self.model
        owner = self._owner
        # Per foot: force (3) and moment about the world origin (3), summed over its contacts.
        lx = ly = lz = lmx = lmy = lmz = 0.0
        rx = ry = rz = rmx = rmy = rmz = 0.0
        left_count = right_count = other = 0
        efc, addresses, positions, geoms, frames, dims, frictions, _, _ = snapshot
        left_sole, right_sole = self._sole_geoms
        # The sole boxes' record: sum p f_n over their contacts (x, y), normal force and corners per foot, and the
        # contacts that touch neither box (the legs against each other).
        sx = sy = left_normal = right_normal = 0.0
        left_corners = right_corners = legs = 0
        if addresses:
            for i in range(len(addresses)):
                address = addresses[i]
                if address < 0:  # within the margin but not active: no force
                    continue
                g1, g2 = geoms[i]
                if left_sole in (g1, g2) or right_sole in (g1, g2):
                    normal = efc[address] + efc[address + 1] + efc[address + 2] + efc[address + 3]
                    px, py, _ = positions[i]
                    sx += px * normal
                    sy += py * normal
                    if left_sole in (g1, g2):
                        left_normal += normal
                        left_corners += 1
                    else:
                        right_normal += normal
                        right_corners += 1
                else:
                    legs += 1
                o1, o2 = owner[g1], owner[g2]
                if o1 > 0 and o2 == 0:
                    left, sign = o1 == 1, -1.0  # the force on geom1 is minus the contact force
                elif o2 > 0 and o1 == 0:
                    left, sign = o2 == 1, 1.0
                else:
                    if (o1 != 0) != (o2 != 0):  # the robot, not through a sole, against the environment
                        other += 1
                    continue
                dim = dims[i]
                if self._pyramidal and dim == 3:
                    # mj_contactForce's decoding of a pyramidal cone's four edge forces, in its order of
                    # operations (its result is bit-identical): normal = their sum, tangent_j = (e_2j - e_2j+1) mu_j;
                    # no torsional or rolling torque.
                    mu = frictions[i]
                    a = 0.0 + efc[address] + efc[address + 1] + efc[address + 2] + efc[address + 3]
                    b = (efc[address] - efc[address + 1]) * mu[0]
                    c = (efc[address + 2] - efc[address + 3]) * mu[1]
                    ta = tb = tc = 0.0
                elif self._pyramidal and dim == 1:
                    a, b, c, ta, tb, tc = efc[address], 0.0, 0.0, 0.0, 0.0, 0.0
                else:  # torsional or rolling friction, or an elliptic cone: MuJoCo decodes it
                    buffer = self._force
                    mujoco.mj_contactForce(model, data, i, buffer)
                    a, b, c, ta, tb, tc = buffer.tolist()
                f0, f1, f2, f3, f4, f5, f6, f7, f8 = frames[i]
                fx = sign * (f0 * a + f3 * b + f6 * c)
                fy = sign * (f1 * a + f4 * b + f7 * c)
                fz = sign * (f2 * a + f5 * b + f8 * c)
                px, py, pz = positions[i]
                # The contact's moment about the world origin p x f, plus its own torque (exactly zero without
                # torsional or rolling friction: adding it then changes no bit of the sums, which start at +0.0).
                mx = py * fz - pz * fy
                my = pz * fx - px * fz
                mz = px * fy - py * fx
                if ta != 0.0 or tb != 0.0 or tc != 0.0:
                    mx = mx + sign * (f0 * ta + f3 * tb + f6 * tc)
                    my = my + sign * (f1 * ta + f4 * tb + f7 * tc)
                    mz = mz + sign * (f2 * ta + f5 * tb + f8 * tc)
                if left:
                    lx += fx
                    ly += fy
                    lz += fz
                    lmx += mx
                    lmy += my
                    lmz += mz
                    left_count += 1
                else:
                    rx += fx
                    ry += fy
                    rz += fz
                    rmx += mx
                    rmy += my
                    rmz += mz
                    right_count += 1
        return _new_tuple(ContactSums, (
            (lx, ly, lz), (lmx, lmy, lmz), left_count, (rx, ry, rz), (rmx, rmy, rmz), right_count, other,
            sx, sy, left_normal, right_normal, left_corners, right_corners, legs,
        ))  # fmt: skip
