"""A run's ``summary.json`` as standard JSON: a number that cannot exist (NaN, an infinity) is written ``null``.

Python's ``json`` writes NaN and infinities as the bare tokens ``NaN`` and ``Infinity``, which the JSON standard
(RFC 8259) does not have and strict readers refuse. A summary states measures of a run; where one has no value (a
ZMP error over no tick, a margin of a walk that fell) ``null`` says so.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from typing import Any

__all__ = ["finite_or_null", "summary_text"]


def finite_or_null(value: Any) -> Any:
    """``value`` with every non-finite float in it (in dicts, lists and tuples, at any depth) replaced by ``None``;
    numpy scalars are made Python numbers first (through their ``item()``)."""
    if hasattr(value, "item") and not isinstance(value, (str, bytes)) and getattr(value, "ndim", 1) == 0:
        value = value.item()
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Mapping):
        return {key: finite_or_null(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite_or_null(item) for item in value]
    return value


def summary_text(summary: Mapping[str, Any]) -> str:
    """The text of ``summary.json``: indented standard JSON, non-finite numbers as ``null``, a final newline."""
    return json.dumps(finite_or_null(summary), indent=2, allow_nan=False) + "\n"
