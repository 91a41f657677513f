"""The HTML replay in a real headless Chromium, driven by Playwright: it loads from a file:// URL with the network
cut off and no errors, draws the robot's meshes and the footprints, plays (the clock advances and the robot
moves), shows the legend and the clock, and starts with the whole walk in view.

Playwright drives the Chromium found on the machine (Debian's ``chromium`` package; ``$RTGAIT_CHROMIUM`` to point
at another): its own browser downloads are never used. The tests are skipped, with the reason, when Playwright
or Chromium is missing; anything else that goes wrong fails them. Set ``RTGAIT_REPLAY_SHOTS=<folder>`` to keep
the screenshots (they are always saved under each test's tmp dir).
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")
pytest.importorskip("meshcat")
Image = pytest.importorskip("PIL.Image")  # a meshcat dependency
sync_api = pytest.importorskip(
    "playwright.sync_api", reason="the browser tests drive Chromium with Playwright: pip install playwright"
)

from walks import Talos, Walk, make_walk, phase_at  # noqa: E402

from rtgait.viz.replay import write_replay_html  # noqa: E402

CANDIDATES = ("chromium", "chromium-browser", "/usr/bin/chromium", "/usr/lib/chromium/chromium")
# Headless (Playwright adds --headless), software WebGL, no network of its own (sync, updates, first-run pages),
# no QUIC; --no-sandbox because CI runs as root, where Chromium's sandbox refuses to start.
FLAGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
VIEWPORT = {"width": 1024, "height": 768}


def find_chromium() -> str | None:
    """The Chromium executable (``$RTGAIT_CHROMIUM`` first), or None when there is none."""
    override = os.environ.get("RTGAIT_CHROMIUM")
    for name in ((override,) if override else ()) + CANDIDATES:
        found = shutil.which(name)
        if found:
            return found
    return None


CHROMIUM = find_chromium()
pytestmark = pytest.mark.skipif(
    CHROMIUM is None, reason="no Chromium executable: apt-get install chromium (Debian), or set RTGAIT_CHROMIUM"
)

STEPS = 4
SEEK = 1.2  # s: a keyframe time (25 fps) that is also a walk sample (100 Hz), mid-step

ROBOT_MESHES = "(() => { const out = []; viewer.scene_tree.find(['rtgait', 'robot']).object.traverse(o => { if (o.isMesh) out.push(o); }); return out; })()"  # noqa: E501
NEXT_FRAMES = "new Promise(done => requestAnimationFrame(() => requestAnimationFrame(() => done(true))))"


@dataclass
class Tab:
    """A page in its own offline browser context, with what it requested and every error it reported."""

    page: Any  # playwright.sync_api.Page
    requests: list[str] = field(default_factory=list)
    blocked: list[str] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)

    def evaluate(self, expression: str) -> Any:
        return self.page.evaluate(expression)

    def settle(self) -> None:
        """Let the viewer draw twice, so that what was just changed is on screen."""
        self.page.evaluate(NEXT_FRAMES)


def open_tab(browser: Any, url: str) -> Tab:
    """Open ``url`` in a fresh context with the network cut off: any request other than file: or data: is
    recorded and aborted (and so shows as an error too)."""
    context = browser.new_context(viewport=VIEWPORT, offline=True)
    tab = Tab(context.new_page())

    def route(request_route: Any) -> None:
        url = request_route.request.url
        if url.startswith(("file:", "data:")):
            request_route.continue_()
        else:
            tab.blocked.append(url)
            request_route.abort()

    context.route("**/*", route)
    tab.page.on("request", lambda request: tab.requests.append(request.url))
    tab.page.on("pageerror", lambda error: tab.problems.append(f"exception: {error}"))
    tab.page.on("console", lambda m: tab.problems.append(f"console.{m.type}: {m.text}") if m.type == "error" else None)
    tab.page.on("requestfailed", lambda request: tab.problems.append(f"failed: {request.url} {request.failure}"))
    tab.page.goto(url)
    return tab


def open_replay(browser: Any, html: Path) -> Tab:
    tab = open_tab(browser, html.resolve().as_uri())
    tab.page.wait_for_function("window.rtgait !== undefined", timeout=30_000)  # the page's script ran to its end
    tab.settle()
    return tab


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    """Debian's Chromium under Playwright, with a fresh temporary profile (Playwright makes one per launch)."""
    with sync_api.sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=CHROMIUM, args=FLAGS, headless=True)
        try:
            yield chromium
        finally:
            chromium.close()


