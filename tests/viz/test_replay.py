"""The HTML replay without a browser: what the page holds (decoded from its scene data), that it needs no network,
that it stays small, that repeated meshes are written once, and that bad input writes nothing."""

from __future__ import annotations

import itertools
import math
import os
import re
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")
pytest.importorskip("meshcat")
pytest.importorskip("umsgpack")  # meshcat's message format

from pages import Decoded, decode  # noqa: E402
from walks import Foot, Talos, Walk, make_walk, phase_at  # noqa: E402

from rtgait.viz import replay, replay_scene  # noqa: E402
from rtgait.viz.replay import write_replay_html  # noqa: E402

SIZE_BUDGET = 3_000_000  # bytes: a Talos replay of a 13 s walk, as `rtgait plan fig8 --robot talos --html` writes


def meshcat_server_children() -> list[int]:
    """Live child processes of this test process that are meshcat servers (the replay starts none)."""
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
    decoded: Decoded
    walk: Walk


def write(talos: Talos, walk: Walk, path: Path, **options: object) -> Written:
    result = write_replay_html(
        path, talos.model, talos.visual_model, walk.times, walk.q, footprints=walk.footprints, sole=walk.sole,
        cog=walk.cog, zmp=walk.zmp, **options,
    )  # fmt: skip
    assert result == path
    page = path.read_text(encoding="utf-8")
    return Written(path, page, decode(page), walk)


@pytest.fixture(scope="module")
def written(talos: Talos, tmp_path_factory: pytest.TempPathFactory) -> Written:
    walk = make_walk(talos, steps=2)
    return write(talos, walk, tmp_path_factory.mktemp("replay") / "walk.html", title="two <steps>",
                 phases=walk.phases)  # fmt: skip


def set_objects(decoded: Decoded) -> set[str]:
    """Paths that hold an object: meshcat commands and shared-mesh robot parts."""
    paths = {c["path"] for c in decoded.commands if c["type"] == "set_object"}
    return paths | {part["path"] for part in decoded.data["robot"]}


def test_page_needs_no_network(written: Written) -> None:
    page = written.page
    assert "MeshCat.Viewer" in page and "handle_command_bytearray" in page  # the viewer's JS is inlined
    assert not re.search(r"<script[^>]*\bsrc\s*=", page, re.IGNORECASE)
    assert not re.search(r"<link[^>]*\bhref\s*=", page, re.IGNORECASE)
    assert not re.search(r"@import|url\(\s*['\"]?https?:", page, re.IGNORECASE)
    # The only absolute URL in meshcat's bundle is the XHTML namespace name, an identifier that is never fetched.
    assert set(re.findall(r"https?://[^\s\"'<>)]+", page)) <= {"http://www.w3.org/1999/xhtml"}
    assert "<title>two &lt;steps&gt;</title>" in page
    assert page.count("<script") == page.count("</script>") == 3  # viewer, scene data, the page's own script


def test_page_holds_every_mesh_footprint_and_path(written: Written, talos: Talos) -> None:
    objects = set_objects(written.decoded)
    robot = {p for p in objects if p.startswith("/rtgait/robot/")}
    assert len(robot) == len(talos.visual_model.geometryObjects)
    for geometry in talos.visual_model.geometryObjects:
        joint = talos.model.names[geometry.parentJoint]
        assert f"/rtgait/robot/{joint}/{geometry.name}" in robot
    footprints = sorted(p for p in objects if p.startswith("/rtgait/footprints/"))
    assert [p.rsplit("_", 1)[1] for p in footprints] == [f.side for f in written.walk.footprints]
    assert {"/rtgait/cog_path", "/rtgait/zmp_path", "/rtgait/cog", "/rtgait/zmp/disc"} <= objects
    assert not {"/rtgait/planned_cog_path", "/rtgait/planned_zmp_path"} & objects  # none given


