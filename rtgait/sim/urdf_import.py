"""A robot's URDF as MuJoCo's importer needs it, and the edits made to the imported model's spec.

:mod:`rtgait.sim.model` builds the physics model from these (its module docstring says what changes and why):

* :func:`urdf_for_mujoco`: the URDF's text with ``package://`` mesh URIs resolved to files under the description's
  ``package_dirs``, collision elements and ``<mimic>`` couplings dropped, visual meshes MuJoCo cannot decode
  (:data:`MESH_FORMATS`) left out with one :class:`MeshSkippedWarning`, and MuJoCo's ``<mujoco><compiler/>``
  extension that keeps the paths and visuals and takes the inertia from ``<inertial>`` only;
* :func:`lock_joint`: a joint replaced by its body turned (or slid) by a fixed angle (rad, or m);
* :func:`compile_spec`: the spec compiled, MuJoCo's refusal turned into a :class:`~rtgait.robot.description.RobotError`
  that names the URDF.

:func:`resolve_mesh` also serves the leg collision shapes (:mod:`rtgait.sim.contact_model`), which read the
URDF's meshes themselves.
"""

from __future__ import annotations

import warnings
import xml.etree.ElementTree as ElementTree
from pathlib import Path

import mujoco
import numpy as np

from rtgait.robot.description import RobotDescription, RobotError

__all__ = ["MESH_FORMATS", "MeshSkippedWarning", "compile_spec", "lock_joint", "resolve_mesh", "urdf_for_mujoco"]

MESH_FORMATS = (".stl", ".obj", ".msh")
"""Mesh file formats MuJoCo decodes; other visual meshes (Romeo's COLLADA ``.dae``) are left out of the model."""


class MeshSkippedWarning(UserWarning):
    """Visual meshes of the robot were left out of its MuJoCo model (a format MuJoCo cannot decode)."""


_PACKAGE = "package://"


def resolve_mesh(uri: str, urdf: Path, package_dirs: tuple[Path, ...]) -> Path | None:
    """The file a URDF mesh URI names: ``package://`` under the first of ``package_dirs`` that has it, else a path
    (``file://`` or plain) relative to the URDF's folder; ``None`` when no such file exists."""
    if uri.startswith(_PACKAGE):
        relative = uri[len(_PACKAGE) :]
        return next((folder / relative for folder in package_dirs if (folder / relative).is_file()), None)
    path = Path(uri.removeprefix("file://"))
    path = path if path.is_absolute() else urdf.parent / path
    return path if path.is_file() else None


def urdf_for_mujoco(description: RobotDescription, meshes: bool) -> str:
    """The URDF's text, ready for MuJoCo's importer (see the module docstring)."""
    try:
        root = ElementTree.parse(description.urdf).getroot()
    except (OSError, ElementTree.ParseError) as error:
        raise RobotError(f"model.urdf {description.urdf} is not a readable URDF: {error}") from None
    for old in root.findall("mujoco"):
        root.remove(old)
    for joint in root.findall("joint"):
        # A <mimic> becomes an equality constraint in MuJoCo, which fails once the joints it names are locked
        # (Romeo's fingers); every joint is either locked or driven by its own servo here.
        for mimic in joint.findall("mimic"):
            joint.remove(mimic)
    undecodable: dict[str, int] = {}
    for link in root.findall("link"):
        for collision in link.findall("collision"):
            link.remove(collision)
        for visual in link.findall("visual"):
            mesh = visual.find("geometry/mesh")
            if mesh is None:
                continue
            found = None
            if meshes:  # without meshes no file is looked for: every visual goes
                found = resolve_mesh(mesh.get("filename", ""), description.urdf, description.package_dirs)
            path = None if found is None else str(found)
            suffix = Path(path).suffix.lower() if path is not None else ""
            if path is not None and suffix not in MESH_FORMATS:
                undecodable[suffix] = undecodable.get(suffix, 0) + 1
                path = None
            if path is None:
                # A missing or undecodable mesh file is only a missing picture; the physics does not depend on it.
                link.remove(visual)
            else:
                mesh.set("filename", path)
    if undecodable:
        kinds = ", ".join(f"{count} {suffix}" for suffix, count in sorted(undecodable.items()))
        warnings.warn(
            f"{description.name}: visual meshes MuJoCo cannot decode ({kinds}) are left out of its MuJoCo model "
            "(they are only its picture; the 3D replay draws them)",
            MeshSkippedWarning,
            stacklevel=3,
        )
    extension = ElementTree.Element("mujoco")
    ElementTree.SubElement(
        extension,
        "compiler",
        {
            "strippath": "false",  # keep the absolute mesh paths written above
            "discardvisual": "false",  # the visual meshes are the only picture of the robot left
            "inertiafromgeom": "false",  # the URDF's <inertial> only, as Pinocchio reads it
            "balanceinertia": "true",  # a few URDF inertias violate the triangle inequality slightly
            "fusestatic": "true",  # links on fixed joints (and locked ones) become part of their parent
            "angle": "radian",
        },
    )
    root.insert(0, extension)
    return ElementTree.tostring(root, encoding="unicode")


# ----- spec edits ------------------------------------------------------------------------------------------------


def _quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    out = np.empty(4)
    mujoco.mju_mulQuat(out, a, b)
    return out


def _rotate(quat: np.ndarray, vector: np.ndarray) -> np.ndarray:
    out = np.empty(3)
    mujoco.mju_rotVecQuat(out, vector, quat)
    return out


def lock_joint(spec: mujoco.MjSpec, joint: mujoco.MjsJoint, angle: float) -> None:
    """Turn (or slide) the joint's body by ``angle`` about the joint axis and remove the joint."""
    body = joint.parent
    axis = np.array(joint.axis, dtype=float)
    axis /= np.linalg.norm(axis)
    anchor = np.array(joint.pos, dtype=float)
    quat = np.array(body.quat, dtype=float)
    quat /= np.linalg.norm(quat)
    if joint.type == mujoco.mjtJoint.mjJNT_HINGE:
        turn = np.empty(4)
        mujoco.mju_axisAngle2Quat(turn, axis, angle)
        # A rotation about an axis through `anchor` (body coordinates): the body origin moves unless anchor = 0.
        body.pos = np.array(body.pos) + _rotate(quat, anchor - _rotate(turn, anchor))
        body.quat = _quat_mul(quat, turn)
    elif joint.type == mujoco.mjtJoint.mjJNT_SLIDE:
        body.pos = np.array(body.pos) + _rotate(quat, angle * axis)
    else:  # pragma: no cover - descriptions only name one-coordinate joints, and URDFs have no others
        raise RobotError(f"cannot lock joint {joint.name!r} of type {joint.type}")
    if hasattr(spec, "delete"):
        spec.delete(joint)
    else:  # MuJoCo before 3.4 removes an element through the element itself
        joint.delete()


def compile_spec(spec: mujoco.MjSpec, description: RobotDescription) -> mujoco.MjModel:
    """``spec`` compiled; MuJoCo's refusal as a :class:`RobotError` naming the description's URDF."""
    try:
        return spec.compile()
    except ValueError as error:
        raise RobotError(f"model.urdf {description.urdf}: MuJoCo cannot compile the robot: {error}") from None
