"""What a walking controller measures on the simulated robot, once per control tick, and the landings of its feet.

:class:`SimMeasurer` turns a MuJoCo state into one immutable :class:`Measurement`: per-foot contact wrench, centre of
pressure (CoP), pose and load, the ZMP of both feet together, the centre of mass (COM) and its velocity, the
divergent component of motion (DCM), and the landings detected since the last tick.

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

**Centre of pressure.** In the sole frame (rotation ``R``, axes x forward, y left, z out of the sole), with
``f = R^T F`` and ``t = R^T tau_o``, the point of the sole plane about which the moment has no tangential part is

    cop_local = (-t_y / f_z, t_x / f_z),        cop = o + R (cop_local, 0)               (m)

It is NaN when the foot carries less than :attr:`SimMeasurer.min_force`.

**ZMP of both feet.** The point of the ground plane ``z = h`` (``ground_height``) about which the net moment of all
foot contact forces is vertical: with the moments about ``O = (0, 0, h)``, ``tau_O = sum_feet (o - O) x F + tau_o``,

    zmp = (-tau_O,y / F_z, tau_O,x / F_z)                                                 (m)

which for feet flat on the ground is the force-weighted mean of their CoPs. NaN when no foot carries ``min_force``.

**COM and its velocity** come from MuJoCo, not Pinocchio: ``data.subtree_com`` of the floating base (the robot is
the base's subtree; the world body holds only the floor) is computed by every ``mj_step`` for free, and
``mujoco.mj_subtreeVel`` (a fraction of a microsecond) fills ``subtree_linvel`` from the same kinematics. Both then
belong to exactly the state whose contact forces are read, which a Pinocchio evaluation would only reproduce after
converting ``qpos``/``qvel`` (the model builder takes the inertias from the URDF for both, so they agree to
round-off; the tests check it). A real robot has neither and estimates them; that estimator is not modelled.
The DCM is ``xi = c + c'/w`` with the planner's ``w = sqrt(g / z_c)``, so that it compares with the plan's.

**Which state.** ``mj_step`` computes kinematics, contacts and forces at the state it starts from, then integrates.
Read right after ``mj_step``, every quantity here belongs to that starting state (time ``data.time - timestep``);
after ``mj_forward`` to ``data.time``. The caller stamps the measurement with its tick time ``t``.

**Loaded feet and landings.** A foot becomes *loaded* when its vertical force exceeds ``landing_force`` and
*unloaded* when it falls below ``release_force`` (hysteresis: a foot at the threshold does not chatter). A transition
from unloaded to loaded after at least ``min_unloaded_time`` in the air is a *landing*, reported once with the
measured sole pose at that tick (:class:`Landing`). The default threshold is auto_stabilizer's early touch-down
force, 25 N (``FootStepGenerator.h``, ``contactDetectionThreshold``), scaled to the robot's weight from a 90 kg robot:
2.8 % of the weight; the release force is half of it. A shorter time in the air is a scuff, not a step.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import TYPE_CHECKING, NamedTuple

import mujoco
import numpy as np

from rtgait.core.geometry.footsteps import Footstep, Side
from rtgait.sim.step_snapshot import StepSnapshot, read_snapshot

if TYPE_CHECKING:  # for type hints only: the measurer reads the model by attribute name
    from rtgait.sim.model import SimModel

__all__ = [
    "DEFAULT_LANDING_FRACTION",
    "DEFAULT_MIN_UNLOADED_TIME",
    "FootState",
    "Landing",
    "Measurement",
    "SimMeasurer",
]

DEFAULT_LANDING_FRACTION = 25.0 / (90.0 * 9.81)
"""Landing threshold as a fraction of the robot's weight: auto_stabilizer's 25 N on a 90 kg robot (2.8 %)."""

DEFAULT_MIN_UNLOADED_TIME = 0.05
"""Least time in the air (s) before a load counts as a landing; shorter unloading is a scuff at lift-off."""

_NAN2 = (math.nan, math.nan)
_new_tuple = tuple.__new__  # a NamedTuple made from a tuple at once, without its generated __new__'s argument parsing
_NO_LANDINGS: tuple[Landing, ...] = ()


class FootState(NamedTuple):
    """One foot at one tick (world frame unless said otherwise; SI units).

    Attributes:
        force: contact force of the ground on the foot ``(fx, fy, fz)`` (N).
        torque: its moment about the sole frame origin ``(tx, ty, tz)`` (N m).
        normal_force: ``fz``, the vertical force (N); the floor is horizontal, so this is its normal force.
        cop: centre of pressure on the sole plane ``(x, y)`` (m); NaN below the measurer's ``min_force``.
        cop_local: the same in the sole frame (x forward, y left) (m); NaN likewise.
        pose: sole frame ``(x, y, z, yaw)`` (m, rad), yaw of the sole's x axis projected on the ground.
        roll, pitch: the sole's remaining rotation, ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (rad).
        tilt: angle between the sole normal and the vertical (rad).
        loaded: the load state after hysteresis (module docstring).
        contacts: contact points of the foot with the environment.
    """

    force: tuple[float, float, float]
    torque: tuple[float, float, float]
    normal_force: float
    cop: tuple[float, float]
    cop_local: tuple[float, float]
    pose: tuple[float, float, float, float]
    roll: float
    pitch: float
    tilt: float
    loaded: bool
    contacts: int

    def footstep(self, side: Side) -> Footstep:
        """The foot's pose as a planner footprint (x, y, yaw)."""
        x, y, _, yaw = self.pose
        return Footstep(x, y, yaw, side)


