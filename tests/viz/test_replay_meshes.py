"""The replay's mesh library on small meshes it writes itself: reading STL, sharing identical and mirrored files,
simplifying to a budget, crease normals and the 16-bit packing."""

from __future__ import annotations

import base64
import math
import struct
from pathlib import Path

import numpy as np
import pytest
from pages import mesh_triangles, mesh_vertices

from rtgait.viz import replay_meshes
from rtgait.viz.replay_meshes import Mesh, MeshLibrary, crease_normals, encode_mesh, read_mesh, simplify


def write_stl(path: Path, vertices: np.ndarray, triangles: np.ndarray) -> Path:
    """A binary STL file of the mesh (normals left zero, as many exporters do)."""
    data = bytearray(b"\0" * 80 + struct.pack("<I", len(triangles)))
    for face in triangles:
        data += struct.pack("<3f", 0, 0, 0) + np.asarray(vertices[face], dtype="<f4").tobytes() + b"\0\0"
    path.write_bytes(bytes(data))
    return path


def sphere(subdivisions: int = 3) -> Mesh:
    """A unit icosphere (20 * 4**subdivisions triangles, outward winding)."""
    t = (1.0 + math.sqrt(5.0)) / 2.0
    vertices = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
                (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]  # fmt: skip
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
             (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
             (6, 2, 10), (8, 6, 7), (9, 8, 1)]  # fmt: skip
    points = [np.array(v, dtype=float) / np.linalg.norm(v) for v in vertices]
    for _ in range(subdivisions):
        middle: dict[tuple[int, int], int] = {}

        def split(a: int, b: int, middle: dict[tuple[int, int], int] = middle) -> int:
            key = (min(a, b), max(a, b))
            if key not in middle:
                m = points[a] + points[b]
                points.append(m / np.linalg.norm(m))
                middle[key] = len(points) - 1
            return middle[key]

        faces = [f for a, b, c in faces for f in (
            (a, split(a, b), split(c, a)), (b, split(b, c), split(a, b)), (c, split(c, a), split(b, c)),
            (split(a, b), split(b, c), split(c, a)),
        )]  # fmt: skip
    return Mesh(np.array(points), np.array(faces, dtype=np.int64))


# An asymmetric wedge: no mirror of it is itself, so a mirrored copy can only match as a mirror.
WEDGE = Mesh(
    np.array([[0, 0, 0], [0.3, 0, 0], [0, 0.2, 0], [0, 0, 0.1], [0.05, 0.04, 0.02]], dtype=float),
    np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 4], [1, 4, 3], [2, 3, 4]], dtype=np.int64),
)


def test_reads_binary_and_ascii_stl(tmp_path: Path) -> None:
    path = write_stl(tmp_path / "wedge.STL", WEDGE.vertices, WEDGE.triangles)
    mesh = read_mesh(path)
    assert mesh is not None and len(mesh.vertices) == 5 and mesh.triangles.shape == (6, 3)  # corners merged
    assert np.sort(mesh.vertices[mesh.triangles].reshape(-1, 3), axis=0) == pytest.approx(
        np.sort(WEDGE.vertices[WEDGE.triangles].reshape(-1, 3), axis=0), abs=1e-7
    )  # float32 in the file
    fallback = replay_meshes._read_binary_stl(path)  # without trimesh
    assert fallback is not None and len(fallback.vertices) == 5 and len(fallback.triangles) == 6
    ascii_lines = ["solid wedge"]
    for face in WEDGE.triangles:
        corners = [f"vertex {x} {y} {z}" for x, y, z in WEDGE.vertices[face]]
        ascii_lines += ["facet normal 0 0 0", "outer loop", *corners, "endloop", "endfacet"]
    (tmp_path / "ascii.stl").write_text("\n".join([*ascii_lines, "endsolid wedge", ""]))
    pytest.importorskip("trimesh", reason="ASCII STL is read by trimesh")
    text = read_mesh(tmp_path / "ascii.stl")
    assert text is not None and len(text.vertices) == 5 and len(text.triangles) == 6
    assert read_mesh(tmp_path / "wedge.dae") is None  # not an STL: left to Pinocchio's loader
    (tmp_path / "empty.stl").write_bytes(b"\0" * 84)
    assert read_mesh(tmp_path / "empty.stl") is None


