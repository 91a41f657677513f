"""The robot's meshes for the HTML replay: read once, shared, simplified and packed small.

A robot's visual meshes, sent one by one as float32 triangle meshes, would be most of a replay's bytes.
:class:`MeshLibrary` shrinks them:

- **Sharing.** A mesh file used by several links (Talos' right leg and arm reuse the left ones, mirrored by a
  ``-1`` mesh scale) is read once. So is a file whose vertices are those of another file, or their mirror image
  across one axis (a robot whose right parts are separate, mirrored copies of its left ones, as G1's ankles): the
  geometry that uses it points at the shared mesh with the mirror folded into its fixed transform. The page builds
  one three.js geometry per shared mesh.
- **Simplification.** A mesh of more than :data:`MESH_TRIANGLES` triangles is decimated by quadric error
  (trimesh with fast-simplification), which removes first the triangles whose removal moves the surface least:
  the fine tessellation of flat and gently curved areas goes, the silhouette stays.
- **Normals.** Simplified meshes drawn flat look faceted; :func:`crease_normals` gives them smooth normals
  within crease-free regions and sharp ones across edges, as the full mesh looks.
- **Packing.** Vertex coordinates are quantized to 16 bits over the mesh's bounding box (below 10 um for a
  0.5 m part, far under a pixel), normals to 8 bits, and triangle indices are 16 bits when the mesh has fewer
  than 65 536 vertices.

Only STL files are read here; STL carries no colour, so the geometry's URDF colour is the whole look. Other
formats (DAE, OBJ) keep their own materials and are left to Pinocchio's meshcat loader by the caller. Without
trimesh, binary STL is read with numpy; without fast-simplification, meshes are shared and packed but not
simplified (a warning says so). Page sizes: ``docs/design/figures_and_replay.md``.
"""

from __future__ import annotations

import base64
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

__all__ = [
    "CREASE_ANGLE",
    "MESH_TRIANGLES",
    "Mesh",
    "MeshLibrary",
    "MeshUse",
    "crease_normals",
    "encode_mesh",
    "read_mesh",
    "simplify",
]

MESH_TRIANGLES = 1500
"""Default triangle budget per distinct mesh. Why 1500: at whole-body view (the robot about 500 px tall) Talos'
largest links, the torso (24 072 triangles), hips (13 242) and knees (5 872), keep their outline and their
machined edges, with smooth normals; at 800 the hips and pelvis show dents, and a larger budget costs page size for
a difference seen only in close-ups (``docs/design/figures_and_replay.md``). Parts already below the budget
(fingers, wrists, the arms' meshes) are kept whole."""

CREASE_ANGLE = np.radians(40.0)
"""Faces meeting at more than this angle (rad) are drawn with a sharp edge between them, others smooth: 40 deg
keeps the edges of machined covers and smooths the facets that simplification leaves on curved ones."""

SHARE_TOLERANCE = 1e-3
"""Two mesh files are drawn with one mesh when each vertex of either lies within this fraction of the bounding-box
diagonal of a vertex of the other (0.5 mm on a 0.5 m part: well below what simplification moves, and far from
the millimetres by which a left part and its not-quite-mirrored right part differ)."""

_MIRRORS = (np.diag([-1.0, 1.0, 1.0]), np.diag([1.0, -1.0, 1.0]), np.diag([1.0, 1.0, -1.0]))


@dataclass(frozen=True)
class Mesh:
    """A triangle mesh: ``vertices`` ``(n, 3)`` float64 in the file's units, ``triangles`` ``(m, 3)`` int64
    indices into them, counter-clockwise seen from outside, and optionally unit ``normals`` ``(n, 3)`` per
    vertex (see :func:`crease_normals`)."""

    vertices: np.ndarray
    triangles: np.ndarray
    normals: np.ndarray | None = None


@dataclass(frozen=True)
class MeshUse:
    """How one geometry draws a shared mesh: ``index`` into :attr:`MeshLibrary.meshes`, and ``mirror``, the
    3x3 diagonal matrix (identity or one ``-1``) that maps the shared mesh onto the geometry's own file."""

    index: int
    mirror: np.ndarray


def read_mesh(path: str | Path) -> Mesh | None:
    """The triangles of an STL file (binary or ASCII), or None when it is not a readable, non-empty STL file.

    Duplicate corners are merged into shared vertices, so the mesh is indexed (an STL file repeats each corner
    in every triangle that touches it).
    """
    if not str(path).lower().endswith(".stl"):
        return None
    try:
        import trimesh
    except ImportError:
        return _read_binary_stl(Path(path))
    try:
        loaded = trimesh.load(str(path), file_type="stl", force="mesh", process=True)
    except Exception:
        return None
    faces = np.asarray(getattr(loaded, "faces", np.zeros((0, 3))), dtype=np.int64)
    vertices = np.asarray(getattr(loaded, "vertices", np.zeros((0, 3))), dtype=np.float64)
    if faces.ndim != 2 or len(faces) == 0 or not np.all(np.isfinite(vertices)):
        return None
    return Mesh(vertices, faces)


