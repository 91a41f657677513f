"""The simulator's ground truth of a walking robot, read off MuJoCo once per control tick: the contact forces summed
on each sole with the soles' poses, the centre of mass (COM) and its velocity (:class:`~rtgait.interface.truth.
GroundTruth`); the ground-truth estimator (:mod:`rtgait.estimation.ground_truth`) turns it into the walking state.

**Contact wrench of a foot.** For every active contact between a geom of the foot's body and a geom outside the
robot (the floor), ``mujoco.mj_contactForce`` gives the force in the contact frame, whose first axis is the normal
pointing from ``geom1`` to ``geom2``; rotated to the world by the contact frame it is the force on ``geom2``
(``f_world = frame^T f_contact``), and its negative the force on ``geom1``. With contact points ``p_i`` and forces
``f_i`` on the foot, the wrench at the sole frame origin ``o`` (the sole point, in the world frame) is

    F = sum f_i,        tau_o = sum (p_i - o) x f_i + t_i                                (N, N m)

with ``t_i`` a contact's torsional and rolling torque, rotated likewise (zero for the condim 3 soles). This is what a
6-axis force sensor in the ankle would report, moved to the sole point. With MuJoCo's default pyramidal cones, a
condim 3 contact's force is decoded here as ``mj_contactForce`` does, with the same operations in the same order
(so to the bit): its four edge forces ``e_0..e_3`` in ``efc_force`` give the normal ``e_0 + e_1 + e_2 + e_3`` and
the tangential components ``(e_0 - e_1) mu_0`` and ``(e_2 - e_3) mu_1``; other contacts are left to MuJoCo.

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

from collections.abc import Iterable
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from rtgait.interface.truth import FootContact, GroundTruth
from rtgait.sim.step_snapshot import StepSnapshot, read_snapshot

if TYPE_CHECKING:  # the model module is being rewritten: only its attribute names are relied on
    from rtgait.sim.model import SimModel

__all__ = ["GroundTruthReader"]

_new_tuple = tuple.__new__  # a NamedTuple made from a tuple at once, without its generated __new__'s argument parsing


class GroundTruthReader:
    """The ground truth of a simulated humanoid at each tick (module docstring).

    Args:
        model: the compiled MuJoCo model.
        base_body: body id of the floating base (the robot is its subtree).
        left_site, right_site: site ids at the sole frames (x forward, z out of the sole).
        left_geoms, right_geoms: geoms of each foot that may touch the environment; default every geom of the body
            that carries the sole site.

    Stateless but for views of the last ``MjData`` read; :meth:`read` allocates tuples of Python floats and no numpy
    array.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        *,
        base_body: int,
        left_site: int,
        right_site: int,
        left_geoms: Iterable[int] | None = None,
        right_geoms: Iterable[int] | None = None,
    ) -> None:
        self.model = model
        self.base_body = int(base_body)
        self.left_site, self.right_site = int(left_site), int(right_site)
        # geom id -> 1 (left foot), 2 (right foot), -1 (another part of the robot), 0 (the environment).
        root = int(model.body_rootid[self.base_body])
        owner = [-1 if int(model.body_rootid[b]) == root else 0 for b in model.geom_bodyid.tolist()]
        for code, site, geoms in ((1, self.left_site, left_geoms), (2, self.right_site, right_geoms)):
            if geoms is None:
                body = int(model.site_bodyid[site])
                geoms = [g for g, b in enumerate(model.geom_bodyid.tolist()) if b == body]
            for g in geoms:
                owner[int(g)] = code
        self._owner = owner
        self._force = np.zeros(6)  # the one buffer mj_contactForce writes into (contacts not decoded here)
        self._pyramidal = model.opt.cone == mujoco.mjtCone.mjCONE_PYRAMIDAL
        self._rows_of: mujoco.MjData | None = None
        self._base_rows: tuple[np.ndarray, np.ndarray] = (self._force, self._force)

    @classmethod
    def for_sim(cls, sim: SimModel) -> GroundTruthReader:
        """The reader of a :class:`~rtgait.sim.model.SimModel`: its base body and sole sites."""
        return cls(sim.model, base_body=sim.base_body, left_site=sim.left_sole_site, right_site=sim.right_sole_site)

    def read(
        self,
        data: mujoco.MjData,
        t: float | None = None,
        snapshot: StepSnapshot | None = None,
        velocities: bool = False,
    ) -> GroundTruth:
        """The truth of ``data`` (see the module docstring for which state that is), stamped ``t`` (s; default
        ``data.time``); ``snapshot``: its contact and site arrays already read
        (:func:`~rtgait.sim.step_snapshot.read_snapshot`, of this same state); ``velocities``: whether
        ``mj_subtreeVel`` has already been run on this state (it is not run again)."""
        model = self.model
        t = float(data.time) if t is None else float(t)
        owner = self._owner
        # Per foot: force (3) and moment about the world origin (3), summed over its contacts.
        lx = ly = lz = lmx = lmy = lmz = 0.0
        rx = ry = rz = rmx = rmy = rmz = 0.0
        left_count = right_count = other = 0
        if snapshot is None:
            snapshot = read_snapshot(data)
        efc, addresses, positions, geoms, frames, dims, frictions, sites_position, sites_rotation = snapshot
        if addresses:
            for i in range(len(addresses)):
                address = addresses[i]
                if address < 0:  # within the margin but not active: no force
                    continue
                g1, g2 = geoms[i]
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

        if not velocities:
            mujoco.mj_subtreeVel(model, data)
        if data is not self._rows_of:  # the base's rows of this data's fixed-size arrays, as views kept
            base = self.base_body
            self._rows_of, self._base_rows = data, (data.subtree_com[base], data.subtree_linvel[base])
        com_row, linvel_row = self._base_rows
        cx, cy, cz = com_row.tolist()
        vx, vy, vz = linvel_row.tolist()
        left = _new_tuple(
            FootContact,
            ((lx, ly, lz), (lmx, lmy, lmz), left_count, sites_position[self.left_site], sites_rotation[self.left_site]),
        )
        right = _new_tuple(
            FootContact,
            ((rx, ry, rz), (rmx, rmy, rmz), right_count, sites_position[self.right_site],
             sites_rotation[self.right_site]),
        )  # fmt: skip
        return _new_tuple(GroundTruth, (t, (cx, cy, cz), (vx, vy, vz), left, right, other))
