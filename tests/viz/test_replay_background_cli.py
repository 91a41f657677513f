"""``--replay-background white`` reaches the replay written by ``rtgait plan --html`` (the page's scene settings)."""

from __future__ import annotations

import pytest

pytest.importorskip("meshcat")
pytest.importorskip("pinocchio")

from rtgait.cli.main import main


@pytest.mark.parametrize("background", ["sky", "white"])
def test_plan_html_background(tmp_path, background):
    out = tmp_path / background
    assert main(["plan", "fig6", "--html", "--no-figures", "--quiet", "--replay-background", background,
                 "--out", str(out)]) == 0  # fmt: skip
    page = (out / "replay.html").read_text(encoding="utf-8")
    assert f'<body class="rtgait-{background}">' in page
