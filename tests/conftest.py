"""Fixtures shared by every test folder."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
from scenario_files import scenario_text


@pytest.fixture
def write_scenario(tmp_path: Path) -> Callable[..., Path]:
    """Write a scenario file (see :func:`scenario_text` for the keywords) into ``tmp_path``; returns its path."""

    def write(**values: object) -> Path:
        path = tmp_path / f"{values.get('name', 'probe')}.toml"
        path.write_text(scenario_text(**values), encoding="utf-8")  # type: ignore[arg-type]
        return path

    return write