_STL_TRIANGLE = np.dtype([("normal", "<f4", 3), ("corners", "<f4", (3, 3)), ("attribute", "<u2")])


def _read_binary_stl(path: Path) -> Mesh | None:
    """Binary STL with numpy alone, for an environment without trimesh (ASCII STL then reads as None)."""
    try:
        data = path.read_bytes()
    except OSError:
        return None
    count = int.from_bytes(data[80:84], "little") if len(data) >= 84 else 0
    if count == 0 or len(data) != 84 + _STL_TRIANGLE.itemsize * count:
        return None
    corners = np.frombuffer(data, dtype=_STL_TRIANGLE, count=count, offset=84)["corners"].reshape(-1, 3)
    vertices, index = np.unique(corners.astype(np.float64), axis=0, return_inverse=True)
    return Mesh(vertices, index.reshape(-1, 3).astype(np.int64))


_warned_no_simplifier = False


def simplify(mesh: Mesh, budget: int) -> Mesh:
    """``mesh`` decimated toward ``budget`` triangles by quadric error, or ``mesh`` itself when it is within
    the budget. The decimation stops early on meshes made of many small separate pieces, so the result may keep
    more triangles than asked. Without fast-simplification installed the mesh is returned whole, with a warning.
    """
    if len(mesh.triangles) <= budget:
        return mesh
    try:
        import fast_simplification
    except ImportError:
        global _warned_no_simplifier
        if not _warned_no_simplifier:
            warnings.warn(
                "fast-simplification is not installed: the replay's meshes are not simplified and the page is "
                "larger (pip install trimesh fast-simplification)", RuntimeWarning, stacklevel=2,
            )  # fmt: skip
            _warned_no_simplifier = True
        return mesh
    vertices, triangles = fast_simplification.simplify(
        np.ascontiguousarray(mesh.vertices, dtype=np.float64),
        np.ascontiguousarray(mesh.triangles, dtype=np.int64),
        target_count=int(budget),
    )
    if len(triangles) == 0:  # a degenerate input can collapse entirely: keep the original then
        return mesh
    return Mesh(np.asarray(vertices, dtype=np.float64), np.asarray(triangles, dtype=np.int64))


def crease_normals(mesh: Mesh, angle: float = CREASE_ANGLE) -> Mesh:
    """``mesh`` with a normal per vertex that is smooth across edges whose faces meet at less than ``angle``
    (rad) and sharp across the others, a vertex being split where a crease runs through it.

    Why: a simplified mesh has large facets; drawn flat, each shows as a patch of its own shade, and a curved
    cover looks cut from cardboard. Smooth normals within each crease-free region draw curved surfaces smooth
    and keep machined edges sharp, which is how the full-resolution mesh looks.
    """
    corners = mesh.vertices[mesh.triangles]  # (m, 3, 3)
    face = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])  # length: twice the area
    length = np.linalg.norm(face, axis=1)
    unit = face / np.where(length > 0.0, length, 1.0)[:, None]
    # Every pair of corners around the same vertex; a corner takes the (area-weighted) normals of the faces
    # of the pairs whose faces are within the crease angle of its own.
    vertex = mesh.triangles.reshape(-1)
    order = np.argsort(vertex, kind="stable")
    sorted_vertex = vertex[order]
    starts = np.flatnonzero(np.r_[True, sorted_vertex[1:] != sorted_vertex[:-1]])
    sizes = np.diff(np.r_[starts, len(order)])
    size_of = np.repeat(sizes, sizes)  # per sorted corner: how many corners share its vertex
    start_of = np.repeat(starts, sizes)
    rows = np.repeat(np.arange(len(order)), size_of)
    partners = start_of[rows] + (np.arange(len(rows)) - np.repeat(np.cumsum(size_of) - size_of, size_of))
    mine, theirs = order[rows] // 3, order[partners] // 3  # faces of the two corners
    keep = np.einsum("ij,ij->i", unit[mine], unit[theirs]) >= np.cos(angle)
    summed = np.zeros((len(order), 3))
    np.add.at(summed, order[rows[keep]], face[theirs[keep]])
    norm = np.linalg.norm(summed, axis=1)
    normals = np.where(norm[:, None] > 0.0, summed / np.where(norm > 0.0, norm, 1.0)[:, None], unit.repeat(3, axis=0))
    # One vertex per distinct (position, normal rounded to the 8-bit code the page stores).
    code = np.round(normals * 127.0).astype(np.int64)
    keys = np.column_stack([vertex, code])
    distinct, index = np.unique(keys, axis=0, return_inverse=True)
    first = np.zeros(len(distinct), dtype=np.int64)
    first[index] = np.arange(len(index))
    return Mesh(mesh.vertices[distinct[:, 0]], index.reshape(-1, 3).astype(np.int64), normals[first])


