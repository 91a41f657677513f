"""Hand-guided walking in physics (the paper's Section 6): a person leads the robot by the hand.

The person is a point that walks a :class:`~rtgait.scenario.scenario.GuidePath` at constant speed, starting at the
robot's hand when the walk begins. The person's arm is a horizontal spring-damper between that point and the robot's
hand (:class:`Leash`); its force is applied to the robot every tick through ``data.xfrc_applied`` on the body that
carries the hand (with the torque that moves it from the hand to the body's centre of mass, where MuJoCo applies it),
and read back as the wrist sensor. :class:`rtgait.core.laws.guidance.HandGuide` turns that reading into the planner's
velocity command, one decision per step (quasi-real-time), and once the person has stopped and the command is zero the
planner is told to stop.

The torque about the vertical, which the paper's operator gives by twisting the hand, is the person's: a twist
proportional to how far the robot's heading lags the path's (:attr:`Leash.twist_gain`), applied to the hand's body
as a torque (``data.xfrc_applied``) and read by the wrist sensor. The pull alone would not turn the robot: the hand
is beside the body, and the moment of a forward pull about the base is a constant bias, not a turn.

The leash is scaled to the robot (:meth:`Leash.for_robot`): its force limit is a fraction of the robot's weight
(:data:`FORCE_FRACTION`, 4.5 %: 40 N on Talos, 15 N on G1), its stiffness and damping and the twist's gain and limit
in proportion, so that the person leads any robot as they lead Talos, and a person does not drag a robot: the robot
must walk after the hand, its stance feet still (:attr:`rtgait.sim.result.SimResult.foot_slip_max`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np
import pinocchio as pin

from rtgait.control.controller import ControllerOptions, WalkingController, make_controller
from rtgait.core.laws.guidance import HandGuide
from rtgait.core.planner.levels import ControllerLevel
from rtgait.core.planner.online import OnlinePlanner, VelocityCommand
from rtgait.robot.controller_info import robot_info
from rtgait.scenario.scenario import GuidePath, Scenario
from rtgait.sim.loop import LoopOptions
from rtgait.sim.model import SimModel
from rtgait.sim.result import SimResult
from rtgait.sim.run_loop import run_sim_loop

__all__ = [
    "FORCE_FRACTION",
    "HAND_FRAMES",
    "GuideOutcome",
    "HandPull",
    "Leash",
    "guided_options",
    "simulate_guided",
]

FORCE_FRACTION = 0.045
"""Largest pull of the leash as a fraction of the robot's weight: 40 N on Talos (90 kg), the value the guided walk
was first tuned with, about a tenth of what the soles' friction (coefficient 1) could hold in single support."""

_TALOS_WEIGHT = 40.0 / FORCE_FRACTION  # N: the weight the default leash is sized for

HAND_FRAMES = ("gripper_right_base_link", "right_rubber_hand", "right_wrist_yaw_link")
"""Right-hand frames of the built-in robots (Talos, G1), tried in this order when no hand frame is given."""


@dataclass(frozen=True)
class Leash:
    """The person's arm: a horizontal spring-damper from the person to the robot's hand, and a twist.

    Attributes:
        stiffness: force per metre of stretch (N/m).
        damping: force per m/s of relative speed (N s/m).
        max_force: the pull is clipped to this (N): a person does not drag a robot.
        twist_gain: torque about the vertical per radian of heading lag behind the path (N m/rad).
        max_twist: the twist is clipped to this (N m).
        hand_frame: the robot's hand, a frame of its full Pinocchio model; ``None``: the first of
            :data:`HAND_FRAMES` the robot has.
    """

    stiffness: float = 150.0
    damping: float = 40.0
    max_force: float = 40.0
    twist_gain: float = 30.0
    max_twist: float = 10.0
    hand_frame: str | None = None

    def __post_init__(self) -> None:
        for name in ("stiffness", "damping", "max_force", "twist_gain", "max_twist"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"leash {name} must be finite and >= 0, got {value}")

    @classmethod
    def for_robot(cls, mass: float, gravity: float = 9.81, hand_frame: str | None = None) -> Leash:
        """The default leash scaled to a robot of ``mass`` (kg): force limit :data:`FORCE_FRACTION` of its weight,
        stiffness, damping, twist gain and twist limit in the same proportion to the defaults (sized for Talos)."""
        if not (math.isfinite(mass) and mass > 0.0):
            raise ValueError(f"mass must be > 0 kg, got {mass}")
        scale = mass * gravity / _TALOS_WEIGHT
        base = cls()
        return cls(
            stiffness=base.stiffness * scale,
            damping=base.damping * scale,
            max_force=FORCE_FRACTION * mass * gravity,
            twist_gain=base.twist_gain * scale,
            max_twist=base.max_twist * scale,
            hand_frame=hand_frame,
        )


