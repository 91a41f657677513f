"""What touches what in the MuJoCo model: the soles and the floor, the two legs with each other, and the solver.

* **Soles.** One box per foot, the description's sole rectangle (``[feet.sole]``) with its bottom face on the sole
  point: the only geometry that touches the floor. A walking pattern's support polygon is that rectangle, so the
  physics supports the robot exactly where the plan assumes it can.
* **Legs.** Each link of a leg (the chain from the root link to a sole) gets a convex shape: the convex hull of its
  URDF geometry (collision and visual, meshes read from their STL files; links fixed to it included), a MuJoCo
  mesh geom. The hull, not the link's bounding box: a box in the link's frame is much bigger than the link where
  the link is slanted or tapered, and would make the legs touch where their meshes do not. The shapes
  of one leg collide with those of the other leg only, never with their own leg (parent and child links overlap at
  every joint) nor with the floor; a pair that already touches at half-sitting (e.g. the two hip housings under the
  pelvis) is excluded, since nothing could ever separate them. A step that crosses the feet, or a swing foot that
  hits the stance shin, then meets resistance in physics.
* **Contact softness.** MuJoCo's soft contact with time constant ``contact_timeconst`` (at least two physics steps,
  MuJoCo's own advice for a stable contact) and damping ratio ``contact_dampratio`` (1, critical, by default).
* **Static friction.** MuJoCo's soft contacts let a loaded foot creep slowly even below the friction limit (the
  constraint force is a stiff spring-damper on the contact velocity, not a lock). ``noslip_iterations`` of
  MuJoCo's no-slip solver project the friction forces back onto the cone after each step, which removes that
  drift: a foot pushed sideways below the friction limit then stays where it is.

Collision bits: the floor (type 1) collides with the soles (affinity 1); left-leg shapes (type 2, affinity 4) with
right-leg shapes (type 4, affinity 2); nothing else collides (visual meshes have 0 and 0).
"""

from __future__ import annotations

import functools
import struct
import xml.etree.ElementTree as ElementTree
from pathlib import Path
from typing import TYPE_CHECKING

import mujoco
import numpy as np
import pinocchio as pin
from scipy.spatial import ConvexHull, QhullError

from rtgait.robot.model import RobotModel
from rtgait.sim.urdf_import import resolve_mesh

if TYPE_CHECKING:
    from rtgait.sim.config import SimConfig

__all__ = [
    "FLOOR_BITS",
    "LEG_BITS",
    "SOLE_BITS",
    "LegShape",
    "add_floor",
    "add_leg_shapes",
    "add_sole",
    "exclude_pairs",
    "floor_contact_parameters",
    "leg_links",
    "leg_shapes",
    "touching_pairs",
]

FLOOR_BITS = (1, 0)
"""``(contype, conaffinity)`` of the floor."""
SOLE_BITS = (0, 1)
"""``(contype, conaffinity)`` of the sole boxes: they touch the floor only."""
LEG_BITS = {"left": (2, 4), "right": (4, 2)}
"""``(contype, conaffinity)`` of each leg's shapes: a left and a right shape collide, two shapes of one leg do not."""
_CLEARANCE = 0.002  # m: shapes closer than this at half-sitting are taken as touching (their pair is excluded)


# ----- soles and floor ---------------------------------------------------------------------------------------


def floor_contact_parameters(config: SimConfig) -> dict[str, object]:
    """The floor's (and the soles') friction and soft-contact parameters, as ``add_geom`` keywords."""
    return {
        "friction": [config.friction, 0.005, 0.0001],
        "solref": [config.contact_timeconst, config.contact_dampratio],
        "solimp": [*config.contact_impedance, 0.001, 0.5, 2.0],
    }


def add_floor(spec: mujoco.MjSpec, config: SimConfig) -> str:
    """Add the floor plane; returns its geom name."""
    spec.worldbody.add_geom(
        name="floor",
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        size=[0.0, 0.0, 0.05],  # infinite plane (size 0); the 0.05 is the grid spacing for viewers
        contype=FLOOR_BITS[0],
        conaffinity=FLOOR_BITS[1],
        rgba=[0.8, 0.8, 0.8, 1.0],
        **floor_contact_parameters(config),
    )
    return "floor"


