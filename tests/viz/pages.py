"""Reading a replay page back in Python: its scene data, meshcat commands, shared meshes and animation arrays."""

from __future__ import annotations

import base64
import json
import re
from dataclasses import dataclass
from typing import Any

import numpy as np

DATA = re.compile(r'<script id="rtgait-data" type="application/json">(.*?)</script>', re.DOTALL)


@dataclass(frozen=True)
class Decoded:
    data: dict[str, Any]  # the page's JSON scene
    commands: list[dict[str, Any]]  # meshcat's drawing commands, as the viewer receives them
    times: np.ndarray  # (frames,) s
    positions: dict[str, np.ndarray]  # animated node -> (frames, 3) m
    quaternions: dict[str, np.ndarray]  # animated node -> (frames, 4) x, y, z, w


def b64(text: str, dtype: str) -> np.ndarray:
    return np.frombuffer(base64.b64decode(text), dtype=dtype)


def decode(page: str) -> Decoded:
    (raw,) = DATA.findall(page)
    data = json.loads(raw)
    import umsgpack  # meshcat's message format (a meshcat dependency)

    commands = [umsgpack.unpackb(base64.b64decode(blob)) for blob in data["commands"]]
    animation = data["animation"]
    times = b64(animation["times"], "<f4")
    nodes = animation["nodes"]
    positions = b64(animation["positions"], "<f4").reshape(len(nodes), len(times), 3)
    quaternions = b64(animation["quaternions"], "<f4").reshape(len(nodes), len(times), 4)
    return Decoded(
        data, commands, times, dict(zip(nodes, positions, strict=True)), dict(zip(nodes, quaternions, strict=True))
    )


def mesh_vertices(mesh: dict[str, Any]) -> np.ndarray:
    """A shared mesh's vertices (file units), as the page decodes them."""
    steps = b64(mesh["positions"], "<i2").reshape(-1, 3).astype(np.float64)
    return np.asarray(mesh["offset"]) + np.asarray(mesh["step"]) * steps


def mesh_triangles(mesh: dict[str, Any]) -> np.ndarray:
    return b64(mesh["indices"], "<u4" if mesh["index_bytes"] == 4 else "<u2").reshape(-1, 3)
