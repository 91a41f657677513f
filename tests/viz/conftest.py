"""Fixtures of the replay tests; they need Pinocchio, example-robot-data and meshcat (the robot and viz extras)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

if TYPE_CHECKING:
    from walks import Talos


@pytest.fixture(scope="session")
def talos() -> Talos:
    """Talos with its visual meshes, loaded once per test session; skips without example-robot-data's files."""
    pytest.importorskip("pinocchio")
    from walks import load_talos

    from rtgait.robot.data import RobotDataError

    try:
        return load_talos()
    except RobotDataError as exc:
        pytest.skip(f"Talos' URDF and meshes are not installed (example-robot-data): {exc}")
