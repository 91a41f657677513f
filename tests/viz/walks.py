"""A synthetic Talos walk for the replay tests: no IK, just a moving base and swinging legs and arms.

The motion is not dynamically meaningful; it only has to look like a robot walking over its footprints, so a
replay of it can be checked by eye and by the browser tests.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from rtgait.robot.data import data_file, share_dir

STEP_TIME = 0.8  # s per step
STEP_LENGTH = 0.1  # m


@dataclass(frozen=True)
class Foot:
    """A footprint as the replay reads it: x, y (m), yaw (rad), side."""

    x: float
    y: float
    yaw: float
    side: str


@dataclass(frozen=True)
class Sole:
    """Talos-like sole (m from the sole frame)."""

    front: float = 0.11
    back: float = 0.10
    inner: float = 0.065
    outer: float = 0.065


@dataclass(frozen=True)
class Talos:
    model: pin.Model
    visual_model: pin.GeometryModel
    half_sitting: np.ndarray  # soles on the ground (z = 0)
    foot_y: float  # m, lateral position of the left sole frame


@dataclass(frozen=True)
class Walk:
    times: np.ndarray  # (k,) s
    q: np.ndarray  # (k, nq)
    footprints: tuple[Foot, ...]
    sole: Sole
    cog: np.ndarray  # (k, 3) m
    zmp: np.ndarray  # (k, 2) m
    phases: tuple[str, ...]  # (k,) support phase per sample


def phase_at(walk: Walk, t: float) -> str:
    """The phase label of the sample at or just before ``t`` (s)."""
    return walk.phases[int(np.searchsorted(walk.times, t + 1e-9, side="right")) - 1]


def load_talos() -> Talos:
    """Talos with its visual meshes and its half-sitting pose, soles on the ground."""
    urdf = str(data_file("talos_data/robots/talos_reduced.urdf"))
    model = pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer())
    visual_model = pin.buildGeomFromUrdf(model, urdf, pin.GeometryType.VISUAL, package_dirs=[str(share_dir())])
    pin.loadReferenceConfigurations(model, str(data_file("talos_data/srdf/talos.srdf")))
    q = model.referenceConfigurations["half_sitting"].copy()
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    left = data.oMf[model.getFrameId("left_sole_link")].translation
    q[2] -= left[2]  # soles on the ground
    q[0] -= left[0]  # sole frames at x = 0
    return Talos(model, visual_model, q, float(left[1]))


def make_walk(talos: Talos, steps: int, dt: float = 0.01) -> Walk:
    """``steps`` steps of STEP_LENGTH m, STEP_TIME s each, starting and ending with the feet side by side."""
    model = talos.model
    duration = steps * STEP_TIME
    times = np.arange(0.0, duration + 0.5 * dt, dt)
    idx = {name: model.joints[model.getJointId(name)].idx_q for name in (
        "leg_left_3_joint", "leg_left_4_joint", "leg_right_3_joint", "leg_right_4_joint",
        "arm_left_1_joint", "arm_right_1_joint", "torso_1_joint",
    )}  # fmt: skip
    q = np.repeat(talos.half_sitting[None, :], len(times), axis=0)
    phase = 2.0 * math.pi * times / (2.0 * STEP_TIME)
    swing = np.sin(phase) * np.sin(math.pi * times / duration)  # fades in and out
    q[:, 0] += STEP_LENGTH * (steps - 1) * (times / duration - np.sin(2 * math.pi * times / duration) / (2 * math.pi))
    q[:, 1] += 0.03 * np.sin(phase)
    q[:, idx["leg_left_3_joint"]] -= 0.25 * np.maximum(swing, 0.0)
    q[:, idx["leg_left_4_joint"]] += 0.5 * np.maximum(swing, 0.0)
    q[:, idx["leg_right_3_joint"]] -= 0.25 * np.maximum(-swing, 0.0)
    q[:, idx["leg_right_4_joint"]] += 0.5 * np.maximum(-swing, 0.0)
    q[:, idx["arm_left_1_joint"]] += 0.3 * swing
    q[:, idx["arm_right_1_joint"]] += 0.3 * swing
    q[:, idx["torso_1_joint"]] += 0.1 * swing
    feet = [Foot(0.0, talos.foot_y, 0.0, "left"), Foot(0.0, -talos.foot_y, 0.0, "right")]
    for k in range(1, steps + 1):
        side = "right" if k % 2 else "left"
        x = min(k, steps - 1) * STEP_LENGTH  # the last step closes the feet
        feet.append(Foot(x, talos.foot_y if side == "left" else -talos.foot_y, 0.0, side))
    cog = np.column_stack([q[:, 0], q[:, 1] * 0.8, np.full(len(times), 0.87)])
    zmp = np.column_stack([q[:, 0], 0.08 * np.sin(phase)])
    # The left leg swings while swing > 0 (standing on the right foot), the right one while swing < 0.
    phases = tuple("right support" if s > 0.05 else "left support" if s < -0.05 else "double support" for s in swing)
    return Walk(times, q, tuple(feet), Sole(), cog, zmp, phases)