class Landing(NamedTuple):
    """A swing foot touched down: its measured sole pose at the tick the load crossed the landing threshold.

    Attributes:
        t: the tick's time (s).
        side: ``"left"`` or ``"right"``.
        x, y, z, yaw: sole frame position (m) and heading (rad).
        roll, pitch: the sole's remaining rotation (rad).
        normal_force: vertical force on the foot at that tick (N).
    """

    t: float
    side: Side
    x: float
    y: float
    z: float
    yaw: float
    roll: float
    pitch: float
    normal_force: float

    def footstep(self) -> Footstep:
        """Where it landed, as a planner footprint."""
        return Footstep(self.x, self.y, self.yaw, self.side)


class Measurement(NamedTuple):
    """Everything measured at one control tick (world frame, SI units); see the module docstring.

    Attributes:
        t: the tick's time (s), as given by the caller.
        com: centre of mass ``(x, y, z)`` (m).
        com_vel: its velocity (m/s).
        dcm: horizontal divergent component of motion ``c + c'/w`` (m).
        zmp: ZMP of both feet on the ground plane (m); NaN when no foot carries ``min_force``.
        normal_force: vertical force on both feet together (N).
        left, right: the feet.
        landings: landings detected at this tick (usually none).
        other_contacts: contacts of the robot with the environment that are not on a sole (a knee, a hand): 0
            while walking.
    """

    t: float
    com: tuple[float, float, float]
    com_vel: tuple[float, float, float]
    dcm: tuple[float, float]
    zmp: tuple[float, float]
    normal_force: float
    left: FootState
    right: FootState
    landings: tuple[Landing, ...]
    other_contacts: int

    @property
    def support(self) -> str:
        """Which feet are loaded: ``"double"``, ``"left"``, ``"right"`` or ``"none"``."""
        left, right = self.left.loaded, self.right.loaded
        if left and right:
            return "double"
        return "left" if left else ("right" if right else "none")


