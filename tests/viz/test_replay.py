"""The HTML replay without a browser: what the page holds (decoded from meshcat's embedded commands), that it
needs no network, that bad input writes nothing, and that no meshcat server outlives the call."""

from __future__ import annotations

import base64
import math
import os
import re
import struct
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")
pytest.importorskip("meshcat")
umsgpack = pytest.importorskip("umsgpack")  # meshcat's message format

from walks import Foot, Talos, Walk, make_walk  # noqa: E402

from rtgait.viz import replay  # noqa: E402
from rtgait.viz.replay import write_replay_html  # noqa: E402

COMMAND = re.compile(r'fetch\("data:application/octet-binary;base64,([A-Za-z0-9+/=]+)"\)')


def decode_commands(page: str) -> list[dict]:
    """meshcat's drawing commands embedded in a static page, as the viewer receives them."""
    return [umsgpack.unpackb(base64.b64decode(blob)) for blob in COMMAND.findall(page)]


def meshcat_server_children() -> list[int]:
    """Live child processes of this test process that are meshcat servers."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
            cmdline = (stat.parent / "cmdline").read_bytes()
        except OSError:
            continue
        if int(fields[1]) == os.getpid() and fields[0] != "Z" and b"meshcat.servers" in cmdline:
            found.append(int(stat.parent.name))
    return found


@dataclass(frozen=True)
class Written:
    path: Path
    page: str
    commands: list[dict]
    walk: Walk


@pytest.fixture(scope="module")
def written(talos: Talos, tmp_path_factory: pytest.TempPathFactory) -> Written:
    walk = make_walk(talos, steps=2)
    path = tmp_path_factory.mktemp("replay") / "walk.html"
    result = write_replay_html(
        path, talos.model, talos.visual_model, walk.times, walk.q, footprints=walk.footprints, sole=walk.sole,
        cog=walk.cog, zmp=walk.zmp, title="two <steps>",
    )  # fmt: skip
    assert result == path
    page = path.read_text(encoding="utf-8")
    return Written(path, page, decode_commands(page), walk)


def test_page_needs_no_network(written: Written) -> None:
    page = written.page
    assert "MeshCat.Viewer" in page and "handle_command_bytearray" in page  # the viewer's JS is inlined
    assert not re.search(r"<script[^>]*\bsrc\s*=", page, re.IGNORECASE)
    assert not re.search(r"<link[^>]*\bhref\s*=", page, re.IGNORECASE)
    assert not re.search(r"@import|url\(\s*['\"]?https?:", page, re.IGNORECASE)
    # The only absolute URL in meshcat's bundle is the XHTML namespace name, an identifier that is never fetched.
    assert set(re.findall(r"https?://[^\s\"'<>)]+", page)) <= {"http://www.w3.org/1999/xhtml"}
    assert "<title>two &lt;steps&gt;</title>" in page


def test_page_holds_every_mesh_footprint_and_path(written: Written, talos: Talos) -> None:
    objects = {c["path"] for c in written.commands if c["type"] == "set_object"}
    robot = {p for p in objects if p.startswith("/rtgait/robot/")}
    assert len(robot) == len(talos.visual_model.geometryObjects)
    for geometry in talos.visual_model.geometryObjects:
        joint = talos.model.names[geometry.parentJoint]
        assert f"/rtgait/robot/{joint}/{geometry.name}" in robot
    footprints = sorted(p for p in objects if p.startswith("/rtgait/footprints/"))
    assert [p.rsplit("_", 1)[1] for p in footprints] == [f.side for f in written.walk.footprints]
    assert {"/rtgait/cog_path", "/rtgait/zmp_path", "/rtgait/cog", "/rtgait/zmp/disc"} <= objects


def test_footprint_rectangles_follow_the_sole(written: Written) -> None:
    """Each box covers the sole rectangle around its footprint: inner edge toward the other foot."""
    sole = written.walk.sole
    transforms = {c["path"]: np.array(c["matrix"]).reshape(4, 4).T for c in written.commands
                  if c["type"] == "set_transform"}  # fmt: skip
    boxes = {c["path"]: c["object"]["geometries"][0] for c in written.commands
             if c["type"] == "set_object" and c["path"].startswith("/rtgait/footprints/")}  # fmt: skip
    for index, foot in enumerate(written.walk.footprints):
        path = f"/rtgait/footprints/{index:03d}_{foot.side}"
        box, pose = boxes[path], transforms[path]
        assert (box["width"], box["height"]) == pytest.approx((sole.front + sole.back, sole.inner + sole.outer))
        y_min, y_max = (-sole.inner, sole.outer) if foot.side == "left" else (-sole.outer, sole.inner)
        expected_centre = [foot.x + 0.5 * (sole.front - sole.back), foot.y + 0.5 * (y_min + y_max)]
        assert pose[:2, 3] == pytest.approx(expected_centre, abs=1e-9)
        assert 0.0 < pose[2, 3] < 0.01  # flat on the ground


def test_animation_replays_the_kinematics(written: Written, talos: Talos) -> None:
    """Keyframes at 25 fps over the whole walk; each joint's keyframe is Pinocchio's forward kinematics."""
    (animation,) = [c for c in written.commands if c["type"] == "set_animation"]
    assert animation["options"]["play"] is True and animation["options"]["repetitions"] == math.inf
    clips = {a["path"]: a["clip"] for a in animation["animations"]}
    joints = {g.parentJoint for g in talos.visual_model.geometryObjects}
    assert {f"/rtgait/robot/{talos.model.names[j]}" for j in joints} <= set(clips)
    assert {"/rtgait/cog", "/rtgait/zmp"} <= set(clips)

    times, q = written.walk.times, written.walk.q
    fps = replay.DEFAULT_FPS
    model, data = talos.model, talos.model.createData()
    for name in ("leg_left_4_joint", "arm_right_1_joint", "root_joint"):
        clip = clips[f"/rtgait/robot/{name}"]
        assert clip["fps"] == fps
        tracks = {t["name"]: t["keys"] for t in clip["tracks"]}
        keys = tracks[".position"]
        assert len(keys) == round(times[-1] * fps) + 1
        assert keys[-1]["time"] / fps == pytest.approx(times[-1])
        for key, quaternion in zip(keys[::7], tracks[".quaternion"][::7], strict=True):
            t = key["time"] / fps
            sample = int(np.argmin(abs(times - t)))
            assert times[sample] == pytest.approx(t, abs=1e-9)  # 25 fps keyframes fall on the 100 Hz samples
            pin.forwardKinematics(model, data, q[sample])
            pose = data.oMi[model.getJointId(name)]
            assert key["value"] == pytest.approx(pose.translation, abs=1e-9)
            x, y, z, w = quaternion["value"]
            assert pin.Quaternion(w, x, y, z).toRotationMatrix() == pytest.approx(pose.rotation, abs=1e-9)


def test_no_meshcat_server_left_running(written: Written) -> None:
    assert written.path.exists()
    assert meshcat_server_children() == []


def test_binary_stl_becomes_an_indexed_mesh(tmp_path: Path) -> None:
    corners = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float32)
    faces = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
    stl = bytearray(b"\0" * 80 + struct.pack("<I", len(faces)))
    for face in faces:
        stl += struct.pack("<3f", 0, 0, 0) + corners[list(face)].tobytes() + b"\0\0"
    (tmp_path / "tet.stl").write_bytes(bytes(stl))
    mesh = replay._read_binary_stl(str(tmp_path / "tet.stl"))
    assert mesh is not None
    vertices, triangles = mesh
    assert len(vertices) == 4 and triangles.shape == (4, 3) and triangles.dtype == np.uint32
    assert np.array_equal(vertices[triangles], corners[np.array(faces)])  # same triangles, same orientation
    (tmp_path / "ascii.stl").write_text("solid t\nfacet normal 0 0 1\nendfacet\nendsolid t\n")
    assert replay._read_binary_stl(str(tmp_path / "ascii.stl")) is None  # left to meshcat's own STL loader


def test_frame_times_cover_the_walk() -> None:
    assert replay._frame_times(np.array([0.0, 1.0]), 4.0) == pytest.approx([0, 0.25, 0.5, 0.75, 1.0])
    assert replay._frame_times(np.array([1.0, 1.3]), 4.0) == pytest.approx([1.0, 1.25, 1.3])
    assert replay._frame_times(np.array([2.0]), 25.0) == pytest.approx([2.0])


def bad_inputs(walk: Walk) -> dict[str, tuple[dict, str]]:
    """name -> (keyword arguments, text the error must contain)."""
    nan_q = walk.q.copy()
    nan_q[2, 9] = np.nan
    zero_rotation = walk.q.copy()
    zero_rotation[4, 3:7] = 0.0  # the free flyer's quaternion
    nan_times = walk.times.copy()
    nan_times[3] = np.nan
    backwards = walk.times.copy()
    backwards[[3, 4]] = backwards[[4, 3]]
    return {
        "q short": ({"q": walk.q[:, :-1]}, "q must have shape"),
        "q rows": ({"q": walk.q[:-1]}, "q must have shape"),
        "q nan": ({"q": nan_q}, "q must be finite"),
        "q zero quaternion": ({"q": zero_rotation}, "q[4] has a zero-length quaternion"),
        "times nan": ({"times": nan_times}, "times must be finite"),
        "times order": ({"times": backwards}, "strictly increasing"),
        "times 2d": ({"times": walk.times[:, None]}, "times must have shape"),
        "cog shape": ({"cog": walk.cog[:, :2]}, "cog must have shape"),
        "zmp shape": ({"zmp": walk.cog}, "zmp must have shape"),
        "zmp nan": ({"zmp": walk.zmp * np.nan}, "zmp must be finite"),
        "foot side": ({"footprints": [Foot(0.0, 0.1, 0.0, "middle")]}, "footprints[0].side"),
        "foot nan": ({"footprints": [*walk.footprints[:2], Foot(np.nan, 0.1, 0.0, "left")]}, "footprints[2].x"),
        "not a footprint": ({"footprints": [object()]}, "footprints[0].x"),
        "sole negative": ({"sole": replace(walk.sole, inner=-0.01)}, "sole.inner"),
        "fps": ({"fps": 0.0}, "fps"),
        "repetitions": ({"repetitions": 0}, "repetitions"),
    }


BAD_NAMES = [
    "q short", "q rows", "q nan", "q zero quaternion", "times nan", "times order", "times 2d", "cog shape",
    "zmp shape", "zmp nan", "foot side", "foot nan", "not a footprint", "sole negative", "fps", "repetitions",
]  # fmt: skip


@pytest.mark.parametrize("name", BAD_NAMES)
def test_bad_input_raises_and_writes_nothing(name: str, talos: Talos, tmp_path: Path) -> None:
    walk = make_walk(talos, steps=1, dt=0.05)
    cases = bad_inputs(walk)
    assert sorted(cases) == sorted(BAD_NAMES)
    kwargs, message = cases[name]
    arguments = {"times": walk.times, "q": walk.q, "footprints": walk.footprints, "sole": walk.sole,
                 "cog": walk.cog, "zmp": walk.zmp} | kwargs  # fmt: skip
    target = tmp_path / "replay.html"
    target.write_text("previous replay")
    with pytest.raises(ValueError, match=re.escape(message)):
        write_replay_html(target, talos.model, talos.visual_model, **arguments)
    assert target.read_text() == "previous replay"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["replay.html"]
    assert meshcat_server_children() == []


def test_missing_folder_raises(talos: Talos, tmp_path: Path) -> None:
    walk = make_walk(talos, steps=1, dt=0.05)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        write_replay_html(tmp_path / "no" / "replay.html", talos.model, talos.visual_model, walk.times, walk.q)


def test_failure_while_writing_leaves_the_old_file(talos: Talos, tmp_path: Path,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:  # fmt: skip
    """A crash between writing the page and renaming it leaves neither a partial page nor a temporary file."""
    walk = make_walk(talos, steps=1, dt=0.05)
    target = tmp_path / "replay.html"
    target.write_text("previous replay")

    def broken_replace(src: str, dst: str) -> None:
        assert Path(src).stat().st_size > 100_000  # the page was written in full, under another name
        raise OSError("disk went away")

    monkeypatch.setattr(replay.os, "replace", broken_replace)
    with pytest.raises(OSError, match="disk went away"):
        write_replay_html(target, talos.model, talos.visual_model, walk.times, walk.q)
    assert target.read_text() == "previous replay"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["replay.html"]
    assert meshcat_server_children() == []
