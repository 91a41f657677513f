"""Fixtures of the replay tests; they need Pinocchio, example-robot-data and meshcat (the robot and viz extras)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

if TYPE_CHECKING:
    from walks import Talos


@pytest.fixture(scope="session")
def talos() -> Talos:
    """Talos with its visual meshes, loaded once per test session."""
    pytest.importorskip("pinocchio")
    from walks import load_talos

    return load_talos()
