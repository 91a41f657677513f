"""The HTML page of the 3D replay: meshcat's viewer, the scene data, and the script that builds the scene.

The page is one file with everything inlined, so it opens from disk with no network: meshcat's viewer bundle
(three.js included), one JSON block with the scene (:func:`page_html` documents its keys), and a short script
that, in order and synchronously:

1. starts the meshcat viewer (the global ``viewer``, as in meshcat's own static export);
2. replays meshcat's drawing commands (footprints, paths, markers, primitives, background);
3. builds one three.js geometry per shared robot mesh and one mesh object per robot geometry that uses it;
4. loads the animation into meshcat's animator (play, pause and the time slider stay in meshcat's controls);
5. points the camera so that the whole walk fits the window, until the user moves the camera;
6. keeps the clock and the walking phase on screen, read from the animation's own time.

meshcat's own export decodes each command in a separate asynchronous ``fetch``; replaying them in one loop keeps
their order and lets the rest of the script run once the scene is complete.
"""

from __future__ import annotations

import html
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import meshcat

__all__ = ["BACKGROUNDS", "LegendEntry", "page_html"]

VIEWER_JS = Path(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js"
"""meshcat's viewer bundle (three.js, dat.GUI, msgpack), inlined in every page."""

BACKGROUNDS = ("sky", "white")
"""The page's backgrounds: meshcat's blue gradient, or white (for figures and print)."""


@dataclass(frozen=True)
class LegendEntry:
    """One line of the legend: ``label`` next to a swatch of ``color`` (0xRRGGBB) shaped as ``shape``: ``"box"``
    (a footprint), ``"line"`` (a path) or ``"marker"`` (a path with the moving marker on it)."""

    label: str
    color: int
    shape: str


CSS = """
html, body { margin: 0; height: 100%; overflow: hidden; }
#meshcat-pane { width: 100vw; height: 100vh; overflow: hidden; }
.rtgait-panel {
  position: absolute; left: 10px; padding: 6px 10px; border-radius: 4px; pointer-events: none;
  font: 13px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, Helvetica, Arial, sans-serif;
  color: #1a1a1a; background: rgba(255, 255, 255, 0.82); box-shadow: 0 1px 3px rgba(0, 0, 0, 0.25);
}
body.rtgait-white .rtgait-panel { background: rgba(245, 245, 245, 0.92); }
#rtgait-clock { top: 10px; font-variant-numeric: tabular-nums; }
#rtgait-clock .rtgait-title { font-weight: 600; }
#rtgait-legend { bottom: 10px; }
.rtgait-key { display: flex; align-items: center; gap: 8px; white-space: nowrap; }
.rtgait-swatch { display: inline-block; width: 22px; height: 12px; position: relative; flex: none; }
.rtgait-swatch.box { border-radius: 2px; opacity: 0.85; }
.rtgait-swatch.line::before, .rtgait-swatch.marker::before {
  content: ""; position: absolute; left: 0; right: 0; top: 5px; height: 2px; background: var(--c);
}
.rtgait-swatch.marker::after {
  content: ""; position: absolute; left: 7px; top: 2px; width: 8px; height: 8px; border-radius: 50%;
  background: var(--c);
}
"""

SCRIPT = r"""
(function () {
  "use strict";
  const THREE = MeshCat.THREE;
  const data = JSON.parse(document.getElementById("rtgait-data").textContent);
  const bytes = (text) => {
    const raw = atob(text);
    const out = new Uint8Array(raw.length);
    for (let i = 0; i < raw.length; i++) out[i] = raw.charCodeAt(i);
    return out;
  };
  const split = (path) => path.split("/").filter((part) => part.length > 0);

  const viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
  window.viewer = viewer;
  viewer.set_3d_pane_size();
  for (const command of data.commands) viewer.handle_command_bytearray(bytes(command));

  // Robot meshes: one geometry per shared mesh, coordinates back from 16-bit steps to file units.
  const geometries = data.meshes.map((mesh) => {
    const steps = new Int16Array(bytes(mesh.positions).buffer);
    const positions = new Float32Array(steps.length);
    for (let i = 0; i < steps.length; i++) positions[i] = mesh.offset[i % 3] + mesh.step[i % 3] * steps[i];
    const indices = bytes(mesh.indices).buffer;
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute("position", new THREE.BufferAttribute(positions, 3));
    geometry.setIndex(new THREE.BufferAttribute(
      mesh.index_bytes === 4 ? new Uint32Array(indices) : new Uint16Array(indices), 1));
    if (mesh.normals !== undefined) {
      geometry.setAttribute("normal", new THREE.BufferAttribute(new Int8Array(bytes(mesh.normals).buffer), 3, true));
    }
    geometry.computeBoundingSphere();
    return geometry;
  });
  const materials = new Map();
  const material = (rgba, flat) => {
    const key = rgba.join(",") + (flat ? ",flat" : "");
    if (!materials.has(key)) {
      // Without normals, flat shading draws each facet with its own normal, as three.js draws an STL file. Both
      // sides are drawn, so that a facet turned over by the simplification leaves no hole.
      materials.set(key, new THREE.MeshPhongMaterial({
        color: new THREE.Color(rgba[0], rgba[1], rgba[2]), opacity: rgba[3], transparent: rgba[3] < 1,
        flatShading: flat, side: THREE.DoubleSide,
      }));
    }
    return materials.get(key);
  };
  for (const part of data.robot) {
    const path = split(part.path);
    const geometry = geometries[part.mesh];
    const mesh = new THREE.Mesh(geometry, material(part.color, geometry.getAttribute("normal") === undefined));
    mesh.castShadow = true;
    mesh.receiveShadow = true;
    viewer.set_transform(path, part.matrix);
    viewer.set_object(path, mesh);
  }

  // Animation: per node, positions and quaternions at the keyframe times (s), into meshcat's animator.
  const animation = data.animation;
  const times = new Float32Array(bytes(animation.times).buffer);
  const positions = new Float32Array(bytes(animation.positions).buffer);
  const quaternions = new Float32Array(bytes(animation.quaternions).buffer);
  const count = times.length;
  viewer.set_animation(animation.nodes.map((node, i) => ({
    path: split(node),
    clip: { name: "default", fps: 1, tracks: [
      { name: ".position", type: "vector3", times: times.slice(),
        values: positions.slice(3 * count * i, 3 * count * (i + 1)) },
      { name: ".quaternion", type: "quaternion", times: times.slice(),
        values: quaternions.slice(4 * count * i, 4 * count * (i + 1)) },
    ] },
  })), { play: true, repetitions: animation.repetitions === null ? Infinity : animation.repetitions });

  // Camera: look at the middle of the walk (the origin of the page's world, where meshcat's orbit controls turn)
  // from view.direction, as close as lets every corner of the walk's bounding box (robot, footprints and paths
  // over the whole replay) fit the window with a margin.
  const view = data.view;
  const camera = viewer.camera;
  let moved = false;
  const frame = () => {
    const back = new THREE.Vector3(...view.direction).normalize();
    const forward = back.clone().negate();
    const right = new THREE.Vector3().crossVectors(forward, new THREE.Vector3(0, 0, 1)).normalize();
    const up = new THREE.Vector3().crossVectors(right, forward);
    camera.fov = view.fov;
    const tanV = Math.tan(THREE.MathUtils.degToRad(view.fov) / 2) / view.margin;
    const tanH = tanV * camera.aspect;
    let distance = 0.5;
    for (const x of [0, 1]) for (const y of [0, 1]) for (const z of [0, 1]) {
      const corner = new THREE.Vector3(view.box[x][0], view.box[y][1], view.box[z][2]);
      corner.sub(new THREE.Vector3(...view.centre));
      const depth = corner.dot(forward);
      distance = Math.max(distance, Math.abs(corner.dot(right)) / tanH - depth,
                          Math.abs(corner.dot(up)) / tanV - depth);
    }
    viewer.scene.updateMatrixWorld(true);
    // Scene coordinates are z up; meshcat turns the whole scene to three.js' y up, and the camera's parent
    // (/Cameras/default/rotated) back, so the camera's position goes through both.
    camera.position.copy(camera.parent.worldToLocal(viewer.scene.localToWorld(back.multiplyScalar(distance))));
    camera.updateProjectionMatrix();
    viewer.controls.update();
    viewer.set_dirty();
  };
  frame();
  viewer.controls.addEventListener("start", () => { moved = true; });
  window.addEventListener("resize", () => { if (!moved) frame(); });

  // Clock and phase, from the time of the first animation track (s, within the current repetition).
  const clock = document.getElementById("rtgait-time");
  const phase = document.getElementById("rtgait-phase");
  const phases = data.overlay.phases;
  let shown = "";
  const tick = () => {
    const actions = viewer.animator.actions;
    const t = actions.length > 0 ? actions[0].time : 0;
    let text = t.toFixed(2);
    let label = "";
    if (phases.length > 0) {
      let lo = 0, hi = phases.length - 1;
      while (lo < hi) { const mid = (lo + hi + 1) >> 1; if (phases[mid][0] <= t + 1e-6) lo = mid; else hi = mid - 1; }
      label = phases[lo][1];
    }
    if (text + label !== shown) {
      clock.textContent = text;
      if (phase) phase.textContent = label;
      shown = text + label;
    }
    requestAnimationFrame(tick);
  };
  tick();
  window.rtgait = { frame: frame, time: () => (viewer.animator.actions[0] || { time: 0 }).time };
})();
"""


def _json_for_script(value: Any) -> str:
    """JSON that cannot end the ``<script>`` element holding it (``<``, ``>`` and ``&`` as escapes)."""
    text = json.dumps(value, separators=(",", ":"), allow_nan=False)
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def _legend_html(entries: list[LegendEntry]) -> str:
    rows = []
    for entry in entries:
        color = f"#{entry.color:06x}"
        style = f"background:{color}" if entry.shape == "box" else f"--c:{color}"
        rows.append(
            f'<div class="rtgait-key"><span class="rtgait-swatch {entry.shape}" style="{style}"></span>'
            f"<span>{html.escape(entry.label)}</span></div>"
        )
    return "".join(rows)


def page_html(
    *,
    title: str,
    data: dict[str, Any],
    legend: list[LegendEntry],
    duration: float,
    background: str,
    has_phases: bool,
) -> str:
    """The whole page.

    Args:
        title: page title, also shown above the clock.
        data: the scene, as JSON: ``commands`` (base64 msgpack meshcat commands, applied in order), ``meshes``
            (:func:`rtgait.viz.replay_meshes.encode_mesh` each), ``robot`` (per geometry: ``path``, ``mesh``
            index, fixed ``matrix`` as 16 column-major numbers, ``color`` RGBA 0..1), ``animation`` (``nodes``,
            base64 float32 ``times`` (s), ``positions`` ``(nodes, frames, 3)`` (m) and ``quaternions``
            ``(nodes, frames, 4)`` (x, y, z, w), ``repetitions`` or null for forever), ``view`` (``box`` of the
            walk and its ``centre`` (m, world; the page shifts the world by -centre), camera ``direction`` from
            the centre, vertical ``fov`` (deg), ``margin`` factor)
            and ``overlay`` (``phases``: ``[start time (s), label]`` pairs in time order).
        legend: the legend's lines, top to bottom.
        duration: length of the replay (s), shown next to the clock.
        background: ``"sky"`` or ``"white"``.
        has_phases: show a phase line under the clock.
    """
    heading = f'<div class="rtgait-title">{html.escape(title)}</div>' if title else ""
    phase = '<div id="rtgait-phase"></div>' if has_phases else ""
    parts = [
        '<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">',
        f"<title>{html.escape(title or 'rtgait replay')}</title>",
        f"<style>{CSS}</style>\n</head>",
        f'<body class="rtgait-{background}">\n<div id="meshcat-pane"></div>',
        f'<div id="rtgait-clock" class="rtgait-panel">{heading}'
        f'<div>t = <span id="rtgait-time">0.00</span> s / {duration:.2f} s</div>{phase}</div>',
    ]
    if legend:
        parts.append(f'<div id="rtgait-legend" class="rtgait-panel">{_legend_html(legend)}</div>')
    parts += [
        f"<script>\n{VIEWER_JS.read_text(encoding='utf-8')}\n</script>",
        f'<script id="rtgait-data" type="application/json">{_json_for_script(data)}</script>',
        f"<script>{SCRIPT}</script>\n</body>\n</html>\n",
    ]
    return "\n".join(parts)
