"""A humanoid's kinematic and inertial model for walking, built with Pinocchio from a robot description.

Two models are kept: the *full* model (every URDF joint, free-flyer root) for output, and the *reduced* model in
which every joint outside ``walking.moving_joints`` is locked at the half-sitting posture (its links' inertia
merged into the parent). The reduced model is what the whole-body IK and the multibody check work on: with the
locked joints at rest, both models have the same mass distribution, COG and centroidal momentum.

Configurations follow Pinocchio: ``q[0:3]`` base position (m), ``q[3:7]`` base orientation as a unit quaternion
``(qx, qy, qz, qw)``, then one coordinate per joint (rad or m), in the model's joint order.
"""

from __future__ import annotations

import os
import sys
import tempfile
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from rtgait.robot.description import RobotDescription, RobotError, load_robot
from rtgait.robot.physical_checks import check_whole_body

__all__ = ["BASE_COLUMNS", "RobotModel"]

BASE_COLUMNS = ("base_x", "base_y", "base_z", "base_qx", "base_qy", "base_qz", "base_qw")
"""Names of the 7 free-flyer coordinates, in Pinocchio's order (position in m, quaternion x, y, z, w)."""

# A half-sitting posture whose soles are further than this from flat on the ground cannot be a standing start.
_FLAT_TOLERANCE = 0.01  # m of height difference between the soles, and rad of sole tilt
_ROOT_JOINT = "root_joint"


def _tilt(rotation: np.ndarray) -> float:
    """Angle between a frame's z axis and the world's vertical (rad)."""
    return float(np.arccos(np.clip(rotation[2, 2], -1.0, 1.0)))