@dataclass(frozen=True)
class Replay:
    tab: Tab
    walk: Walk
    html: Path


@pytest.fixture(scope="module")
def replay(browser: Any, talos: Talos, tmp_path_factory: pytest.TempPathFactory) -> Replay:
    walk = make_walk(talos, steps=STEPS)
    html = write_replay_html(
        tmp_path_factory.mktemp("replay") / "walk.html", talos.model, talos.visual_model, walk.times, walk.q,
        footprints=walk.footprints, sole=walk.sole, cog=walk.cog, zmp=walk.zmp, title="browser test",
        phases=walk.phases,
    )  # fmt: skip
    return Replay(open_replay(browser, html), walk, html)


def shot(tab: Tab, tmp_path: Path, name: str) -> np.ndarray:
    """A screenshot, saved under the test's tmp dir (and ``$RTGAIT_REPLAY_SHOTS``), as an RGB int16 array."""
    path = tmp_path / name
    tab.page.screenshot(path=str(path))
    keep = os.environ.get("RTGAIT_REPLAY_SHOTS")
    if keep:
        Path(keep).mkdir(parents=True, exist_ok=True)
        shutil.copy(path, Path(keep) / name)
    return np.asarray(Image.open(path).convert("RGB"), dtype=np.int16)


def pause_at(tab: Tab, t: float) -> None:
    tab.evaluate(f"viewer.animator.pause(); viewer.animator.seek({t}); true")
    tab.settle()


def test_page_loads_offline_without_errors(replay: Replay) -> None:
    tab = replay.tab
    assert tab.problems == []
    assert tab.page.title() == "browser test"
    assert tab.evaluate("typeof MeshCat") == "object"
    # Everything the page loaded came from the file itself: no CDN, no server.
    assert tab.requests == [replay.html.resolve().as_uri()] and tab.blocked == []


def test_error_detection_works(browser: Any, tmp_path: Path) -> None:
    """The same checks catch a broken page (so a clean result above means something)."""
    broken = tmp_path / "broken.html"
    broken.write_text("<script>console.error('bad'); throw new Error('boom');</script>"
                      "<script src='https://cdn.example.invalid/x.js'></script>")  # fmt: skip
    tab = open_tab(browser, broken.resolve().as_uri())
    tab.page.wait_for_timeout(300)
    problems = "\n".join(tab.problems)
    assert "console.error: bad" in problems and "boom" in problems
    assert tab.blocked == ["https://cdn.example.invalid/x.js"]
    tab.page.context.close()


def test_scene_has_the_robot_meshes_and_footprints(replay: Replay, talos: Talos) -> None:
    tab = replay.tab
    geometries = len(talos.visual_model.geometryObjects)
    assert tab.evaluate(f"{ROBOT_MESHES}.length") == geometries
    # Shared meshes: the robot's mesh objects use fewer three.js geometries than there are objects.
    distinct = tab.evaluate(f"new Set({ROBOT_MESHES}.map(o => o.geometry)).size")
    shared = tab.evaluate("JSON.parse(document.getElementById('rtgait-data').textContent).meshes.length")
    primitives = sum(1 for g in talos.visual_model.geometryObjects if not g.meshPath.lower().endswith(".stl"))
    assert distinct == shared + primitives < geometries
    footprints = tab.evaluate(
        "(() => { const n = viewer.scene_tree.find(['rtgait', 'footprints']); return Object.keys(n.children)"
        ".filter(k => n.children[k].find(['<object>']).object.isMesh).length; })()"
    )
    assert footprints == len(replay.walk.footprints)
    actions, duration = tab.evaluate("[viewer.animator.actions.length, viewer.animator.duration]")
    joints = {g.parentJoint for g in talos.visual_model.geometryObjects}
    assert actions == len(joints) + 2  # + the COG and ZMP markers
    assert duration == pytest.approx(replay.walk.times[-1])


# Inside the page, so that no screenshot or round trip comes in between: the animation's time, the page's clock
# (s), the robot's base position (m) and the clock on screen, now and 1 s later.
TWO_READINGS = """new Promise(done => {
  const read = () => {
    const base = new MeshCat.THREE.Vector3();
    viewer.scene_tree.find(['rtgait', 'robot', 'root_joint']).object.getWorldPosition(base);
    const clock = document.getElementById('rtgait-time').textContent;
    return [rtgait.time(), performance.now() / 1000, base.toArray(), clock];
  };
  const first = read();
  setTimeout(() => done([first, read()]), 1000);
})"""


