"""summary.json is standard JSON: a measure without a value is null, never a bare NaN or Infinity token."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from rtgait.io.summary_json import finite_or_null, summary_text


def _strict(text: str) -> object:
    """Parse as the JSON standard allows: NaN, Infinity and -Infinity are refused."""

    def refuse(token: str) -> None:
        raise ValueError(f"not JSON: {token}")

    return json.loads(text, parse_constant=refuse)


def test_non_finite_numbers_become_null_at_any_depth():
    summary = {
        "margin": math.nan,
        "errors": {"rms": [1.5, math.inf, -math.inf], "max": np.float64("nan")},
        "steps": np.int64(3),
        "pushes": ({"impulse": np.float32(30.0)},),
        "name": "fig8",
    }
    parsed = _strict(summary_text(summary))
    assert parsed == {
        "margin": None,
        "errors": {"rms": [1.5, None, None], "max": None},
        "steps": 3,
        "pushes": [{"impulse": 30.0}],
        "name": "fig8",
    }


def test_finite_values_are_kept_to_the_bit():
    values = [0.1, 1e-300, -2.5e300, 123456.789]
    assert finite_or_null(values) == values
    assert _strict(summary_text({"v": values})) == {"v": values}


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_a_plan_summary_with_a_measure_that_has_no_value_is_valid_json(tmp_path, monkeypatch, bad):
    from rtgait.cli.main import main
    from rtgait.io import plan_files, plan_summary

    original = plan_summary.summarize

    def summarize(result, scenario):  # a measure that cannot exist for this run, as a zero-mass robot gives
        summary = original(result, scenario)
        summary["min_margin"] = bad
        return summary

    monkeypatch.setattr(plan_files, "summarize", summarize)
    out = tmp_path / "o"
    assert main(["plan", "fig8", "--out", str(out), "--no-figures", "--quiet"]) == 0
    assert _strict((out / "summary.json").read_text(encoding="utf-8"))["min_margin"] is None