def test_footprint_rectangles_follow_the_sole(written: Written) -> None:
    """Each box covers the sole rectangle around its footprint: inner edge toward the other foot."""
    sole = written.walk.sole
    commands = written.decoded.commands
    transforms = {c["path"]: np.array(c["matrix"]).reshape(4, 4).T for c in commands if c["type"] == "set_transform"}
    boxes = {c["path"]: c["object"]["geometries"][0] for c in commands
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
    animation = written.decoded.data["animation"]
    assert animation["repetitions"] is None  # loops forever
    joints = {g.parentJoint for g in talos.visual_model.geometryObjects}
    nodes = set(animation["nodes"])
    assert {f"/rtgait/robot/{talos.model.names[j]}" for j in joints} | {"/rtgait/cog", "/rtgait/zmp"} == nodes

    times, q = written.walk.times, written.walk.q
    keys = written.decoded.times
    assert len(keys) == round(times[-1] * replay.DEFAULT_FPS) + 1
    assert keys[0] == 0.0 and keys[-1] == pytest.approx(times[-1])
    model, data = talos.model, talos.model.createData()
    for name in ("leg_left_4_joint", "arm_right_1_joint", "root_joint"):
        positions = written.decoded.positions[f"/rtgait/robot/{name}"]
        quaternions = written.decoded.quaternions[f"/rtgait/robot/{name}"]
        for t, position, (x, y, z, w) in list(zip(keys, positions, quaternions, strict=True))[::7]:
            sample = int(np.argmin(abs(times - t)))
            assert times[sample] == pytest.approx(t, abs=1e-6)  # 25 fps keyframes fall on the 100 Hz samples
            pin.forwardKinematics(model, data, q[sample])
            pose = data.oMi[model.getJointId(name)]
            assert position == pytest.approx(pose.translation, abs=1e-6)  # float32 in the page
            rotation = pin.Quaternion(float(w), float(x), float(y), float(z)).normalized().toRotationMatrix()
            assert rotation == pytest.approx(pose.rotation, abs=1e-6)
    cog = written.decoded.positions["/rtgait/cog"]
    assert cog[-1] == pytest.approx(written.walk.cog[-1], abs=1e-6)


def test_legend_clock_and_phases(written: Written) -> None:
    page = written.page
    legend = re.search(r'<div id="rtgait-legend"[^>]*>(.*?)</div>\n', page, re.DOTALL)
    assert legend is not None
    labels = re.findall(r"<span>([^<]*)</span>", legend.group(1))
    assert labels == [
        "left footprints", "right footprints", "COG path and current COG (ball)", "ZMP path and current ZMP (disc)",
    ]  # fmt: skip
    assert 'class="rtgait-swatch box" style="background:#1f77b4"' in legend.group(1)
    clock = re.search(r'<div id="rtgait-clock"[^>]*>(.*?)</div>\n', page, re.DOTALL)
    assert clock is not None
    assert "two &lt;steps&gt;" in clock.group(1) and f"/ {written.walk.times[-1]:.2f} s" in clock.group(1)
    assert 'id="rtgait-time"' in clock.group(1) and 'id="rtgait-phase"' in clock.group(1)
    runs = written.decoded.data["overlay"]["phases"]
    assert runs[0] == [0.0, written.walk.phases[0]]
    assert all(a[1] != b[1] and a[0] < b[0] for a, b in itertools.pairwise(runs))  # one entry per change
    for start, label in runs:
        assert phase_at(written.walk, start) == label


def test_view_frames_the_whole_walk(written: Written) -> None:
    """The camera's box holds every footprint and the robot standing (Talos' head at about 1.5 m)."""
    view = written.decoded.data["view"]
    low, high = np.array(view["box"])
    xs = [f.x for f in written.walk.footprints]
    ys = [f.y for f in written.walk.footprints]
    assert low[0] < min(xs) - 0.09 and high[0] > max(xs) + 0.1 and low[1] < min(ys) and high[1] > max(ys)
    assert low[2] <= 0.0 and 1.4 < high[2] < 1.9
    assert view["centre"] == pytest.approx(0.5 * (low + high))
    shift = [c for c in written.decoded.commands if c["type"] == "set_transform" and c["path"] == "/rtgait"]
    assert np.array(shift[-1]["matrix"]).reshape(4, 4).T[:3, 3] == pytest.approx(-0.5 * (low + high))


def test_no_meshcat_server_left_running(written: Written) -> None:
    assert written.path.exists()
    assert meshcat_server_children() == []


def test_white_background_and_planned_paths(talos: Talos, tmp_path: Path) -> None:
    walk = make_walk(talos, steps=1, dt=0.05)
    planned_zmp = walk.zmp + 0.01
    result = write(talos, walk, tmp_path / "white.html", background="white", planned_zmp=planned_zmp,
                   planned_cog=walk.cog + 0.01)  # fmt: skip
    backgrounds = {(c["property"], tuple(c["value"])) for c in result.decoded.commands
                   if c["type"] == "set_property" and c["path"] == "/Background"}  # fmt: skip
    assert backgrounds == {("top_color", (1.0, 1.0, 1.0)), ("bottom_color", (1.0, 1.0, 1.0))}
    assert '<body class="rtgait-white">' in result.page
    line = next(c for c in result.decoded.commands if c["path"] == "/rtgait/planned_zmp_path")
    assert line["object"]["materials"][0]["color"] == replay_scene.PLANNED_ZMP_COLOR
    for label in ("COG path (measured) and current COG (ball)", "COG path (planned)",
                  "ZMP path (measured) and current ZMP (disc)", "ZMP path (planned)"):  # fmt: skip
        assert f"<span>{label}</span>" in result.page
    unlabelled = write(talos, walk, tmp_path / "plan.html", path_source="planned")
    assert "<span>ZMP path (planned) and current ZMP (disc)</span>" in unlabelled.page
    assert '<body class="rtgait-sky">' in unlabelled.page and 'id="rtgait-phase"' not in unlabelled.page


def test_phase_labels_cannot_break_the_page(talos: Talos, tmp_path: Path) -> None:
    walk = make_walk(talos, steps=1, dt=0.05)
    labels = ["</script><script>alert(1)</script>"] * len(walk.times)
    result = write(talos, walk, tmp_path / "labels.html", phases=labels)
    assert result.page.count("</script>") == 3
    assert result.decoded.data["overlay"]["phases"] == [[0.0, labels[0]]]


# ---------------------------------------------------------------------------------------------- size and sharing


@pytest.fixture(scope="module")
def long_walk(talos: Talos, tmp_path_factory: pytest.TempPathFactory) -> Written:
    """A Talos walk as long as fig8's (16 steps, 12.8 s at 200 Hz), with every option that adds bytes."""
    walk = make_walk(talos, steps=16, dt=0.005)
    return write(talos, walk, tmp_path_factory.mktemp("long") / "replay.html", phases=walk.phases,
                 planned_cog=walk.cog, planned_zmp=walk.zmp, title="fig8-long walk")  # fmt: skip


def test_talos_replay_fits_the_size_budget(long_walk: Written) -> None:
    pytest.importorskip("trimesh", reason="the meshes are simplified with trimesh and fast-simplification")
    pytest.importorskip("fast_simplification", reason="the meshes are simplified with fast-simplification")
    size = long_walk.path.stat().st_size
    assert size < SIZE_BUDGET, f"{size / 1e6:.2f} MB"
    meshes = long_walk.decoded.data["meshes"]
    assert all(m["triangles"] <= 2 * replay.MESH_TRIANGLES for m in meshes)  # decimation may stop a little above
    assert sum(len(m["positions"]) + len(m["indices"]) + len(m.get("normals", "")) for m in meshes) < 1_200_000


def test_repeated_and_mirrored_meshes_are_written_once(long_walk: Written, talos: Talos) -> None:
    """Talos' right limbs draw the left limbs' STL files mirrored (-1 mesh scale): one mesh for both."""
    parts = {part["path"]: part for part in long_walk.decoded.data["robot"]}
    files = {}
    for geometry in talos.visual_model.geometryObjects:
        path = f"/rtgait/robot/{talos.model.names[geometry.parentJoint]}/{geometry.name}"
        if path in parts:
            files.setdefault(geometry.meshPath, set()).add(parts[path]["mesh"])
    assert all(len(indices) == 1 for indices in files.values())  # one mesh per file...
    assert len(long_walk.decoded.data["meshes"]) == len({i for (i,) in files.values()}) < len(parts)  # ...shared
    left = parts["/rtgait/robot/leg_left_4_joint/leg_left_4_link_0"]
    right = parts["/rtgait/robot/leg_right_4_joint/leg_right_4_link_0"]
    assert left["mesh"] == right["mesh"]
    assert np.linalg.det(np.array(right["matrix"]).reshape(4, 4)) == pytest.approx(-1.0)  # mirrored in y
    assert np.linalg.det(np.array(left["matrix"]).reshape(4, 4)) == pytest.approx(1.0)


def test_full_meshes_on_request(talos: Talos, tmp_path: Path) -> None:
    """mesh_triangles=None keeps every triangle of every distinct mesh."""
    pytest.importorskip("trimesh")
    walk = make_walk(talos, steps=1, dt=0.05)
    full = write(talos, walk, tmp_path / "full.html", mesh_triangles=None)
    small = write(talos, walk, tmp_path / "small.html")
    triangles_full = sum(m["triangles"] for m in full.decoded.data["meshes"])
    triangles_small = sum(m["triangles"] for m in small.decoded.data["meshes"])
    assert triangles_full > 100_000 > 3 * triangles_small  # Talos: 25 distinct files, 102 244 triangles


# ---------------------------------------------------------------------------------------------- input checks


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
        "planned cog shape": ({"planned_cog": walk.zmp}, "planned_cog must have shape"),
        "planned zmp nan": ({"planned_zmp": walk.zmp * np.nan}, "planned_zmp must be finite"),
        "foot side": ({"footprints": [Foot(0.0, 0.1, 0.0, "middle")]}, "footprints[0].side"),
        "foot nan": ({"footprints": [*walk.footprints[:2], Foot(np.nan, 0.1, 0.0, "left")]}, "footprints[2].x"),
        "not a footprint": ({"footprints": [object()]}, "footprints[0].x"),
        "sole negative": ({"sole": replace(walk.sole, inner=-0.01)}, "sole.inner"),
        "fps": ({"fps": 0.0}, "fps"),
        "repetitions": ({"repetitions": 0}, "repetitions"),
        "phases length": ({"phases": walk.phases[:-1]}, "phases must have one label per sample"),
        "phases type": ({"phases": [*walk.phases[:-1], 3]}, f"phases[{len(walk.times) - 1}] must be a string"),
        "phases string": ({"phases": "double"}, "phases must be a sequence of labels"),
        "background": ({"background": "black"}, "background must be one of"),
        "path source": ({"path_source": "guessed"}, "path_source must be"),
        "mesh triangles": ({"mesh_triangles": 0}, "mesh_triangles must be"),
    }


BAD_NAMES = [
    "q short", "q rows", "q nan", "q zero quaternion", "times nan", "times order", "times 2d", "cog shape",
    "zmp shape", "zmp nan", "planned cog shape", "planned zmp nan", "foot side", "foot nan", "not a footprint",
    "sole negative", "fps", "repetitions", "phases length", "phases type", "phases string", "background",
    "path source", "mesh triangles",
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


def test_single_sample_replay(talos: Talos, tmp_path: Path) -> None:
    """One configuration still makes a page: a still robot, one keyframe."""
    result = write_replay_html(tmp_path / "still.html", talos.model, talos.visual_model, [0.0],
                               talos.half_sitting[None, :])  # fmt: skip
    decoded = decode(result.read_text(encoding="utf-8"))
    assert len(decoded.times) == 1 and decoded.data["animation"]["repetitions"] is None
    assert not math.isnan(decoded.data["view"]["box"][1][2])