def test_animation_plays(replay: Replay, tmp_path: Path) -> None:
    """Playing, the animation's clock advances with the page's own clock, the clock on screen follows, and the
    robot moves, in the scene and between two screenshots."""
    tab = replay.tab
    duration = float(replay.walk.times[-1])
    tab.evaluate("viewer.animator.seek(0.2); viewer.animator.play(); true")
    tab.settle()
    for _ in range(3):  # a loaded machine can stall the page past a whole loop of the replay: measure again then
        (t1, wall1, base1, text1), (t2, wall2, base2, text2) = tab.evaluate(TWO_READINGS)
        if wall2 - wall1 < duration - 1.0:
            break
    # The replay loops: compare modulo its duration. Software WebGL draws a few frames per second, and the
    # readings are the times of the last frames drawn: they agree to about two frames.
    advance = (t2 - t1) % duration
    assert 0.3 < advance < duration - 0.3 and abs(advance - (wall2 - wall1)) < 0.6, (t1, t2, wall1, wall2)
    assert text2 != text1
    assert np.linalg.norm(np.subtract(base2, base1)) > 0.005  # m: the robot walked on

    before_time = tab.evaluate("rtgait.time()")
    before = shot(tab, tmp_path, "replay_playing_1.png")
    # The next screenshot at least 0.4 s of walk later (modulo the loop), however slow the page draws.
    tab.page.wait_for_function(
        f"(() => {{ const d = ((rtgait.time() - {before_time}) % {duration} + {duration}) % {duration};"
        f" return d > 0.4 && d < {duration} - 0.4; }})()", timeout=30_000,
    )  # fmt: skip
    after = shot(tab, tmp_path, "replay_playing_2.png")
    pause_at(tab, SEEK)
    assert (np.abs(after - before).max(axis=2) > 30).mean() > 0.002  # the robot moved on screen


def test_robot_stands_on_its_footprints_and_follows_the_kinematics(replay: Replay, talos: Talos) -> None:
    tab = replay.tab
    pause_at(tab, SEEK)
    # World positions in the replay's own frame (/rtgait), whatever shift the page applies to centre the view.
    positions = tab.evaluate(
        "(() => { const root = viewer.scene_tree.find(['rtgait']).object; const out = {};"
        " for (const name of ['root_joint', 'leg_left_6_joint', 'leg_right_6_joint', 'head_2_joint']) {"
        "  const v = new MeshCat.THREE.Vector3();"
        "  viewer.scene_tree.find(['rtgait', 'robot', name]).object.getWorldPosition(v);"
        "  out[name] = root.worldToLocal(v).toArray(); }"
        " return out; })()"
    )
    sample = int(np.argmin(abs(replay.walk.times - SEEK)))
    data = talos.model.createData()
    pin.forwardKinematics(talos.model, data, replay.walk.q[sample])
    for name, xyz in positions.items():
        assert xyz == pytest.approx(data.oMi[talos.model.getJointId(name)].translation, abs=1e-4), name

    low, high = tab.evaluate(
        "(() => { const root = viewer.scene_tree.find(['rtgait']).object;"
        " const box = new MeshCat.THREE.Box3().setFromObject(viewer.scene_tree.find(['rtgait', 'robot']).object);"
        " return [root.worldToLocal(box.min.clone()).toArray(), root.worldToLocal(box.max.clone()).toArray()]; })()"
    )
    assert abs(low[2]) < 0.03  # feet on the ground
    assert high[2] > 1.4  # head up: Talos stands about 1.5 m tall in its half-sitting pose
    feet_x = [f.x for f in replay.walk.footprints]
    assert min(feet_x) - 0.3 < low[0] and high[0] < max(feet_x) + 0.4  # over the footprints