def _box(vertices: np.ndarray) -> np.ndarray:
    """Lowest and highest corner of ``vertices``, shape ``(2, 3)``."""
    return np.array([vertices.min(axis=0), vertices.max(axis=0)])


def _same_shape(a: np.ndarray, b: np.ndarray, tolerance: float) -> bool:
    """Whether every vertex of ``a`` has one of ``b`` within ``tolerance`` and the other way round (the
    Hausdorff distance of the two vertex sets, in file units)."""
    return bool(
        cKDTree(b).query(a, distance_upper_bound=tolerance)[0].max() <= tolerance
        and cKDTree(a).query(b, distance_upper_bound=tolerance)[0].max() <= tolerance
    )


class MeshLibrary:
    """The distinct meshes of a robot, each simplified once, and which one each geometry draws.

    Args:
        budget: triangle budget per distinct mesh (see :func:`simplify`); ``None`` keeps every triangle.
    """

    def __init__(self, budget: int | None = MESH_TRIANGLES) -> None:
        self.budget = budget
        self.meshes: list[Mesh] = []
        self.triangles_read = 0  # over distinct meshes, before simplification
        self._by_path: dict[str, MeshUse | None] = {}
        self._originals: list[np.ndarray] = []  # vertices of each distinct mesh as read, to compare new ones with
        self._boxes: list[np.ndarray] = []  # and their bounding boxes

    def use(self, path: str) -> MeshUse | None:
        """The shared mesh that draws the mesh file ``path``, or None when it is not an STL file this library
        reads (the caller draws it another way)."""
        if path in self._by_path:
            return self._by_path[path]
        mesh = read_mesh(path)
        found = None if mesh is None else self._share(mesh)
        self._by_path[path] = found
        return found

    def _share(self, mesh: Mesh) -> MeshUse:
        box = _box(mesh.vertices)
        tolerance = SHARE_TOLERANCE * float(np.linalg.norm(box[1] - box[0]))
        for mirror in (np.eye(3), *_MIRRORS):
            turned = np.sort(box @ mirror, axis=0)  # the box of the mirrored vertices
            for index, (original, original_box) in enumerate(zip(self._originals, self._boxes, strict=True)):
                # The boxes first: a cheap rejection of nearly every pair.
                if np.abs(turned - original_box).max() <= tolerance and _same_shape(
                    mesh.vertices @ mirror, original, tolerance
                ):
                    return MeshUse(index, mirror)
        self.triangles_read += len(mesh.triangles)
        self._originals.append(mesh.vertices)
        self._boxes.append(box)
        self.meshes.append(crease_normals(mesh if self.budget is None else simplify(mesh, self.budget)))
        return MeshUse(len(self.meshes) - 1, np.eye(3))

    def bounds(self, index: int) -> np.ndarray:
        """Corners of the bounding box of mesh ``index``, shape ``(8, 3)`` (file units)."""
        vertices = self.meshes[index].vertices
        low, high = vertices.min(axis=0), vertices.max(axis=0)
        return np.array([[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1]) for z in (low[2], high[2])])


def _b64(array: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(array).tobytes()).decode("ascii")


def encode_mesh(mesh: Mesh) -> dict[str, Any]:
    """``mesh`` as the page reads it: base64 little-endian int16 coordinates with the ``offset`` and ``step`` that
    turn them back into file units (``x = offset + step * q`` per axis), base64 uint16 or uint32 indices, and
    with normals, base64 int8 ``normals`` (``n = code / 127``, as WebGL reads a normalized byte)."""
    low = mesh.vertices.min(axis=0)
    span = mesh.vertices.max(axis=0) - low
    step = np.where(span > 0.0, span / 65535.0, 1.0)
    quantized = np.round((mesh.vertices - low) / step) - 32768.0
    wide = len(mesh.vertices) > 65535
    encoded = {
        "positions": _b64(np.clip(quantized, -32768, 32767).astype("<i2")),
        "offset": (low + 32768.0 * step).tolist(),
        "step": step.tolist(),
        "indices": _b64(mesh.triangles.astype("<u4" if wide else "<u2")),
        "index_bytes": 4 if wide else 2,
        "triangles": len(mesh.triangles),
    }
    if mesh.normals is not None:
        encoded["normals"] = _b64(np.round(np.clip(mesh.normals, -1.0, 1.0) * 127.0).astype(np.int8))
    return encoded
