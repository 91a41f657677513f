"""What every rtgait figure shares: colours, units, tick labels, axis spans, and writing a figure in any format.

One convention across the figures, so a reader who learnt one reads the others: units in square brackets
(``[m]``, ``[mm]``, ``[s]``, ``[N s]``), positions in m and the small quantities (deviations, margins, errors) in
mm, time in s from the walk's start (:data:`TIME_LABEL`), the same colour for the same quantity.

Figures are built with matplotlib's object API on an Agg canvas: no pyplot state, no display needed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import Formatter

__all__ = [
    "CHANGE_COLOR",
    "COG_COLOR",
    "DOUBLE_COLOR",
    "DPI",
    "MINUS",
    "REF_COLOR",
    "TIME_LABEL",
    "ZMP_COLOR",
    "CleanFormatter",
    "clean_ticks",
    "new_figure",
    "runs",
    "save",
    "signed_mm",
    "span_limits",
]

DPI = 100
TIME_LABEL = "time from the walk's start [s]"
"""Every time axis: t = 0 is the walk's start (the planner's start), in plans and simulations alike."""

ZMP_COLOR = "tab:blue"
REF_COLOR = "black"
COG_COLOR = "tab:red"
BAND_COLOR = "tab:green"
DOUBLE_COLOR = "0.85"
CHANGE_COLOR = "tab:purple"
PUSH_COLOR = "tab:purple"
SIDE_COLORS = {"left": "tab:blue", "right": "tab:orange"}

MINUS = "\N{MINUS SIGN}"  # what matplotlib's own tick labels use for a negative number


def new_figure(width: float, height: float) -> Figure:
    """A figure of ``width`` x ``height`` inches on its own Agg canvas, laid out by matplotlib's constrained layout."""
    figure = Figure(figsize=(width, height), dpi=DPI, layout="constrained")
    FigureCanvasAgg(figure)
    return figure


def save(figure: Figure, path: Path) -> Path:
    """Write ``figure`` to ``path`` in the format its suffix names (``.png``, ``.pdf``, ``.svg``); returns ``path``.

    The PDF and SVG files carry no creation date and SVG ids come from a fixed salt, so the same run gives the
    same bytes: a remade figure can be compared with the first one.
    """
    path = Path(path)
    fmt = path.suffix.lstrip(".").lower()
    metadata = {"pdf": {"CreationDate": None}, "svg": {"Date": None}}.get(fmt)
    with matplotlib.rc_context({"svg.hashsalt": "rtgait"}):
        figure.savefig(path, dpi=DPI, format=fmt, metadata=metadata)
    return path


def _decimals(values: Sequence[float]) -> int:
    """The fewest decimals that write every value of ``values`` (tick positions) exactly."""
    values = [v for v in values if math.isfinite(v)]
    if not values:
        return 0
    spacing = np.diff(sorted(values))
    step = float(spacing[spacing > 0].min()) if np.any(spacing > 0) else max(abs(values[0]), 1.0)
    for decimals in range(10):
        if all(abs(round(v, decimals) - v) <= 1e-3 * step for v in values):
            return decimals
    return 10


class CleanFormatter(Formatter):
    """Tick labels ``value * scale`` with as many decimals as the ticks need and never a negative zero.

    matplotlib's default formatter writes a tick that is zero up to round-off as ``-0.0`` or ``-0.000``, and an
    axis in m of deviations in mm as ``0.005`` steps; this one writes ``0`` and lets an axis be labelled in mm
    (``scale=1000``) while its data stay in m.
    """

    def __init__(self, scale: float = 1.0) -> None:
        self.scale = scale
        self._decimals: int | None = None

    def set_locs(self, locs: Sequence[float]) -> None:
        """Called by the axis with the tick positions before it labels them: they fix the decimals."""
        super().set_locs(locs)
        self._decimals = _decimals([float(v) * self.scale for v in locs]) if len(locs) else None

    def __call__(self, x: float, pos: int | None = None) -> str:
        decimals = self._decimals if self._decimals is not None else _decimals([x * self.scale])
        text = f"{x * self.scale:.{decimals}f}"
        if float(text) == 0.0:
            text = f"{0.0:.{decimals}f}"  # drops the sign of a negative zero
        return text.replace("-", MINUS)


def clean_ticks(ax: Axes, x: bool = True, y: bool = True, y_scale: float = 1.0) -> None:
    """Use :class:`CleanFormatter` on the axes' x and/or y ticks (the y values times ``y_scale``)."""
    if x:
        ax.xaxis.set_major_formatter(CleanFormatter())
    if y:
        ax.yaxis.set_major_formatter(CleanFormatter(y_scale))


def signed_mm(value: float, decimals: int = 1) -> str:
    """``value`` (m) as a signed length in mm for a caption: ``+70.0 mm``, or ``-34.1 mm`` with a true minus sign;
    never ``-0.0 mm``."""
    text = f"{value * 1000:+.{decimals}f}"
    if float(text) == 0.0:
        text = f"{0.0:.{decimals}f}"
    return f"{text.replace('-', MINUS)} mm"


def span_limits(
    values: np.ndarray, min_span: float, include: float | None = None, pad: float = 0.1
) -> tuple[float, float]:
    """Axis limits around the finite ``values``, padded by ``pad`` of their range and at least ``min_span`` wide
    (centred on the data), so near-constant data are not blown up into noise; ``include`` is kept inside too."""
    data = np.asarray(values, dtype=float)
    data = data[np.isfinite(data)]
    points = [float(data.min()), float(data.max())] if data.size else []
    if include is not None:
        points.append(include)
    if not points:
        return -min_span / 2, min_span / 2
    low, high = min(points), max(points)
    low, high = low - pad * (high - low), high + pad * (high - low)
    if high - low < min_span:
        centre = (low + high) / 2
        low, high = centre - min_span / 2, centre + min_span / 2
    return low, high


def runs(mask: np.ndarray, times: np.ndarray) -> list[tuple[float, float]]:
    """``(start, end)`` times (s) of each run of consecutive true ticks; a run ends where the next tick starts."""
    mask = np.asarray(mask, dtype=bool)
    if not mask.any():
        return []
    edges = np.diff(np.concatenate(([0], mask.astype(np.int8), [0])))
    starts = np.flatnonzero(edges == 1)
    ends = np.flatnonzero(edges == -1)  # index one past the run
    dt = float(times[1] - times[0]) if len(times) > 1 else 0.0
    last = float(times[-1]) + dt
    return [(float(times[s]), float(times[e]) if e < len(times) else last) for s, e in zip(starts, ends, strict=True)]