@dataclass(frozen=True)
class GuideOutcome:
    """Where the person led the robot.

    Attributes:
        person_end: the person's end point (m, world x, y).
        expected_base: where the base should end: the person's end point minus the hand's offset from the base
            at the start, turned by the path's final heading (m, world x, y).
        base_end: where the base ended (m, world x, y).
        max_force: the largest pull on the hand (N).
        stop_time: when the planner was told to stop (s), or ``None``.
        force_limit: the leash's force limit (N).
        max_twist: the largest twist applied to the hand (N m).
    """

    person_end: tuple[float, float]
    expected_base: tuple[float, float]
    base_end: tuple[float, float]
    max_force: float
    stop_time: float | None
    force_limit: float = math.nan
    max_twist: float = 0.0

    @property
    def base_error(self) -> float:
        """Distance from the base's end to where it should be (m)."""
        return math.dist(self.base_end, self.expected_base)


def _yaw(qpos: np.ndarray) -> float:
    """Heading (rad) of the free joint's quaternion ``(qw, qx, qy, qz)`` at ``qpos[3:7]``."""
    w, x, y, z = qpos[3], qpos[4], qpos[5], qpos[6]
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


class HandPull:
    """The person, the leash and the wrist sensor: a :attr:`rtgait.sim.loop.LoopOptions.on_tick` hook.

    Args:
        sim: the robot in MuJoCo.
        planner: the planner, walking by command (``OnlinePlanner(config, None)``), quasi-real-time.
        path: the person's path, relative to the hand at the walk's start and the robot's heading.
        leash: the person's arm.
        max_steps: the planner is stopped once this many steps are committed, whatever the pull.
        controller: the walking controller, told the pull each tick (the wrist sensor's force at the hand's height)
            so that it leans against it (:meth:`~rtgait.control.controller.WalkingController.set_external_force`).
    """

    def __init__(
        self,
        sim: SimModel,
        planner: OnlinePlanner,
        path: GuidePath,
        leash: Leash | None = None,
        max_steps: int = 100,
        controller: WalkingController | None = None,
    ) -> None:
        self.sim = sim
        self.controller = controller
        self.planner = planner
        self.path = path
        self.leash = leash or Leash.for_robot(sim.robot.mass, float(-sim.model.opt.gravity[2]))
        self.guide = HandGuide(planner)
        self.max_steps = max_steps
        robot = sim.robot
        full = robot.full_model
        candidates = HAND_FRAMES if self.leash.hand_frame is None else (self.leash.hand_frame,)
        found = [name for name in candidates if full.existFrame(name)]
        if not found:
            raise ValueError(f"{robot.name} has no hand frame (tried {', '.join(candidates)}); give Leash.hand_frame")
        self._frame = full.getFrameId(found[0])
        # The hand's body in MuJoCo: the child body of the nearest moving joint above it (locked joints were fused
        # into their parents by the model builder).
        joint = full.frames[self._frame].parentJoint
        while full.names[joint] not in sim.joint_names and joint > 1:
            joint = full.parents[joint]
        name = full.names[joint]
        self._body = (
            sim.base_body
            if name not in sim.joint_names
            else int(sim.model.jnt_bodyid[mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_JOINT, name)])
        )
        self._local: np.ndarray | None = None  # the hand in the body's frame (m)
        self._origin = np.zeros(2)  # the path's start in the world (m)
        self._heading0 = 0.0
        self._offset = np.zeros(2)  # hand minus base at the start, in the robot's frame (m)
        self._t0 = 0.0
        self._hand_previous = np.zeros(2)
        self.stop_time: float | None = None
        self.max_force = 0.0
        self.max_twist = 0.0

    def _begin(self, t: float, data: mujoco.MjData) -> None:
        """At the walk's start: where the hand is on its body, and the path's placement in the world."""
        robot = self.sim.robot
        pin_data = robot.full_model.createData()
        pin.framesForwardKinematics(robot.full_model, pin_data, self.sim.full_configurations(data.qpos))
        hand = pin_data.oMf[self._frame].translation
        body_position, body_rotation = data.xpos[self._body], data.xmat[self._body].reshape(3, 3)
        self._local = body_rotation.T @ (hand - body_position)
        self._origin = hand[:2].copy()
        self._heading0 = _yaw(data.qpos)
        c, s = math.cos(self._heading0), math.sin(self._heading0)
        d = hand[:2] - data.qpos[0:2]
        self._offset = np.array([c * d[0] + s * d[1], -s * d[0] + c * d[1]])
        self._hand_previous = hand[:2].copy()
        self._t0 = t

    def person(self, t: float) -> tuple[np.ndarray, np.ndarray, float]:
        """The person's position (m), velocity (m/s) and heading (rad) in the world at time ``t`` (s)."""
        travelled = self.path.speed * (t - self._t0)
        x, y, heading = self.path.at(travelled)
        c, s = math.cos(self._heading0), math.sin(self._heading0)
        position = self._origin + np.array([c * x - s * y, s * x + c * y])
        world_heading = self._heading0 + heading
        moving = 0.0 <= travelled < self.path.length
        speed = self.path.speed if moving else 0.0
        return position, speed * np.array([math.cos(world_heading), math.sin(world_heading)]), world_heading

    def __call__(self, t: float, data: mujoco.MjData) -> None:
        """One tick: apply the pull, read the wrist, update the command (see the module docstring)."""
        if self._local is None:
            self._begin(t, data)
        assert self._local is not None
        leash = self.leash
        body = self._body
        # The hand at the state's kinematics (computed by the last step); its velocity by a finite difference.
        hand = data.xpos[body] + data.xmat[body].reshape(3, 3) @ self._local
        dt = self.sim.control_dt  # called once per control tick
        hand_velocity = (hand[:2] - self._hand_previous) / dt
        self._hand_previous = hand[:2].copy()
        target, target_velocity, path_heading = self.person(t)
        force = leash.stiffness * (target - hand[:2]) + leash.damping * (target_velocity - hand_velocity)
        size = float(np.hypot(*force))
        if size > leash.max_force:
            force *= leash.max_force / size
        self.max_force = max(self.max_force, min(size, leash.max_force))
        force3 = np.array([force[0], force[1], 0.0])
        xfrc = data.xfrc_applied[body]
        xfrc[0:3] = force3
        # MuJoCo applies xfrc_applied at the body's centre of mass: add the moment of moving it from the hand.
        xfrc[3:6] = np.cross(hand - data.xipos[body], force3)
        if self.controller is not None:  # the wrist sensor's force, at the hand's height: the robot leans against it
            self.controller.set_external_force((float(force[0]), float(force[1])), float(hand[2]))
        heading = _yaw(data.qpos)
        lag = math.remainder(path_heading - heading, math.tau)
        twist = 0.0 if self.stop_time is not None else leash.twist_gain * lag
        twist = min(max(twist, -leash.max_twist), leash.max_twist)
        xfrc[5] += twist  # the person's twist of the hand, a torque about the vertical on the hand's body
        self.max_twist = max(self.max_twist, abs(twist))
        if self.stop_time is not None:
            return
        # The wrist sensor reads the force applied to the hand (world frame) and the person's twist.
        self.guide.update(t, float(xfrc[0]), float(xfrc[1]), twist, heading)
        person_stopped = t - self._t0 >= self.path.duration
        too_many = self.planner.first_open_step() > self.max_steps
        if (person_stopped and self.guide.command == VelocityCommand()) or too_many:
            self.planner.stop()
            self.stop_time = t

    def outcome(self, base_end: np.ndarray) -> GuideOutcome:
        """Where the person led the robot, with the base's final position ``base_end`` (m)."""
        end, _, heading = self.person(self._t0 + self.path.duration)
        c, s = math.cos(heading), math.sin(heading)
        ox, oy = self._offset
        expected = end - np.array([c * ox - s * oy, s * ox + c * oy])
        return GuideOutcome(
            person_end=(float(end[0]), float(end[1])),
            expected_base=(float(expected[0]), float(expected[1])),
            base_end=(float(base_end[0]), float(base_end[1])),
            max_force=self.max_force,
            stop_time=self.stop_time,
            force_limit=self.leash.max_force,
            max_twist=self.max_twist,
        )


