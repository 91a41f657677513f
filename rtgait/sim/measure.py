"""What a walking controller measures on the simulated robot with the ground-truth estimator: the simulator's truth
(:mod:`rtgait.sim.ground_truth`) turned into the walking state (:mod:`rtgait.estimation.ground_truth`) in one call.

This is ``--state truth``: the controller sees what a perfect estimator would give it.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import TYPE_CHECKING

import mujoco

from rtgait.estimation.ground_truth import GroundTruthEstimator
from rtgait.estimation.load import DEFAULT_LANDING_FRACTION, DEFAULT_MIN_UNLOADED_TIME
from rtgait.estimation.state import Measurement
from rtgait.sim.contact_reading import ContactReader
from rtgait.sim.ground_truth import GroundTruthReader
from rtgait.sim.step_snapshot import StepSnapshot

if TYPE_CHECKING:
    from rtgait.sim.model import SimModel

__all__ = ["DEFAULT_LANDING_FRACTION", "DEFAULT_MIN_UNLOADED_TIME", "SimMeasurer"]


class SimMeasurer:
    """The walking state of a simulated humanoid each tick, from the simulator's truth.

    Args:
        model: the compiled MuJoCo model.
        base_body: body id of the floating base (the robot is its subtree).
        left_site, right_site: site ids at the sole frames (x forward, z out of the sole).
        omega: pendulum frequency ``w = sqrt(g / z_c)`` of the planner (1/s), for the DCM.
        left_geoms, right_geoms: geoms of each foot that may touch the environment; default every geom of the body
            that carries the sole site.
        mass: robot mass (kg) for the default thresholds; default the base subtree's mass in the model.
        landing_force, release_force, min_unloaded_time, min_force, ground_height: the estimator's
            (:class:`~rtgait.estimation.ground_truth.GroundTruthEstimator`).
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
        ground_height: float | None = None,
    ) -> None:
        contacts = ContactReader(
            model, base_body=base_body, left_site=left_site, right_site=right_site, left_geoms=left_geoms,
            right_geoms=right_geoms,
        )  # fmt: skip
        self.reader = GroundTruthReader(contacts)
        self.mass = float(model.body_subtreemass[int(base_body)]) if mass is None else float(mass)
        weight = self.mass * float(-model.opt.gravity[2])
        if not weight > 0.0:
            raise ValueError(f"the robot's weight must be > 0 N, got {weight} (mass {self.mass} kg)")
        self.estimator = GroundTruthEstimator(
            omega, weight, landing_force=landing_force, release_force=release_force,
            min_unloaded_time=min_unloaded_time, min_force=min_force, ground_height=ground_height,
        )  # fmt: skip
        self._read, self._update = self.reader.read, self.estimator.update

    @property
    def landing_force(self) -> float:
        """Load at which a foot counts as loaded and, after flight, as landed (N)."""
        return self.estimator.load.landing_force

    @property
    def release_force(self) -> float:
        """Load below which a foot counts as unloaded (N)."""
        return self.estimator.load.release_force

    @property
    def omega(self) -> float:
        """The planner's pendulum frequency (1/s) the DCM is made with."""
        return self.estimator.omega

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
        self.estimator.reset()

    def measure(
        self,
        data: mujoco.MjData,
        t: float | None = None,
        snapshot: StepSnapshot | None = None,
        velocities: bool = False,
    ) -> Measurement:
        """The walking state of ``data``, stamped ``t`` (s; default ``data.time``); ``snapshot`` and ``velocities``
        as :meth:`~rtgait.sim.ground_truth.GroundTruthReader.read`."""
        return self._update(None, self._read(data, t, snapshot, velocities))