def _sole_placement(robot: RobotModel, frame_id: int) -> tuple[str | None, pin.SE3]:
    """The URDF joint a sole frame hangs from (``None``: the root link) and the frame's placement in it."""
    full = robot.full_model
    frame = full.frames[frame_id]
    # Pinocchio's joint frame is the child link's frame, which is MuJoCo's body frame for that link.
    joint = full.names[frame.parentJoint]
    return (None if frame.parentJoint == 1 else joint), frame.placement


def _wxyz(rotation: np.ndarray) -> np.ndarray:
    quat = pin.Quaternion(rotation).coeffs()  # (x, y, z, w)
    return np.array([quat[3], quat[0], quat[1], quat[2]])


def add_sole(
    spec: mujoco.MjSpec, robot: RobotModel, side: str, root: mujoco.MjsBody, config: SimConfig
) -> tuple[str, str]:
    """Add a sole contact box and a site at the sole point; returns their names."""
    frame_id = robot.full_left_sole_id if side == "left" else robot.full_right_sole_id
    joint, placement = _sole_placement(robot, frame_id)
    body = root if joint is None else spec.joint(joint).parent
    sole = robot.description.sole
    # `inner` is toward the other foot: -y for the left foot, +y for the right one.
    toward_other = -1.0 if side == "left" else 1.0
    half = np.array([0.5 * (sole.front + sole.back), 0.5 * (sole.inner + sole.outer), 0.5 * config.sole_thickness])
    centre = np.array(
        [0.5 * (sole.front - sole.back), toward_other * 0.5 * (sole.inner - sole.outer), half[2]]
    )  # in the sole frame: the box stands on the sole point's plane
    rotation = placement.rotation
    wxyz = _wxyz(rotation)
    geom_name, site_name = f"{side}_sole_contact", f"{side}_sole"
    body.add_geom(
        name=geom_name,
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=half,
        pos=placement.translation + rotation @ centre,
        quat=wxyz,
        contype=SOLE_BITS[0],
        conaffinity=SOLE_BITS[1],
        condim=3,
        mass=0.0,
        group=3,
        rgba=[0.9, 0.5, 0.1, 0.6],
        **floor_contact_parameters(config),
    )
    body.add_site(name=site_name, pos=placement.translation, quat=wxyz, size=[0.01, 0.01, 0.01])
    return geom_name, site_name


# ----- leg geometry from the URDF --------------------------------------------------------------------------------


@functools.lru_cache(maxsize=64)
def _stl_vertices(path: str) -> np.ndarray:
    """Vertices of an STL file (binary or ASCII), shape ``(n, 3)``, in the file's units (m for URDF meshes)."""
    data = Path(path).read_bytes()
    if len(data) >= 84:
        count = struct.unpack("<I", data[80:84])[0]
        if len(data) == 84 + 50 * count:
            record = np.dtype([("normal", "<3f4"), ("vertices", "<9f4"), ("attribute", "<u2")])
            return np.frombuffer(data, dtype=record, count=count, offset=84)["vertices"].reshape(-1, 3).astype(float)
    words = data.decode("ascii", errors="replace").split()
    values = [words[i + 1 : i + 4] for i, word in enumerate(words) if word == "vertex"]
    return np.array(values, dtype=float).reshape(-1, 3)


def _rotation_rpy(text: str) -> np.ndarray:
    roll, pitch, yaw = (float(v) for v in text.split())
    return pin.rpy.rpyToMatrix(roll, pitch, yaw)


def _origin(element: ElementTree.Element) -> tuple[np.ndarray, np.ndarray]:
    origin = element.find("origin")
    if origin is None:
        return np.eye(3), np.zeros(3)
    return _rotation_rpy(origin.get("rpy", "0 0 0")), np.array([float(v) for v in origin.get("xyz", "0 0 0").split()])


