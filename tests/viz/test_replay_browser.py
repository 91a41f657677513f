"""The HTML replay in a real headless Chromium: it loads offline without errors, and the robot is drawn,
standing on its footprints and moving as Pinocchio says.

Chromium is driven over the DevTools pipe (tests/viz/cdp.py, standard library only). The test is skipped only
when no Chromium executable exists (CI installs Debian's ``chromium``); anything else that goes wrong fails it.
Set ``RTGAIT_REPLAY_SHOTS=<folder>`` to keep the screenshots.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")
pytest.importorskip("meshcat")
Image = pytest.importorskip("PIL.Image")  # a meshcat dependency

from cdp import Browser, find_chromium  # noqa: E402
from walks import Talos, Walk, make_walk  # noqa: E402

from rtgait.viz.replay import write_replay_html  # noqa: E402

CHROMIUM = find_chromium()
pytestmark = pytest.mark.skipif(
    CHROMIUM is None, reason="no Chromium executable (apt-get install chromium, or set RTGAIT_CHROMIUM)"
)

STEPS = 4
SEEK = 1.2  # s: a keyframe time (25 fps) that is also a walk sample (100 Hz), mid-step

MESH_COUNT = "(() => { let n = 0; viewer.scene_tree.find(['rtgait', 'robot']).object.traverse(o => { if (o.isMesh) n++; }); return n; })()"  # noqa: E501
NEXT_FRAMES = "new Promise(done => requestAnimationFrame(() => requestAnimationFrame(() => done(true))))"


@dataclass(frozen=True)
class Page:
    browser: Browser
    walk: Walk
    html: Path


@pytest.fixture(scope="module")
def page(talos: Talos, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Page]:
    assert CHROMIUM is not None
    walk = make_walk(talos, steps=STEPS)
    html = write_replay_html(
        tmp_path_factory.mktemp("replay") / "walk.html", talos.model, talos.visual_model, walk.times, walk.q,
        footprints=walk.footprints, sole=walk.sole, cog=walk.cog, zmp=walk.zmp, title="browser test",
    )  # fmt: skip
    with Browser(CHROMIUM) as browser:
        browser.open(html.resolve().as_uri())
        # The page decodes its embedded commands asynchronously: wait until every mesh is in the scene.
        expected = len(talos.visual_model.geometryObjects)
        browser.wait_for(f"{MESH_COUNT} >= {expected}", timeout=30)
        browser.evaluate(NEXT_FRAMES)
        yield Page(browser, walk, html)


def shot(page: Page, tmp_path: Path, name: str) -> np.ndarray:
    path = page.browser.screenshot(tmp_path / name)
    keep = os.environ.get("RTGAIT_REPLAY_SHOTS")
    if keep:
        Path(keep).mkdir(parents=True, exist_ok=True)
        shutil.copy(path, Path(keep) / name)
    return np.asarray(Image.open(path).convert("RGB"), dtype=np.int16)


def test_page_loads_offline_without_errors(page: Page) -> None:
    assert page.browser.problems() == []
    assert page.browser.evaluate("document.title") == "browser test"
    assert page.browser.evaluate("typeof MeshCat") == "object"
    # Everything the page loaded came from the file itself: no CDN, no server.
    urls = page.browser.requested_urls()
    assert urls and all(u.startswith(("file:", "data:")) for u in urls), [u[:80] for u in urls]


def test_error_detection_works(page: Page, tmp_path: Path) -> None:
    """The same checks catch a broken page (so a clean result above means something)."""
    broken = tmp_path / "broken.html"
    broken.write_text("<script>console.error('bad'); throw new Error('boom');</script>"
                      "<script src='https://cdn.example.invalid/x.js'></script>")  # fmt: skip
    browser = Browser(str(CHROMIUM))
    try:
        browser.open(broken.resolve().as_uri())
        browser.pump(0.5)
        problems = "\n".join(browser.problems())
        assert "console.error: bad" in problems and "boom" in problems
        assert any(u.startswith("https://cdn.example.invalid") for u in browser.requested_urls())
    finally:
        browser.close()


def test_robot_meshes_and_animation_are_loaded(page: Page, talos: Talos) -> None:
    meshes = page.browser.evaluate(MESH_COUNT)
    assert meshes == len(talos.visual_model.geometryObjects)
    actions, duration, playing = page.browser.evaluate(
        "[viewer.animator.actions.length, viewer.animator.duration, viewer.animator.playing]"
    )
    joints = {g.parentJoint for g in talos.visual_model.geometryObjects}
    assert actions == len(joints) + 2  # + the COG and ZMP markers
    assert duration == pytest.approx(page.walk.times[-1])
    assert playing is True


def test_robot_stands_on_its_footprints_and_follows_the_kinematics(page: Page, talos: Talos) -> None:
    browser = page.browser
    browser.evaluate(f"viewer.animator.pause(); viewer.animator.seek({SEEK}); true")
    browser.evaluate(NEXT_FRAMES)
    # World positions in the replay's own frame (/rtgait), whatever shift the page applies to centre the view.
    positions = browser.evaluate(
        "(() => { const root = viewer.scene_tree.find(['rtgait']).object; const out = {};"
        " for (const name of ['root_joint', 'leg_left_6_joint', 'leg_right_6_joint', 'head_2_joint']) {"
        "  const v = new MeshCat.THREE.Vector3();"
        "  viewer.scene_tree.find(['rtgait', 'robot', name]).object.getWorldPosition(v);"
        "  out[name] = root.worldToLocal(v).toArray(); }"
        " return out; })()"
    )
    sample = int(np.argmin(abs(page.walk.times - SEEK)))
    data = talos.model.createData()
    pin.forwardKinematics(talos.model, data, page.walk.q[sample])
    for name, xyz in positions.items():
        assert xyz == pytest.approx(data.oMi[talos.model.getJointId(name)].translation, abs=1e-4), name

    low, high = browser.evaluate(
        "(() => { const root = viewer.scene_tree.find(['rtgait']).object;"
        " const box = new MeshCat.THREE.Box3().setFromObject(viewer.scene_tree.find(['rtgait', 'robot']).object);"
        " return [root.worldToLocal(box.min.clone()).toArray(), root.worldToLocal(box.max.clone()).toArray()]; })()"
    )
    assert abs(low[2]) < 0.03  # feet on the ground
    assert high[2] > 1.4  # head up: Talos stands about 1.5 m tall in its half-sitting pose
    feet_x = [f.x for f in page.walk.footprints]
    assert min(feet_x) - 0.3 < low[0] and high[0] < max(feet_x) + 0.4  # over the footprints


def test_robot_is_drawn(page: Page, tmp_path: Path) -> None:
    """The screenshot shows the robot: hiding it changes a large part of the picture."""
    browser = page.browser
    browser.evaluate(f"viewer.animator.pause(); viewer.animator.seek({SEEK}); true")
    browser.evaluate(NEXT_FRAMES)
    with_robot = shot(page, tmp_path, "replay_with_robot.png")
    browser.evaluate("viewer.scene_tree.find(['rtgait', 'robot']).object.visible = false; viewer.set_dirty(); true")
    browser.evaluate(NEXT_FRAMES)
    without_robot = shot(page, tmp_path, "replay_without_robot.png")
    browser.evaluate("viewer.scene_tree.find(['rtgait', 'robot']).object.visible = true; viewer.set_dirty(); true")

    height, width, _ = with_robot.shape
    assert (height, width) == without_robot.shape[:2] and height > 300 and width > 300
    assert len(np.unique(with_robot.reshape(-1, 3), axis=0)) > 100  # not a blank canvas
    changed = np.abs(with_robot - without_robot).max(axis=2) > 30
    assert changed.mean() > 0.01  # the robot covers more than 1 % of the view...
    rows, cols = np.nonzero(changed)
    # ...around the middle of the view, where the camera looks (the middle of the walk).
    assert 0.2 * width < cols.mean() < 0.8 * width and 0.15 * height < rows.mean() < 0.85 * height
    assert browser.problems() == []