def guided_options(pull: HandPull, options: LoopOptions, margin: float = 8.0) -> LoopOptions:
    """``options`` with ``pull`` as its hook and a duration that covers the person's walk and ``margin`` seconds
    (s) for the robot to catch up and stop."""
    duration = pull.path.duration + margin
    return dataclasses.replace(options, on_tick=pull, duration=duration, stop_after_steps=None)


def simulate_guided(
    sim: SimModel,
    walk: Scenario,
    options: LoopOptions | None = None,
    *,
    controller: ControllerLevel = "adaptive",
    controller_options: ControllerOptions | None = None,
    path: GuidePath | None = None,
    leash: Leash | None = None,
    progress: Callable[[float], None] | None = None,
) -> tuple[SimResult, GuideOutcome]:
    """Walk ``walk`` led by the hand in closed loop (see the module docstring).

    Args:
        sim: the robot in MuJoCo.
        walk: the scenario as walked by this robot (:func:`rtgait.robot.motion.robot_scenario`); its timing and
            connection (quasi-real-time) build the planner, ``walk.steps`` is the most steps allowed.
        options: further loop settings; its hook, duration and ``stop_after_steps`` are replaced.
        controller: the controller level (:mod:`rtgait.control.controller`).
        controller_options: its gains and landing handling.
        path: the person's path (default: ``walk.guide``).
        leash: the person's arm (default :meth:`Leash.for_robot` of the simulated robot).
        progress: called now and then with the fraction simulated.

    Returns:
        The run and where the person led the robot.

    Raises:
        ValueError: no path (neither ``path`` nor ``walk.guide``), or not quasi-real-time.
    """
    path = path or walk.guide
    if path is None:
        raise ValueError(f"scenario {walk.name!r} has no [guide] path")
    level = make_controller(
        controller,
        walk.planner_config(),
        None,
        walk.sole,
        robot_info(sim.robot, gains=sim.config.gains),
        dt=sim.control_dt,
        options=controller_options,
    )
    pull = HandPull(sim, level.planner, path, leash, max_steps=walk.steps, controller=level)
    result = run_sim_loop(sim, level, guided_options(pull, options or LoopOptions()), progress=progress)
    return result, pull.outcome(result.base_position[-1])
