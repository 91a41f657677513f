"""Physics parameters of a simulated robot and its floor: the physics step, the control period, contacts, solver, and
how the drives act (which gains, the motor model, the command's delay)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rtgait.interface.command import GAIN_SETS
from rtgait.sim.actuation import substeps

if TYPE_CHECKING:
    from rtgait.robot.model import RobotModel

__all__ = ["GAIN_SETS", "SensorSettings", "SimConfig"]

# GAIN_SETS, SimConfig.gains' choices, is rtgait.interface.command's (re-exported here): "stiff", the description's
# kp/kd or the gains derived from the URDF (rtgait.sim.actuation); "robot", robot_kp/robot_kd.


@dataclass(frozen=True)
class SensorSettings:
    """How the simulated sensors of a run report (:mod:`rtgait.sim.sensors`); the sensors themselves are the robot
    description's ``[sensors]``.

    Attributes:
        noise: factor on every noise, bias and offset of the description (1: as described; 0: noise-free, the
            readings are the simulator's truth, not quantized).
        latency: control periods between sampling and reading; ``None``: the description's ``sensors.latency``.
        seed: seed of the run's random generator: the same seed, the same readings.
    """

    noise: float = 1.0
    latency: int | None = None
    seed: int = 0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.noise) and self.noise >= 0.0):
            raise ValueError(f"SensorSettings.noise must be a finite number >= 0, got {self.noise}")
        latency = self.latency
        if latency is not None and not (isinstance(latency, int) and not isinstance(latency, bool) and latency >= 0):
            raise ValueError(f"SensorSettings.latency must be a whole number of control periods >= 0, got {latency}")
        if not (isinstance(self.seed, int) and not isinstance(self.seed, bool) and self.seed >= 0):
            raise ValueError(f"SensorSettings.seed must be an integer >= 0, got {self.seed}")


@dataclass(frozen=True)
class SimConfig:
    """Physics parameters of the simulated robot and its floor.

    Why the defaults (measurements in ``docs/design/simulation.md``):

    * ``physics_dt``: the robot description's ``actuation.physics_dt`` (1 ms for Talos, its control period; 0.5 ms
      for G1, four steps per 2 ms control period), the step at which that robot's outcomes have converged; a
      shorter step costs wall time in proportion.
    * A contact time constant of 10 ms with critical damping (ratio 1, MuJoCo's default): the soles sink a fraction
      of a millimetre under the robot's weight, like a thin rubber sole on a hard floor, and settle without ringing.
      MuJoCo's contact stiffness goes as 1 / (time constant x damping ratio)^2: much stiffer, a foot rolls onto one
      edge at a time and the body's sideways rocking on its soles is barely damped.
    * 10 no-slip iterations: they remove the creep of a loaded foot (:mod:`rtgait.sim.contact_model`); their cost is
      mostly independent of the iteration count.
    * Friction 1: rubber on a dry floor.

    Attributes:
        physics_dt: physics step (s); must divide the control period; ``None``: the description's
            ``actuation.physics_dt``.
        control_dt: control period (s): a new joint reference every period; ``None``: the description's
            ``actuation.control_dt`` (1 ms for Talos, 2 ms for G1).
        friction: sliding friction coefficient between soles and floor.
        contact_timeconst: time constant of the soft contact (s); MuJoCo's ``solref[0]``, at least two physics steps.
        contact_dampratio: damping ratio of the soft contact; MuJoCo's ``solref[1]``.
        contact_impedance: MuJoCo's ``solimp[0:2]``, the contact's impedance at zero and at 1 mm penetration.
        sole_thickness: height of the sole contact boxes (m); their bottom face is on the sole point.
        noslip_iterations: iterations of MuJoCo's no-slip solver per step (0: none; the feet then creep).
        leg_collisions: give the leg links convex shapes that collide with the other leg's.
        gain_scale: factor on every joint's kp and kd (1: the description's or derived gains); for ensembles.
        armature_scale: factor on every joint's armature; for ensembles.
        meshes: keep the visual meshes (for viewing); without them the model builds faster and simulates the same.
        sensors: noise, latency and seed of the simulated sensors' readings (:class:`SensorSettings`); the
            physics does not depend on them.
        model_error: seed of the differences between the simulated robot and the controller's model of it (masses,
            centres of mass, joint zeros: :mod:`rtgait.sim.model_error`); ``None``: none, the robot is the model.
        gains: the drives' own gains, those a command without gains gets: one of :data:`GAIN_SETS`.
        motor_model: whether the drives have their motor types' torque-speed envelopes and joint friction
            (:mod:`rtgait.sim.motors`); ``False``: ideal drives, clipped at their torque limits only.
        command_delay: control periods between writing a command and the drives' applying it (a bus that delivers
            it in the next cycle: 1); ``None``: the description's ``actuation.command_delay``.

    The drives of today's runs are ``gains="stiff"``, no motor model, no delay; the robot's own drives are
    ``gains="robot", motor_model=True, command_delay=None``.
    """

    physics_dt: float | None = None
    control_dt: float | None = None
    friction: float = 1.0
    contact_timeconst: float = 0.01
    contact_dampratio: float = 1.0
    contact_impedance: tuple[float, float] = (0.9, 0.95)
    sole_thickness: float = 0.01
    noslip_iterations: int = 10
    leg_collisions: bool = True
    gain_scale: float = 1.0
    armature_scale: float = 1.0
    meshes: bool = True
    sensors: SensorSettings = SensorSettings()
    model_error: int | None = None
    gains: str = "stiff"
    motor_model: bool = False
    command_delay: int | None = 0

    def __post_init__(self) -> None:
        step = self.physics_dt
        rules = {
            "friction": (self.friction > 0.0, "> 0"),
            # Two physics steps at the least; checked again against the description's step when the model is built.
            "contact_timeconst": (
                self.contact_timeconst > 0.0 and self.contact_timeconst >= 2.0 * (step or 0.0),
                ">= 2 physics steps (s)",
            ),
            "contact_dampratio": (self.contact_dampratio > 0.0, "> 0"),
            "sole_thickness": (self.sole_thickness > 0.0, "> 0 m"),
            "gain_scale": (self.gain_scale > 0.0, "> 0"),
            "armature_scale": (self.armature_scale > 0.0, "> 0"),
        }
        if step is not None:
            rules["physics_dt"] = (step > 0.0, "> 0 s")
        for name, (ok, rule) in rules.items():
            value = getattr(self, name)
            if not (math.isfinite(value) and ok):
                raise ValueError(f"SimConfig.{name} must be finite and {rule}, got {value}")
        if self.control_dt is not None:
            # Raises on a period that is not > 0, or a step longer than it or not dividing it.
            substeps(self.control_dt, self.control_dt if step is None else step)
        if not (isinstance(self.noslip_iterations, int) and 0 <= self.noslip_iterations <= 1000):
            raise ValueError(
                f"SimConfig.noslip_iterations must be an integer in [0, 1000], got {self.noslip_iterations}"
            )
        seed = self.model_error
        if seed is not None and not (isinstance(seed, int) and not isinstance(seed, bool) and seed >= 0):
            raise ValueError(f"SimConfig.model_error must be an integer seed >= 0 or None, got {seed!r}")
        if self.gains not in GAIN_SETS:
            raise ValueError(f"SimConfig.gains must be one of {', '.join(GAIN_SETS)}, got {self.gains!r}")
        if not isinstance(self.motor_model, bool):
            raise ValueError(f"SimConfig.motor_model must be true or false, got {self.motor_model!r}")
        delay = self.command_delay
        if delay is not None and not (isinstance(delay, int) and not isinstance(delay, bool) and delay >= 0):
            raise ValueError(
                f"SimConfig.command_delay must be a whole number of control periods >= 0 or None, got {delay!r}"
            )
        low, high = self.contact_impedance
        if not 0.0 < low <= high < 1.0:
            raise ValueError(
                f"SimConfig.contact_impedance must be (low, high) with 0 < low <= high < 1, got {(low, high)}"
            )

    def resolved(self, robot: RobotModel) -> SimConfig:
        """These settings with the physics step and command delay of ``robot``'s description where not given.

        Raises:
            ValueError: the contact time constant is shorter than two of the resolved physics steps.
        """
        actuation = robot.description.actuation
        step = self.physics_dt if self.physics_dt is not None else actuation.physics_dt
        if self.contact_timeconst < 2.0 * step:
            raise ValueError(
                f"SimConfig.contact_timeconst must be >= 2 physics steps ({2.0 * step:g} s for {robot.name}), "
                f"got {self.contact_timeconst}"
            )
        delay = actuation.command_delay if self.command_delay is None else self.command_delay
        return dataclasses.replace(self, physics_dt=step, command_delay=delay)