@dataclass(frozen=True, eq=False)
class RobotModel:
    """A loaded humanoid: full and reduced Pinocchio models and the half-sitting start configuration.

    Attributes:
        description: the robot description it was built from.
        full_model: every URDF joint, free-flyer root joint first.
        model: the reduced model (moving joints only, free-flyer root first); the IK works on this one.
        q_half_sitting: half-sitting configuration of the reduced model: both soles flat on the ground (z = 0),
            their midpoint at the origin, heading +x.
        q_full_half_sitting: the same configuration in the full model.
        mass: total mass (kg).
        step_width: lateral distance between the two sole points at half-sitting (m).
        cog_half_sitting: COG at half-sitting (m), world frame.
        left_sole_id, right_sole_id, torso_id: frame ids in the reduced model.
        full_left_sole_id, full_right_sole_id: the sole frame ids in the full model.
    """

    description: RobotDescription
    full_model: pin.Model
    model: pin.Model
    q_half_sitting: np.ndarray
    q_full_half_sitting: np.ndarray
    mass: float
    step_width: float
    cog_half_sitting: np.ndarray
    left_sole_id: int
    right_sole_id: int
    torso_id: int
    full_left_sole_id: int
    full_right_sole_id: int
    _full_index: np.ndarray
    _reduced_index: np.ndarray

    @classmethod
    def load(cls, description: RobotDescription | str | Path = "talos") -> RobotModel:
        """Build the models from a description (or a built-in robot name / description file path).

        Raises:
            RobotError: the URDF cannot be parsed by Pinocchio, the half-sitting posture does not put both soles
                flat on the ground, or the robot's total mass or COM height is implausible
                (:func:`~rtgait.robot.physical_checks.check_whole_body`).
        """
        if not isinstance(description, RobotDescription):
            description = load_robot(description)
        full = _build_full_model(description.urdf)
        full.name = description.name
        left_id, right_id = _sole_frames(full, description)

        q_full = _posture_configuration(full, description)
        _place_on_ground(full, q_full, left_id, right_id, description.name)

        moving = set(description.moving_joints)
        locked = [full.getJointId(name) for name in full.names[1:] if name != _ROOT_JOINT and name not in moving]
        model = pin.buildReducedModel(full, locked, q_full)
        model.name = description.name
        full_index, reduced_index = _index_maps(full, model)
        q = np.empty(model.nq)
        q[reduced_index] = q_full[full_index]

        data = model.createData()
        pin.centerOfMass(model, data, q)
        pin.framesForwardKinematics(model, data, q)
        left, right = model.getFrameId(full.frames[left_id].name), model.getFrameId(full.frames[right_id].name)
        torso = model.getFrameId(description.torso_frame)
        # The lateral distance in the ground frame: the soles are level and the feet head +x at half-sitting.
        step_width = float(abs(data.oMf[left].translation[1] - data.oMf[right].translation[1]))
        mass = float(pin.computeTotalMass(model))
        check_whole_body(description.name, mass, float(data.com[0][2]))
        return cls(
            description=description,
            full_model=full,
            model=model,
            q_half_sitting=q,
            q_full_half_sitting=q_full,
            mass=mass,
            step_width=step_width,
            cog_half_sitting=data.com[0].copy(),
            left_sole_id=int(left),
            right_sole_id=int(right),
            torso_id=int(torso),
            full_left_sole_id=int(left_id),
            full_right_sole_id=int(right_id),
            _full_index=full_index,
            _reduced_index=reduced_index,
        )

    @property
    def name(self) -> str:
        """The robot's name."""
        return self.description.name

    @property
    def joint_names(self) -> tuple[str, ...]:
        """URDF names of the reduced model's joints in configuration order (the root joint excluded)."""
        return tuple(self.model.names[2:])

    @property
    def full_joint_names(self) -> tuple[str, ...]:
        """URDF names of the full model's joints in configuration order (the root joint excluded)."""
        return tuple(self.full_model.names[2:])

    def full_configuration(self, q: np.ndarray) -> np.ndarray:
        """Full-model configuration(s) from reduced ones: locked joints at their half-sitting value.

        Args:
            q: shape ``(nq,)`` or ``(k, nq)`` in the reduced model.

        Returns:
            shape ``(full nq,)`` or ``(k, full nq)``.
        """
        q = np.asarray(q, dtype=float)
        if q.shape[-1] != self.model.nq:
            raise ValueError(f"q must have {self.model.nq} coordinates per row, got shape {q.shape}")
        out = np.broadcast_to(self.q_full_half_sitting, (*q.shape[:-1], self.full_model.nq)).copy()
        out[..., self._full_index] = q[..., self._reduced_index]
        return out

    def sole_positions(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World positions of the left and right sole points at reduced configuration ``q`` (m)."""
        data = self.model.createData()
        pin.framesForwardKinematics(self.model, data, q)
        return data.oMf[self.left_sole_id].translation.copy(), data.oMf[self.right_sole_id].translation.copy()


def _build_full_model(urdf: Path) -> pin.Model:
    """Pinocchio's model of ``urdf``, free-flyer root joint first.

    Pinocchio's URDF parser (urdfdom) writes its messages to the process's standard error from C++, several lines
    each, and after some errors goes on: an ``<inertial>`` it cannot read is dropped, and the model is built without
    that link's mass. So its messages are caught: an error refuses the URDF in one line, a warning becomes a Python
    warning (one line on the command line).
    """
    failure = None
    with _stderr_lines() as lines:
        try:
            full = pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer())
        except (RuntimeError, ValueError) as error:
            failure = " ".join(str(error).split())
    errors, notes = _parser_messages(lines)
    if errors or failure is not None:
        raise RobotError(f"model.urdf {urdf}: Pinocchio cannot build it: {errors[0] if errors else failure}")
    for note in notes:
        warnings.warn(f"model.urdf {urdf.name}: {note}", stacklevel=3)
    return full


@contextmanager
def _stderr_lines() -> Iterator[list[str]]:
    """The lines written to file descriptor 2 (by C++ code too) inside the block, given in the list at its end."""
    lines: list[str] = []
    sys.stderr.flush()  # what Python wrote before the block goes out first
    try:
        saved = os.dup(2)
    except OSError:  # no standard error to catch (a closed descriptor): nothing to hide either
        saved = None
    if saved is None:
        yield lines
        return
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), 2)
        try:
            yield lines
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            sink.seek(0)
            lines.extend(sink.read().decode(errors="replace").splitlines())


def _parser_messages(lines: list[str]) -> tuple[list[str], list[str]]:
    """urdfdom's messages (``"Error:   text"`` or ``"Warning: text"``, each followed by an ``"at line N in
    file.cpp"`` line) as the errors' and the other messages' texts."""
    errors: list[str] = []
    notes: list[str] = []
    for line in lines:
        text = line.strip()
        if not text or text.startswith("at line "):
            continue
        level, colon, rest = text.partition(":")
        if colon and level == "Error":
            errors.append(rest.strip())
        else:
            notes.append(rest.strip() if colon and level == "Warning" else text)
    return errors, notes


def _sole_frames(full: pin.Model, description: RobotDescription) -> tuple[int, int]:
    """Frame ids of the sole points in the full model, adding frames when the description gives an offset."""
    ids = []
    mirror = np.array([1.0, -1.0, 1.0])
    for side, name in (("left", description.left_sole_frame), ("right", description.right_sole_frame)):
        if not full.existFrame(name):
            raise RobotError(f"feet.{side}_sole_frame: Pinocchio's model of the URDF has no frame {name!r}")
        frame_id = full.getFrameId(name)
        offset = np.array(description.sole_offset)
        if not offset.any():
            ids.append(frame_id)
            continue
        parent = full.frames[frame_id]
        placement = parent.placement * pin.SE3(np.eye(3), offset if side == "left" else offset * mirror)
        # An operational frame on the same joint: it survives buildReducedModel like the URDF's own frames.
        new = pin.Frame(f"rtgait_{side}_sole", parent.parentJoint, frame_id, placement, pin.FrameType.OP_FRAME)
        ids.append(full.addFrame(new))
    return ids[0], ids[1]


def _posture_configuration(full: pin.Model, description: RobotDescription) -> np.ndarray:
    """Full configuration with the base at the origin and every joint at its posture angle (0 if unlisted)."""
    q = pin.neutral(full)
    for name, angle in description.posture.items():
        joint = full.joints[full.getJointId(name)]
        if joint.nq == 1:
            q[joint.idx_q] = angle
        else:
            # Continuous (unbounded revolute) joints are stored as (cos, sin) in Pinocchio.
            q[joint.idx_q : joint.idx_q + 2] = np.cos(angle), np.sin(angle)
    return q


def _place_on_ground(full: pin.Model, q: np.ndarray, left_id: int, right_id: int, name: str) -> None:
    """Move the base in ``q`` (in place) so the soles' midpoint frame is at the origin, level, heading +x."""
    data = full.createData()
    pin.framesForwardKinematics(full, data, q)
    left, right = data.oMf[left_id], data.oMf[right_id]
    # The mean of the two sole orientations: halfway along the rotation from one to the other.
    half_turn = pin.exp3(0.5 * pin.log3(left.rotation.T @ right.rotation))
    middle = pin.SE3(left.rotation @ half_turn, 0.5 * (left.translation + right.translation))
    base = middle.inverse() * pin.XYZQUATToSE3(q[:7])
    q[:7] = pin.SE3ToXYZQUAT(base)

    pin.framesForwardKinematics(full, data, q)
    left, right = data.oMf[left_id], data.oMf[right_id]
    height = abs(left.translation[2] - right.translation[2])
    tilt = max(_tilt(left.rotation), _tilt(right.rotation))
    if height > _FLAT_TOLERANCE or tilt > _FLAT_TOLERANCE:
        raise RobotError(
            f"posture of {name}: the soles are not flat on the ground at half-sitting "
            f"(height difference {height:.3f} m, tilt {tilt:.3f} rad); check [posture] and the sole frames"
        )
    if left.translation[1] <= right.translation[1]:
        raise RobotError(
            f"feet of {name}: the left sole frame is not to the left of the right one at half-sitting; "
            "check feet.left_sole_frame and feet.right_sole_frame"
        )


def _index_maps(full: pin.Model, reduced: pin.Model) -> tuple[np.ndarray, np.ndarray]:
    """Index arrays such that ``q_full[full_index] = q_reduced[reduced_index]``."""
    full_index: list[int] = []
    reduced_index: list[int] = []
    for joint_id in range(1, reduced.njoints):
        joint = reduced.joints[joint_id]
        source = full.joints[full.getJointId(reduced.names[joint_id])]
        full_index.extend(range(source.idx_q, source.idx_q + source.nq))
        reduced_index.extend(range(joint.idx_q, joint.idx_q + joint.nq))
    return np.array(full_index), np.array(reduced_index)
