"""The per-tick record of the MuJoCo closed loop (:class:`rtgait.sim.loop.ClosedLoop`): the whole walk, or a ring
of its last ticks for an open-ended run whose memory must stay bounded.

The arrays are allocated once; the loop writes tick ``k`` into row ``k mod capacity`` in place, so a tick allocates
nothing here. With ``capacity`` at least the walk's length (:func:`rtgait.sim.run_loop.run_sim_loop`) row ``k`` is
tick ``k`` and the ring never wraps. In a ring that has wrapped, the oldest rows have been overwritten: after ``n``
ticks, rows hold ticks ``n - capacity .. n - 1``, and :meth:`TickRecord.arrange` puts them back in tick order.

The replay's configurations are taken every ``replay_every`` ticks only (the ticks ``k = 0, r, 2r, ...``), into a
ring of their own, large enough for every such tick of a window of ``capacity`` ticks.

Row layouts: ``planned`` is (planned ZMP x, y, commanded ZMP x, y, measured DCM x, y, planned DCM x, y) (m);
``base`` is MuJoCo's ``qpos[0:7]`` (x, y, z, qw, qx, qy, qz); ``support`` holds
:data:`rtgait.core.geometry.support.SUPPORT_CODES`.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

if TYPE_CHECKING:
    from rtgait.sim.contact import ContactMonitor

__all__ = ["TickRecord", "TickValues"]


class TickValues(NamedTuple):
    """One tick of the closed loop as a live display shows it (m, rad, s; world frame, walk clock).

    Attributes:
        t: the tick's time (s).
        phase: the planner's phase index (-1 during the start transition).
        support: the plan's support, ``"double"``, ``"left"`` or ``"right"`` (the foot on the ground).
        zmp_planned: the planner's ZMP (during the start transition the COG target's ground projection).
        zmp_command: the ZMP the controller asked of the feet.
        zmp_measured: the centre of pressure of the sole contact forces; NaN while no foot touches the floor.
        dcm: the measured DCM the controller acted on; NaN during the start transition.
        dcm_planned: the plan's DCM; NaN during the start transition.
        cog_target: the COG target given to the IK ``(x, y, z)``.
        left_foot, right_foot: the feet's IK targets ``(x, y, z, yaw)``.
    """

    t: float
    phase: int
    support: str
    zmp_planned: tuple[float, float]
    zmp_command: tuple[float, float]
    zmp_measured: tuple[float, float]
    dcm: tuple[float, float]
    dcm_planned: tuple[float, float]
    cog_target: tuple[float, ...]
    left_foot: tuple[float, ...]
    right_foot: tuple[float, ...]


class TickRecord:
    """Per-tick arrays of ``capacity`` rows (see the module docstring).

    Args:
        capacity: rows, >= 1: the walk's ticks for a whole record, or the length of the ring.
        n_actuators: joint torques per row (MuJoCo's ``nu``).
        n_commanded: coordinates of the commanded configuration (the reduced Pinocchio model's ``nq``).
        n_qpos: MuJoCo's ``nq``, for the replay's configurations.
        replay_every: ticks between two replay configurations (>= 1).
    """

    def __init__(self, capacity: int, n_actuators: int, n_commanded: int, n_qpos: int, replay_every: int) -> None:
        if capacity < 1 or replay_every < 1:
            raise ValueError(f"a record needs capacity >= 1 and replay_every >= 1, got {capacity}, {replay_every}")
        self.capacity = capacity
        self.planned = np.full((capacity, 8), math.nan)
        self.cog = np.empty((capacity, 3))
        self.cog_planned = np.empty((capacity, 3))
        self.base = np.empty((capacity, 7))
        self.support = np.zeros(capacity, dtype=np.int8)
        self.torque = np.empty((capacity, n_actuators))
        self.commanded = np.empty((capacity, n_commanded))
        self.replay_every = replay_every
        self.replay_capacity = (capacity - 1) // replay_every + 1
        self.replay_qpos = np.empty((self.replay_capacity, n_qpos))
        self.replay_soles = np.empty((self.replay_capacity, 2, 3))

    def first_kept(self, ticks: int) -> int:
        """The oldest tick still held after ``ticks`` ticks."""
        return max(0, ticks - self.capacity)

    def arrange(self, rows: np.ndarray, ticks: int) -> np.ndarray:
        """``rows``, one per ring position (at least ``min(ticks, capacity)``), in tick order: ticks
        :meth:`first_kept` to ``ticks - 1``. A view of ``rows`` while the ring has not wrapped, else a new array."""
        if ticks <= self.capacity:
            return rows[:ticks]
        start = ticks % self.capacity
        return np.concatenate((rows[start : self.capacity], rows[:start]))

    def replay(self, ticks: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The replay's rows kept after ``ticks`` ticks: their ticks relative to :meth:`first_kept` (the indices into
        the arranged arrays), MuJoCo configurations and sole site positions, in tick order."""
        first, every = self.first_kept(ticks), self.replay_every
        r_first = -(-first // every)  # the first multiple of `every` at or after `first`
        r_last = (ticks - 1) // every
        rows = np.arange(r_first, r_last + 1) % self.replay_capacity
        return np.arange(r_first, r_last + 1) * every - first, self.replay_qpos[rows], self.replay_soles[rows]

    def arrays(self, ticks: int, contacts: ContactMonitor, threshold: float, k0: int, dt: float) -> dict[str, Any]:
        """The per-tick fields of a :class:`~rtgait.sim.result.SimResult` after ``ticks`` ticks, from this record and
        the contact monitor that recorded into the same rows; ``k0`` is the walk's first tick (time 0) and ``dt``
        the control period (s). Times are ``(k - k0) dt``, computed as the loop computed them."""
        first = self.first_kept(ticks)
        held = min(ticks, self.capacity)
        arrange = self.arrange
        planned = arrange(self.planned, ticks)
        base = arrange(self.base, ticks)
        normal_force = arrange(contacts.normal_force(held), ticks)
        return {
            "times": (np.arange(first, ticks) - k0) * dt,
            "zmp": arrange(contacts.zmp(held), ticks),
            "zmp_planned": planned[:, 0:2].copy(),
            "zmp_command": planned[:, 2:4].copy(),
            "dcm": planned[:, 4:6].copy(),
            "dcm_planned": planned[:, 6:8].copy(),
            "cog": arrange(self.cog, ticks),
            "cog_planned": arrange(self.cog_planned, ticks),
            "base_position": base[:, 0:3].copy(),
            "base_quaternion": base[:, [4, 5, 6, 3]],
            "contact": normal_force > threshold,
            "normal_force": normal_force,
            "corners": arrange(contacts.corners(held), ticks),
            "sole_tilt": arrange(contacts.sole_tilt(held), ticks),
            "sole_pose": arrange(contacts.sole_poses(held), ticks),
            "support": arrange(self.support, ticks),
            "torque": arrange(self.torque, ticks),
            "legs_touch": arrange(contacts.legs_touch(held), ticks),
            "commanded_q": arrange(self.commanded, ticks),
        }