def _shape_points(geometry: ElementTree.Element, urdf: Path, package_dirs: tuple[Path, ...]) -> np.ndarray | None:
    """Points whose convex hull holds the shape (a mesh's vertices, a primitive's bounding box corners), in the
    shape's own frame (m); ``None`` if unreadable."""
    if geometry.tag == "mesh":
        path = resolve_mesh(geometry.get("filename", ""), urdf, package_dirs)
        if path is None:
            return None
        scale = np.array([float(v) for v in geometry.get("scale", "1 1 1").split()])
        return _stl_vertices(str(path)) * scale if path.suffix.lower() == ".stl" else None
    if geometry.tag == "box":
        half = 0.5 * np.array([float(v) for v in geometry.get("size", "0 0 0").split()])
    elif geometry.tag == "sphere":
        half = np.full(3, float(geometry.get("radius", "0")))
    elif geometry.tag == "cylinder":
        radius, length = float(geometry.get("radius", "0")), float(geometry.get("length", "0"))
        half = np.array([radius, radius, 0.5 * length])
    else:
        return None
    return half * np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])


def _link_points(root: ElementTree.Element, link: str, urdf: Path, package_dirs: tuple[Path, ...]) -> np.ndarray:
    """Points of a link's URDF geometry and of the links fixed to it, in the link's frame (m), shape ``(n, 3)``."""
    links = {element.get("name"): element for element in root.findall("link")}
    fixed: dict[str, list[tuple[str, ElementTree.Element]]] = {}
    for joint in root.findall("joint"):
        if joint.get("type") == "fixed":
            parent, child = joint.find("parent"), joint.find("child")
            if parent is not None and child is not None:
                fixed.setdefault(parent.get("link", ""), []).append((child.get("link", ""), joint))
    points: list[np.ndarray] = []
    pending = [(link, np.eye(3), np.zeros(3))]
    while pending:
        name, rotation, translation = pending.pop()
        element = links.get(name)
        if element is None:
            continue
        for kind in ("collision", "visual"):
            for shape in element.findall(kind):
                geometry = shape.find("geometry")
                if geometry is None or not len(geometry):
                    continue
                local = _shape_points(geometry[0], urdf, package_dirs)
                if local is None:
                    continue
                shape_rotation, shape_translation = _origin(shape)
                points.append((local @ shape_rotation.T + shape_translation) @ rotation.T + translation)
        for child, joint in fixed.get(name, []):
            joint_rotation, joint_translation = _origin(joint)
            pending.append((child, rotation @ joint_rotation, rotation @ joint_translation + translation))
    return np.vstack(points) if points else np.zeros((0, 3))


def leg_links(robot: RobotModel, root: ElementTree.Element) -> dict[str, list[str]]:
    """The links of each leg: the child links of the URDF joints (``root``: the URDF's root element) from the root
    link down to each sole frame, from the hip down."""
    children = {}
    for joint in root.findall("joint"):
        child = joint.find("child")
        if child is not None:
            children[joint.get("name", "")] = child.get("link", "")
    full = robot.full_model
    legs: dict[str, list[str]] = {}
    for side, frame_id in (("left", robot.full_left_sole_id), ("right", robot.full_right_sole_id)):
        chain = [j for j in full.supports[full.frames[frame_id].parentJoint] if j > 1]  # past universe and the root
        legs[side] = [children[full.names[j]] for j in chain if full.names[j] in children]
    return legs


class LegShape:
    """The convex hull of a leg link's geometry, in the link's frame.

    Attributes:
        link: the URDF link.
        side: ``"left"`` or ``"right"``.
        vertices: the hull's vertices in the link frame (m), shape ``(n, 3)``.
        centre, half: the centre and half sizes of their bounding box (m), for reports.
    """

    def __init__(self, link: str, side: str, vertices: np.ndarray) -> None:
        self.link, self.side, self.vertices = link, side, vertices
        low, high = vertices.min(axis=0), vertices.max(axis=0)
        self.centre, self.half = 0.5 * (low + high), 0.5 * (high - low)

    @property
    def geom_name(self) -> str:
        """Name of its MuJoCo geom."""
        return f"{self.link}_shape"