def test_legend_and_clock_are_on_screen(replay: Replay, tmp_path: Path) -> None:
    tab = replay.tab
    pause_at(tab, SEEK)
    legend = tab.page.locator("#rtgait-legend")
    clock = tab.page.locator("#rtgait-clock")
    assert legend.is_visible() and clock.is_visible()
    assert legend.inner_text().split("\n") == [
        "left footprints", "right footprints", "COG path and current COG (ball)", "ZMP path and current ZMP (disc)",
    ]  # fmt: skip
    assert tab.page.locator("#rtgait-time").inner_text() == f"{SEEK:.2f}"
    assert tab.page.locator("#rtgait-phase").inner_text() == phase_at(replay.walk, SEEK)
    assert f"/ {replay.walk.times[-1]:.2f} s" in clock.inner_text() and "browser test" in clock.inner_text()
    for box in (legend.bounding_box(), clock.bounding_box()):
        assert box is not None and box["x"] >= 0 and box["y"] >= 0
        assert box["x"] + box["width"] <= VIEWPORT["width"] and box["y"] + box["height"] <= VIEWPORT["height"]
    shot(tab, tmp_path, "replay_overlay.png")


def test_camera_starts_with_the_whole_walk_in_view(replay: Replay) -> None:
    """Every corner of the footprints' box and of the robot's box at the start and at the end projects inside
    the view, and the walk is not lost in the distance (it spans a good part of the view)."""
    tab = replay.tab
    spans = []
    for t in (0.0, float(replay.walk.times[-1])):
        pause_at(tab, t)
        corners = tab.evaluate(
            "(() => { const T = MeshCat.THREE; const out = [];"
            " viewer.scene.updateMatrixWorld(true); viewer.camera.updateMatrixWorld(true);"
            " for (const path of [['rtgait', 'footprints'], ['rtgait', 'robot']]) {"
            "  const box = new T.Box3().setFromObject(viewer.scene_tree.find(path).object);"
            "  for (const x of [box.min.x, box.max.x]) for (const y of [box.min.y, box.max.y])"
            "   for (const z of [box.min.z, box.max.z])"
            "    out.push(new T.Vector3(x, y, z).project(viewer.camera).toArray()); }"
            " return out; })()"
        )
        ndc = np.array(corners)[:, :2]
        assert np.abs(ndc).max() < 1.0, ndc
        spans.append(ndc.max(axis=0) - ndc.min(axis=0))
    assert max(np.max(spans, axis=0)) > 0.8  # of the 2.0 of the whole view, along its larger side


def test_robot_is_drawn(replay: Replay, tmp_path: Path) -> None:
    """The screenshot shows the robot: hiding it changes a large part of the picture."""
    tab = replay.tab
    pause_at(tab, SEEK)
    with_robot = shot(tab, tmp_path, "replay_with_robot.png")
    tab.evaluate("viewer.scene_tree.find(['rtgait', 'robot']).object.visible = false; viewer.set_dirty(); true")
    tab.settle()
    without_robot = shot(tab, tmp_path, "replay_without_robot.png")
    tab.evaluate("viewer.scene_tree.find(['rtgait', 'robot']).object.visible = true; viewer.set_dirty(); true")

    height, width, _ = with_robot.shape
    assert (height, width) == without_robot.shape[:2] == (VIEWPORT["height"], VIEWPORT["width"])
    assert len(np.unique(with_robot.reshape(-1, 3), axis=0)) > 100  # not a blank canvas
    changed = np.abs(with_robot - without_robot).max(axis=2) > 30
    assert changed.mean() > 0.03  # the robot covers more than 3 % of the view...
    rows, cols = np.nonzero(changed)
    # ...around the middle of the view, where the camera looks (the middle of the walk).
    assert 0.2 * width < cols.mean() < 0.8 * width and 0.15 * height < rows.mean() < 0.85 * height
    assert tab.problems == []


def test_white_background(browser: Any, talos: Talos, tmp_path: Path) -> None:
    walk = make_walk(talos, steps=2, dt=0.02)
    html = write_replay_html(
        tmp_path / "white.html", talos.model, talos.visual_model, walk.times, walk.q, footprints=walk.footprints,
        sole=walk.sole, cog=walk.cog, zmp=walk.zmp, planned_zmp=walk.zmp, background="white",
    )  # fmt: skip
    tab = open_replay(browser, html)
    pause_at(tab, 0.8)
    picture = shot(tab, tmp_path, "replay_white.png")
    tab.page.context.close()
    assert tab.problems == []
    height, width, _ = picture.shape
    # The right edge, below meshcat's controls button and away from the walk: the background itself.
    edge = picture[height // 3 : 2 * height // 3, width - 40 :]
    assert (edge.min(axis=2) > 225).mean() > 0.9  # white (the grid's grey lines cross it)