class SimMeasurer:
    """Per-tick measurement of a simulated humanoid (module docstring).

    Args:
        model: the compiled MuJoCo model.
        base_body: body id of the floating base (the robot is its subtree).
        left_site, right_site: site ids at the sole frames (x forward, z out of the sole).
        omega: pendulum frequency ``w = sqrt(g / z_c)`` of the planner (1/s), for the DCM.
        left_geoms, right_geoms: geoms of each foot that may touch the environment; default every geom of the body
            that carries the sole site.
        mass: robot mass (kg) for the default thresholds; default the base subtree's mass in the model.
        landing_force: load at which a foot counts as loaded and, after flight, as landed (N); default
            :data:`DEFAULT_LANDING_FRACTION` of the weight.
        release_force: load below which a foot counts as unloaded (N); default half of ``landing_force``.
        min_unloaded_time: least flight time of a landing (s).
        min_force: least load (N) for which a CoP or a ZMP is given; default 0.1 % of the weight.
        ground_height: height of the ground plane of the ZMP (m).

    Stateful only through the feet's load states (:meth:`reset` clears them); :meth:`measure` allocates tuples of
    Python floats and no numpy array.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        *,
        base_body: int,
        left_site: int,
        right_site: int,
        omega: float,
        left_geoms: Iterable[int] | None = None,
        right_geoms: Iterable[int] | None = None,
        mass: float | None = None,
        landing_force: float | None = None,
        release_force: float | None = None,
        min_unloaded_time: float = DEFAULT_MIN_UNLOADED_TIME,
        min_force: float | None = None,
        ground_height: float = 0.0,
    ) -> None:
        if not (math.isfinite(omega) and omega > 0.0):
            raise ValueError(f"omega must be > 0 (1/s), got {omega}")
        self.model = model
        self.base_body = int(base_body)
        self.left_site, self.right_site = int(left_site), int(right_site)
        self.omega = float(omega)
        self.mass = float(model.body_subtreemass[self.base_body]) if mass is None else float(mass)
        weight = self.mass * float(-model.opt.gravity[2])
        if not weight > 0.0:
            raise ValueError(f"the robot's weight must be > 0 N, got {weight} (mass {self.mass} kg)")
        self.weight = weight
        self.landing_force = DEFAULT_LANDING_FRACTION * weight if landing_force is None else float(landing_force)
        self.release_force = 0.5 * self.landing_force if release_force is None else float(release_force)
        if not 0.0 <= self.release_force <= self.landing_force:
            raise ValueError(
                f"release_force must be within [0, landing_force = {self.landing_force:g}] N, got {self.release_force}"
            )
        if not (math.isfinite(min_unloaded_time) and min_unloaded_time >= 0.0):
            raise ValueError(f"min_unloaded_time must be a duration >= 0 s, got {min_unloaded_time}")
        self.min_unloaded_time = float(min_unloaded_time)
        self.min_force = 1e-3 * weight if min_force is None else float(min_force)
        self.ground_height = float(ground_height)

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
        self.reset()

    @classmethod
    def for_sim(cls, sim: SimModel, omega: float | None = None, **options: float | Iterable[int] | None) -> SimMeasurer:
        """A measurer for a :class:`~rtgait.sim.model.SimModel` (its base body and sole sites; the mass of its
        Pinocchio robot). ``omega`` defaults to the robot description's walking COM height."""
        if omega is None:
            omega = math.sqrt(float(-sim.model.opt.gravity[2]) / sim.robot.description.cog_height)
        options.setdefault("mass", sim.robot.mass)
        return cls(
            sim.model,
            base_body=sim.base_body,
            left_site=sim.left_sole_site,
            right_site=sim.right_sole_site,
            omega=omega,
            **options,  # type: ignore[arg-type]
        )

    def reset(self) -> None:
        """Forget the feet's load states: the next :meth:`measure` takes them as they are, without landings."""
        self._loaded = [False, False]
        self._unloaded_since = [-math.inf, -math.inf]
        self._primed = False

    def measure(
        self,
        data: mujoco.MjData,
        t: float | None = None,
        snapshot: StepSnapshot | None = None,
        velocities: bool = False,
    ) -> Measurement:
        """The measurement of ``data`` (see the module docstring for which state that is), stamped ``t`` (s;
        default ``data.time``); ``snapshot``: its contact and site arrays already read
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

        h = self.ground_height
        min_force = self.min_force
        left_foot, left_landing = self._foot(
            0, t, lx, ly, lz, lmx, lmy, lmz, left_count, sites_position[self.left_site],
            sites_rotation[self.left_site],
        )  # fmt: skip
        right_foot, right_landing = self._foot(
            1, t, rx, ry, rz, rmx, rmy, rmz, right_count, sites_position[self.right_site],
            sites_rotation[self.right_site],
        )  # fmt: skip
        landings = _NO_LANDINGS
        if left_landing is not None or right_landing is not None:
            landings = tuple(landing for landing in (left_landing, right_landing) if landing is not None)
        self._primed = True
        # ZMP moments about (0, 0, h): (o - O) x F + tau_o per foot, in the order the feet are summed.
        zmp_mx = zmp_my = total = 0.0
        for foot in (left_foot, right_foot):
            ox, oy, oz, _ = foot.pose
            fx, fy, fz = foot.force
            tx, ty, _ = foot.torque
            zmp_mx += (oy * fz - (oz - h) * fy) + tx
            zmp_my += ((oz - h) * fx - ox * fz) + ty
            total += fz
        zmp = (-zmp_my / total, zmp_mx / total) if total > min_force else _NAN2
        if not velocities:
            mujoco.mj_subtreeVel(model, data)
        if data is not self._rows_of:  # the base's rows of this data's fixed-size arrays, as views kept
            base = self.base_body
            self._rows_of, self._base_rows = data, (data.subtree_com[base], data.subtree_linvel[base])
        com_row, linvel_row = self._base_rows
        cx, cy, cz = com_row.tolist()
        vx, vy, vz = linvel_row.tolist()
        w = self.omega
        return _new_tuple(
            Measurement,
            (t, (cx, cy, cz), (vx, vy, vz), (cx + vx / w, cy + vy / w), zmp, total, left_foot, right_foot, landings,
             other),
        )  # fmt: skip

    def _foot(
        self, index: int, t: float, fx: float, fy: float, fz: float, mx: float, my: float, mz: float, count: int,
        position: list[float], m: list[float],
    ) -> tuple[FootState, Landing | None]:
        """One foot's state from its summed force ``(fx, fy, fz)`` (N) and moment about the world origin (N m), and
        its sole frame's position and row-major rotation; and its landing at this tick, if it landed."""
        ox, oy, oz = position
        # Moment about the sole origin: tau_o = M - o x F.
        tx = mx - (oy * fz - oz * fy)
        ty = my - (oz * fx - ox * fz)
        tz = mz - (ox * fy - oy * fx)
        # The sole frame's components: R^T v, R row-major (m[3 r + c] = R[r][c]).
        m0, m1, m2, m3, m4, m5, m6, m7, m8 = m
        lfz = m2 * fx + m5 * fy + m8 * fz
        if lfz > self.min_force:
            ltx = m0 * tx + m3 * ty + m6 * tz
            lty = m1 * tx + m4 * ty + m7 * tz
            cx, cy = -lty / lfz, ltx / lfz
            cop_local = (cx, cy)
            cop = (ox + m0 * cx + m1 * cy, oy + m3 * cx + m4 * cy)
        else:
            cop_local = cop = _NAN2
        # R = Rz(yaw) Ry(pitch) Rx(roll); the tilt is the angle between the sole normal and the vertical.
        yaw = math.atan2(m3, m0)
        # max(-1, min(1, v)) written as the builtins decide it (`b if b < a else a` for min(a, b), `b if b > a
        # else a` for max: the same result, NaN included), a call each costing more than the trigonometry.
        sine = -m6 if -m6 < 1.0 else 1.0
        pitch = math.asin(sine if sine > -1.0 else -1.0)
        roll = math.atan2(m7, m8)
        cosine = m8 if m8 < 1.0 else 1.0
        tilt = math.acos(cosine if cosine > -1.0 else -1.0)
        loaded = self._update_load(index, fz, t)
        landing = None
        if loaded is None:
            loaded = True
            side: Side = "left" if index == 0 else "right"
            landing = _new_tuple(Landing, (t, side, ox, oy, oz, yaw, roll, pitch, fz))
        foot = _new_tuple(
            FootState,
            ((fx, fy, fz), (tx, ty, tz), fz, cop, cop_local, (ox, oy, oz, yaw), roll, pitch, tilt, loaded, count),
        )
        return foot, landing

    def _update_load(self, index: int, fz: float, t: float) -> bool | None:
        """The foot's load state after this tick's force ``fz`` (N); ``None`` for a landing (then loaded)."""
        loaded = self._loaded[index]
        if loaded:
            if fz < self.release_force:
                self._loaded[index] = False
                self._unloaded_since[index] = t
                return False
            return True
        if fz > self.landing_force:
            self._loaded[index] = True
            if self._primed and t - self._unloaded_since[index] >= self.min_unloaded_time:
                return None
            return True
        if not self._primed:
            self._unloaded_since[index] = t
        return False
