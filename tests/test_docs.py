"""The API reference builds from the docstrings with pdoc, as ``make docs`` runs it, and documents the planner.

Only ``rtgait.core`` and its subpackages are built here (a few seconds); ``make docs`` builds the whole package.
"""

from __future__ import annotations

import html
import pkgutil
import re
import subprocess
import sys
from pathlib import Path

import pytest

import rtgait.core

pytest.importorskip("pdoc", reason="pdoc is in the dev extra")

CORE_SUBPACKAGES = sorted(
    info.name for info in pkgutil.iter_modules(rtgait.core.__path__, "rtgait.core.") if info.ispkg
)
CORE_TOP_MODULES = sorted(
    info.name for info in pkgutil.iter_modules(rtgait.core.__path__, "rtgait.core.") if not info.ispkg
)
"""The subpackages and top-level modules ``make docs`` names on pdoc's command line (``rtgait.core.__all__`` hides
them otherwise)."""
CORE_MODULES = sorted(info.name for info in pkgutil.walk_packages(rtgait.core.__path__, "rtgait.core."))


def page(root: Path, module: str) -> Path:
    """Where pdoc writes a module's page: its dotted name as a path."""
    return root / (module.replace(".", "/") + ".html")


@pytest.fixture(scope="module")
def api(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("api")
    command = [sys.executable, "-m", "pdoc", "--docformat", "restructuredtext", "--output-directory", str(out)]
    result = subprocess.run(
        [*command, "rtgait.core", *CORE_SUBPACKAGES, *CORE_TOP_MODULES],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    return out


def test_every_core_module_has_a_page(api: Path) -> None:
    assert "rtgait.core.planner.online" in CORE_MODULES  # the walk found the modules
    missing = [name for name in ("rtgait.core", *CORE_MODULES) if not page(api, name).is_file()]
    assert not missing
    assert (api / "index.html").is_file()


def test_the_core_page_documents_every_public_name(api: Path) -> None:
    source = page(api, "rtgait.core").read_text(encoding="utf-8")
    undocumented = [name for name in rtgait.core.__all__ if f'id="{name}"' not in source]
    assert not undocumented
    # The docstrings themselves, not only the names: the planner's methods and its docstring's first line as text.
    assert 'id="OnlinePlanner.sample"' in source
    assert 'id="OnlinePlanner.change_step"' in source
    text = html.unescape(re.sub(r"<[^>]+>", "", source))
    first_line = rtgait.core.OnlinePlanner.__doc__.strip().splitlines()[0].replace("`", "")
    assert first_line in text


def test_subpackage_pages_document_their_classes(api: Path) -> None:
    feedback = page(api, "rtgait.core.laws.feedback").read_text(encoding="utf-8")
    assert 'id="DcmFeedback"' in feedback
    stepping = page(api, "rtgait.core.laws.stepping").read_text(encoding="utf-8")
    assert 'id="StepAdjustment"' in stepping