def test_identical_and_mirrored_files_share_one_mesh(tmp_path: Path) -> None:
    library = MeshLibrary()
    original = write_stl(tmp_path / "left.stl", WEDGE.vertices, WEDGE.triangles)
    copy = write_stl(tmp_path / "copy.stl", WEDGE.vertices[[4, 3, 2, 1, 0]], (4 - WEDGE.triangles)[::-1])
    flip = np.diag([1.0, -1.0, 1.0])
    mirrored = write_stl(tmp_path / "right.stl", WEDGE.vertices @ flip, WEDGE.triangles[:, ::-1])
    other = write_stl(tmp_path / "other.stl", WEDGE.vertices * [1.0, 1.0, 2.0], WEDGE.triangles)
    first = library.use(str(original))
    assert first is not None and first.index == 0 and np.array_equal(first.mirror, np.eye(3))
    assert library.use(str(original)) == first  # the same file again: not read twice
    same = library.use(str(copy))
    assert same is not None and same.index == 0 and np.array_equal(same.mirror, np.eye(3))
    mirror = library.use(str(mirrored))
    assert mirror is not None and mirror.index == 0 and np.array_equal(mirror.mirror, flip)
    different = library.use(str(other))
    assert different is not None and different.index == 1
    assert len(library.meshes) == 2 and library.triangles_read == 12
    assert library.use(str(tmp_path / "missing.stl")) is None


def test_simplify_keeps_the_shape_within_the_budget() -> None:
    pytest.importorskip("fast_simplification")
    ball = sphere(4)  # 5120 triangles
    small = simplify(ball, 500)
    assert 400 <= len(small.triangles) <= 550
    radius = np.linalg.norm(small.vertices, axis=1)
    assert np.abs(radius - 1.0).max() < 0.02  # the vertices stay on the sphere
    assert simplify(ball, 10_000) is ball  # within the budget: untouched


def test_crease_normals_are_smooth_on_curves_and_sharp_on_edges() -> None:
    ball = crease_normals(sphere(2))
    assert ball.normals is not None and len(ball.vertices) == len(sphere(2).vertices)  # no crease: no split
    radial = ball.vertices / np.linalg.norm(ball.vertices, axis=1)[:, None]
    assert np.einsum("ij,ij->i", ball.normals, radial).min() > 0.99
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    cube = Mesh(corners, np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))], dtype=np.int64))
    sharp = crease_normals(cube)
    assert sharp.normals is not None and len(sharp.vertices) == 24  # each corner once per face it touches
    assert np.abs(sharp.normals).max(axis=1) == pytest.approx(np.ones(24))  # along the axes


def test_packing_round_trip() -> None:
    ball = crease_normals(sphere(2))
    encoded = encode_mesh(replace_scale(ball, 0.4))
    assert encoded["index_bytes"] == 2 and encoded["triangles"] == len(ball.triangles)
    vertices = mesh_vertices(encoded)
    assert np.abs(vertices - 0.4 * ball.vertices).max() <= 0.8 / 65535  # half a 16-bit step of the 0.8 m box
    assert np.array_equal(mesh_triangles(encoded), ball.triangles)
    normals = np.frombuffer(base64.b64decode(encoded["normals"]), dtype=np.int8).reshape(-1, 3) / 127
    assert np.abs(normals - ball.normals).max() < 0.01


def replace_scale(mesh: Mesh, scale: float) -> Mesh:
    return Mesh(mesh.vertices * scale, mesh.triangles, mesh.normals)
