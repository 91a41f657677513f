"""The robot's contacts with the world in the closed loop: what is measured of them each control tick, when the
robot has fallen, tipped over or landed a step, and the external contact forces (pushes) applied to it.

:class:`ContactMonitor` keeps the per-tick record of a run: the ZMP (the centre of pressure of the soles' normal forces,
decoded by :mod:`rtgait.sim.contact_reading`), the force on each foot, how many corners of each sole box touch, how far
each sole is tilted, whether the legs touch each other, and it decides when the robot has fallen (:class:`FallLimits`)
or tipped over (a loaded foot rolled onto an edge of its sole: tilted beyond :attr:`FallLimits.tip_angle` from the
tilt it was commanded, :func:`tip_cosine`). :class:`Landings` counts the steps whose foot touched
down in time. :class:`~rtgait.core.push.Push` is a force from outside (a hand on the pelvis), applied by
:class:`Pushes`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from rtgait.core.geometry.terrain import Terrain
from rtgait.core.push import Push
from rtgait.sim.contact_reading import ContactSums
from rtgait.sim.row_packing import row_packer
from rtgait.sim.step_snapshot import StepSnapshot

if TYPE_CHECKING:
    from rtgait.sim.model import SimModel

_TIME_TOLERANCE = 1e-9  # s
_COLUMNS = 15  # ContactMonitor's row (its __init__ says what)

__all__ = ["ContactMonitor", "FallLimits", "Landings", "Pushes", "commanded_normal", "tip_cosine"]

_LEVEL = (0.0, 0.0, 1.0)  # the normal of a level sole


def commanded_normal(target: Sequence[float]) -> tuple[float, float, float]:
    """The unit normal of a sole at the IK's foot target ``target``: ``(x, y, z, yaw)``, level, or ``(x, y, z, yaw,
    pitch, roll)``, turned by ``Rz(yaw) Ry(pitch) Rx(roll)`` (:mod:`rtgait.core.geometry.foot_tilt`):

        n = (cos(yaw) sin(pitch) cos(roll) + sin(yaw) sin(roll),
             sin(yaw) sin(pitch) cos(roll) - cos(yaw) sin(roll),
             cos(pitch) cos(roll)).
    """
    if len(target) < 6 or not (target[4] or target[5]):
        return _LEVEL
    yaw, pitch, roll = target[3], target[4], target[5]
    cy, sy = math.cos(yaw), math.sin(yaw)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cr, sr = math.cos(roll), math.sin(roll)
    return cy * sp * cr + sy * sr, sy * sp * cr - cy * sr, cp * cr


def tip_cosine(rotation: Sequence[float], normal: Sequence[float], start: Sequence[float] | None = None) -> float:
    """The cosine of a sole's tilt from the tilt it was commanded: the angle between its normal ``m``, the third
    column of its orientation ``rotation`` (a 3 x 3 matrix, row-major, 9 numbers: MuJoCo's ``site_xmat``), and the
    commanded ``normal`` ``b`` (:func:`commanded_normal`); a level command gives the sole's tilt from level,
    ``rotation[8]``.

    With ``start`` ``a``, the normal the sole rolls from toward ``b`` (its foothold's, before a toe-off lifts the
    heel), the angle from ``m`` to the nearest normal on the arc from ``a`` to ``b``: a sole behind its commanded
    toe-off (its servo lagging the heel's rise) is on that arc, no tip. With ``k = a x b / |a x b|`` and ``s = m.k``,
    ``m``'s projection ``p = m - s k`` on the arc's plane lies within the arc when ``(a x p).k >= 0`` and
    ``(p x b).k >= 0``; the cosine is then ``sqrt(1 - s^2)``, else the larger of ``m.a`` and ``m.b``.
    """
    m = (rotation[2], rotation[5], rotation[8])
    bx, by, bz = normal
    to_b = float(m[0] * bx + m[1] * by + m[2] * bz) if (bx or by or bz != 1.0) else float(m[2])
    if start is None:
        return to_b
    a, b = np.asarray(start, float), np.asarray(normal, float)
    axis = np.cross(a, b)
    length = float(np.linalg.norm(axis))
    if length < 1e-12:  # no roll between them
        return to_b
    axis /= length
    mv = np.asarray(m, float)
    s = float(mv @ axis)
    p = mv - s * axis
    if np.cross(a, p) @ axis >= 0.0 and np.cross(p, b) @ axis >= 0.0:
        return math.sqrt(max(0.0, 1.0 - s * s))
    return max(float(mv @ a), to_b)


@dataclass(frozen=True)
class FallLimits:
    """When the robot has fallen (any of the first three ends the run) or tipped over (recorded only).

    Attributes:
        base_height_fraction: fallen: the base below this fraction of its height at the start, both heights above
            the terrain under the base (on a ramp down the base goes down with the ground it walks on: G1's, 0.74 m
            up at the start, went under 0.6 of that above the floor's plane 0.27 m down ``slope-down-g1``'s ramp,
            still 0.72 m above the ramp).
        tilt: fallen: the base tilted from upright beyond this angle (rad).
        airborne: fallen: no foot on the floor for longer than this (s).
        tip_angle: tipped over: a foot carrying more than half the load tilted beyond this angle (rad) from the
            tilt it was commanded (the IK's sole target: level on the flat floor, a sloped foothold's surface, the
            heel lifted in a planned toe-off), so that a planned roll onto the toe is no tip and a roll beyond it or
            off the surface is. The default, 0.02 rad, lifts the far edge of a 0.13 m wide sole by 2.6 mm; on flat
            ground the soles of a walk that keeps its ZMP inside tilt a few milliradians at most (the contact's
            softness).
    """

    base_height_fraction: float = 0.6
    tilt: float = math.radians(45.0)
    airborne: float = 0.2
    tip_angle: float = 0.02

    def __post_init__(self) -> None:
        if not 0.0 < self.base_height_fraction < 1.0:
            raise ValueError(f"base_height_fraction must be in (0, 1), got {self.base_height_fraction}")
        for name in ("tilt", "airborne", "tip_angle"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"fall limit {name} must be finite and > 0, got {value}")


class ContactMonitor:
    """The per-tick contact record of a run, and the fall and tip-over decisions (see the module docstring).

    Args:
        data: the MuJoCo state the run steps (its base's height at the start sets the fall limit).
        left_site, right_site: the sole sites' ids.
        n_ticks: rows to allocate.
        threshold: a foot touches the floor when its vertical force exceeds this (N).
        falls: the fall criteria.
        dt: the tick (s), to count the time without a foot on the floor.
    """

    def __init__(
        self,
        data: mujoco.MjData,
        left_site: int,
        right_site: int,
        n_ticks: int,
        threshold: float,
        falls: FallLimits,
        dt: float,
        terrain: Terrain | None = None,
    ) -> None:
        self._sites = (left_site, right_site)
        # The base's height is measured above the terrain under it (the fall limit).
        self._terrain = terrain if terrain is not None and getattr(terrain, "kind", "flat") != "flat" else None
        # The soles' commanded normals (left, right), of the feet targets the robot was last given, and the normals
        # each rolls from in a toe-off (None: no toe-off) (command()).
        self._normals: tuple[tuple[float, float, float], tuple[float, float, float]] = (_LEVEL, _LEVEL)
        self._starts: tuple[tuple[float, float, float] | None, tuple[float, float, float] | None] = (None, None)
        self.threshold = threshold
        # One row per tick, written at once (one assignment costs less than one per quantity): ZMP x, y (NaN while
        # no foot touches), vertical force left, right, sole corners touching left, right, cosine of the sole tilt
        # left, right, contacts between the legs, then each sole's x, y and yaw (left, then right).
        self._table = np.zeros((n_ticks, _COLUMNS))
        # A row is written with one struct packing into the table's bytes: a numpy assignment from a tuple of Python
        # numbers costs twice as much (the values stored are the same float64s).
        self._pack, self._buffer, self._row_bytes = row_packer(self._table)
        self.tip_time: float | None = None
        self._cos_tip = math.cos(falls.tip_angle)
        self._cos_fall = math.cos(falls.tilt)
        self._z_low = falls.base_height_fraction * (float(data.qpos[2]) - self._ground(data.qpos[0], data.qpos[1]))
        self._airborne_ticks = max(1, round(falls.airborne / dt))
        self._airborne = 0

    def record(self, k: int, t: float, sums: ContactSums, snapshot: StepSnapshot) -> tuple[float, float, float, float]:
        """Record tick ``k`` at time ``t`` (s) from the contacts of the last step, which describe the state at ``t``:
        ``snapshot`` its arrays (:func:`~rtgait.sim.step_snapshot.read_snapshot`), ``sums`` its contacts decoded
        (:class:`~rtgait.sim.contact_reading.ContactReader`).

        Returns:
            ``(zmp_x, zmp_y, f_left, f_right)``: the measured ZMP (m; NaN while no foot touches the floor) and the
            vertical force on each foot (N).
        """
        positions_of_sites, rotations = snapshot.site_positions, snapshot.site_rotations
        sx, sy, fl, fr = sums.sole_moment_x, sums.sole_moment_y, sums.left_normal, sums.right_normal
        cl, cr, other = sums.left_corners, sums.right_corners, sums.leg_contacts
        total = fl + fr
        if total > self.threshold:
            x, y = sx / total, sy / total
            self._airborne = 0
        else:
            x = y = math.nan
            self._airborne += 1
        # The z-z entry of a sole's orientation is the cosine of its tilt from level (the model's few sites are
        # read at once).
        left, right = self._sites
        ml, mr, pl, pr = rotations[left], rotations[right], positions_of_sites[left], positions_of_sites[right]
        cos_left, cos_right = ml[8], mr[8]
        self._pack(
            self._buffer, k * self._row_bytes,
            x, y, fl, fr, cl, cr, cos_left, cos_right, other,
            pl[0], pl[1], math.atan2(ml[3], ml[0]), pr[0], pr[1], math.atan2(mr[3], mr[0]),
        )  # fmt: skip
        # Tipping over: the loaded foot turned onto an edge of its sole, beyond the tilt it was commanded (a planned
        # toe-off or a sloped foothold's surface is no tip).
        if self.tip_time is None and (fl > 0.5 * total or fr > 0.5 * total):
            side, m, cos_level = (0, ml, cos_left) if fl > 0.5 * total else (1, mr, cos_right)
            normal = self._normals[side]
            # A level command (the flat floor's every tick) is the tilt from level, already read.
            start = self._starts[side]
            cos_tilt = cos_level if normal is _LEVEL and start is None else tip_cosine(m, normal, start)
            if cos_tilt < self._cos_tip:
                self.tip_time = t
        return x, y, fl, fr

    def command(self, left: Sequence[float], right: Sequence[float], toe_off: tuple[float, float] = (0.0, 0.0)) -> None:
        """The feet targets the robot is given now (``(x, y, z, yaw[, pitch, roll])``, m, rad: the IK's) and the
        toe-off pitch in each (rad, heel up), whose tilts the soles are compared with from the next :meth:`record`
        on (:func:`tip_cosine`: a sole anywhere from its foothold's tilt to its commanded toe-off is no tip); a
        target that is not finite (none while the stack damps) keeps the last one's."""
        normals, starts = [], []
        for target, theta, last, last_start in zip((left, right), toe_off, self._normals, self._starts, strict=True):
            normal = commanded_normal(target)
            if not math.isfinite(normal[0] + normal[1] + normal[2]):
                normals.append(last)
                starts.append(last_start)
                continue
            normals.append(normal)
            starts.append(commanded_normal((*target[:4], target[4] - theta, target[5])) if theta else None)
        self._normals = (normals[0], normals[1])
        self._starts = (starts[0], starts[1])

    def fall(self, base: np.ndarray) -> str | None:
        """Why the robot has fallen, from the base pose ``(x, y, z, qw, qx, qy, qz)`` at the tick last measured,
        or ``None``."""
        x, y, z, _, bx, by, _ = base.tolist()  # Python floats: cheaper than numpy scalars
        upright = 1.0 - 2.0 * (bx * bx + by * by)  # z component of the base's z axis
        if (z if self._terrain is None else z - self._ground(x, y)) < self._z_low:
            return "base too low"
        if upright < self._cos_fall:
            return "base tilted"
        if self._airborne >= self._airborne_ticks:
            return "no foot on the floor"
        return None

    def _ground(self, x: float, y: float) -> float:
        """Height (m) of the terrain under ``(x, y)`` (m): 0 on the flat floor."""
        return 0.0 if self._terrain is None else float(self._terrain.height(float(x), float(y)))

    def zmp(self, ticks: int) -> np.ndarray:
        """The measured ZMP (m) over the first ``ticks`` ticks, shape ``(ticks, 2)``; NaN while no foot touched."""
        return self._table[:ticks, 0:2].copy()

    def normal_force(self, ticks: int) -> np.ndarray:
        """The vertical force on each foot (N) over the first ``ticks`` ticks, shape ``(ticks, 2)``."""
        return self._table[:ticks, 2:4].copy()

    def corners(self, ticks: int) -> np.ndarray:
        """How many corners of each sole box touched the floor over the first ``ticks`` ticks, shape
        ``(ticks, 2)``."""
        return self._table[:ticks, 4:6].astype(np.int8)

    def sole_tilt(self, ticks: int) -> np.ndarray:
        """Angle between each sole's normal and the vertical over the first ``ticks`` ticks (rad), shape
        ``(ticks, 2)``."""
        return np.arccos(np.clip(self._table[:ticks, 6:8], -1.0, 1.0))

    def legs_touch(self, ticks: int) -> np.ndarray:
        """Whether the legs touched each other over the first ``ticks`` ticks, shape ``(ticks,)``."""
        return self._table[:ticks, 8] > 0.0

    def sole_poses(self, ticks: int) -> np.ndarray:
        """Each sole's ground pose ``(x, y, yaw)`` (m, rad; yaw of its x axis) over the first ``ticks`` ticks, shape
        ``(ticks, 2, 3)``, left then right."""
        return self._table[:ticks, 9:15].reshape(ticks, 2, 3).copy()


class Landings:
    """Touch-downs completed: the swing foot of each single support (an odd phase of the planner) must come down on
    the floor, before the single support's planned end (an early landing) or within ``window`` seconds after it.

    A foot that came down early counts even if it bounces off again around the planned end: it landed (G1's feet
    do bounce, for a few ticks, after an early touch-down). Down means a vertical force above ``threshold`` after
    the foot had been off the floor in that single support.

    Args:
        window: how long after the planned touch-down the foot may land (s).
        threshold: the vertical force above which a foot is on the floor (N).
    """

    def __init__(self, window: float, threshold: float) -> None:
        self.window, self.threshold = window, threshold
        self.count = 0
        self.missed = 0
        """Single supports whose swing foot was not on the floor by the end of its window."""
        self._pending: tuple[int, float] | None = None  # (foot index, end of its window)
        self._phase = -1
        self._swing = -1  # the swinging foot in the single support under way (0 left, 1 right), -1 not known yet
        self._lifted = self._down = False  # in that single support: the swing foot left the floor; came back down

    def update(self, t: float, phase: int, code: int, f_left: float, f_right: float) -> None:
        """One tick at time ``t`` (s): the planner's phase and planned support code (1 left, 2 right, 0 double),
        the vertical force on each foot (N)."""
        if phase != self._phase:
            if self._phase >= 1 and self._phase & 1 and self._swing >= 0:  # a single support ended
                if self._down:
                    self.count += 1
                else:
                    self._pending = (self._swing, t + self.window)
            self._phase, self._swing, self._lifted, self._down = phase, -1, False, False
        if phase >= 1 and phase & 1 and not self._down:
            if self._swing < 0 and code:
                self._swing = 1 if code == 1 else 0  # left support (code 1): the right foot (index 1) swings
            if self._swing >= 0:
                if (f_right if self._swing else f_left) <= self.threshold:
                    self._lifted = True
                elif self._lifted:
                    self._down = True
        if self._pending is not None:
            if (f_right if self._pending[0] else f_left) > self.threshold:
                self.count += 1
                self._pending = None
            elif t >= self._pending[1]:
                self._pending = None
                self.missed += 1


class Pushes:
    """The pushes of a run, applied through ``data.xfrc_applied`` at their times (one at a time)."""

    def __init__(self, sim: SimModel, data: mujoco.MjData, pushes: tuple[Push, ...]) -> None:
        self._windows = []
        for push in sorted(pushes, key=lambda p: p.start):
            body = sim.base_body
            if push.body is not None:
                body = mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_BODY, push.body)
            if body < 0:
                raise ValueError(f"push body {push.body!r}: the MuJoCo model of {sim.robot.name} has no such body")
            self._windows.append((push.start, push.start + push.duration, push.force, int(body)))
        self._xfrc = data.xfrc_applied
        self._active: tuple[float, float, tuple[float, float, float], int] | None = None
        self._next = 0

    def update(self, t: float) -> None:
        """Apply the push acting at time ``t`` (s), and end the one that is over. A window edge within a nanosecond
        of a tick counts as on it, so that a push of 0.1 s lasts exactly 100 ticks of 1 ms whatever the round-off of
        the tick times."""
        t += _TIME_TOLERANCE
        active = self._active
        if active is not None and t >= active[1]:
            self._xfrc[active[3], 0:3] = 0.0
            self._active = None
        if self._next < len(self._windows) and t >= self._windows[self._next][0]:
            self.clear()
            self._active = self._windows[self._next]
            self._xfrc[self._active[3], 0:3] = self._active[2]
            self._next += 1

    def clear(self) -> None:
        """Remove the push acting now, if any."""
        if self._active is not None:
            self._xfrc[self._active[3], 0:3] = 0.0
            self._active = None