def leg_shapes(robot: RobotModel) -> list[LegShape]:
    """The convex shape of every leg link with geometry (see the module docstring)."""
    description = robot.description
    try:
        root = ElementTree.parse(description.urdf).getroot()
    except (OSError, ElementTree.ParseError):  # pragma: no cover - the description was read from it already
        return []
    shapes = []
    for side, links in leg_links(robot, root).items():
        for link in links:
            points = _link_points(root, link, description.urdf, description.package_dirs)
            if len(points) == 0:
                continue
            shapes.append(LegShape(link, side, _hull_vertices(points)))
    return shapes


def _hull_vertices(points: np.ndarray) -> np.ndarray:
    """The vertices of the convex hull of ``points`` ``(n, 3)`` (m), a few hundred out of a mesh's thousands (MuJoCo
    takes the hull of a mesh geom's vertices itself; fewer make the model compile faster). A flat or degenerate set
    is thickened to 2 mm first, so that it still has a volume."""
    low, high = points.min(axis=0), points.max(axis=0)
    thin = (high - low) < 2e-3
    if thin.any():
        centre = 0.5 * (low + high)
        offsets = np.array([[dx, dy, dz] for dx in (-1, 1) for dy in (-1, 1) for dz in (-1, 1)], dtype=float) * 1e-3
        points = np.vstack([points, centre + offsets * thin])
    try:
        hull = ConvexHull(points)
    except QhullError:  # pragma: no cover - only for points on a line or a plane, thickened above
        return np.vstack([low - 1e-3, high + 1e-3])
    return points[hull.vertices]


def add_leg_shapes(spec: mujoco.MjSpec, robot: RobotModel) -> list[LegShape]:
    """Add the leg shapes (convex meshes, massless, in group 3 for viewers); returns them. The pairs that touch at
    half-sitting are found on the compiled model (:func:`touching_pairs`) and excluded (:func:`exclude_pairs`)."""
    shapes = leg_shapes(robot)
    for shape in shapes:
        contype, conaffinity = LEG_BITS[shape.side]
        mesh = f"{shape.geom_name}_hull"
        spec.add_mesh(name=mesh, uservert=shape.vertices.ravel().tolist())
        spec.body(shape.link).add_geom(
            name=shape.geom_name,
            type=mujoco.mjtGeom.mjGEOM_MESH,
            meshname=mesh,
            contype=contype,
            conaffinity=conaffinity,
            condim=1,  # frictionless: the legs only need to meet each other, not to grip
            mass=0.0,
            group=3,
            rgba=[0.2, 0.6, 0.9, 0.3],
        )
    return shapes


def touching_pairs(model: mujoco.MjModel, qpos: np.ndarray, shapes: list[LegShape]) -> list[tuple[str, str]]:
    """The bodies of the left and right leg shapes closer than a couple of millimetres at configuration ``qpos``
    (MuJoCo body names of the compiled ``model``, in which links fixed to their parent have been merged)."""
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_kinematics(model, data)
    ids = {s.geom_name: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, s.geom_name) for s in shapes}
    left = [s for s in shapes if s.side == "left"]
    right = [s for s in shapes if s.side == "right"]
    pairs = []
    for a in left:
        for b in right:
            distance = mujoco.mj_geomDistance(model, data, ids[a.geom_name], ids[b.geom_name], 0.05, None)
            if distance < _CLEARANCE:
                body_a, body_b = (model.geom_bodyid[ids[s.geom_name]] for s in (a, b))
                names = (mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, int(i)) for i in (body_a, body_b))
                pairs.append(tuple(names))  # type: ignore[arg-type]
    return sorted(set(pairs))


def exclude_pairs(spec: mujoco.MjSpec, pairs: list[tuple[str, str]]) -> None:
    """Exclude collisions between the bodies of each pair."""
    for a, b in pairs:
        spec.add_exclude(bodyname1=a, bodyname2=b)
