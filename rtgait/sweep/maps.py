"""The paper's conclusion as a map: where each method keeps the ZMP inside, over step change x double support.

:func:`write_map` reads a sweep folder (``results.csv`` and ``sweep.json``, :mod:`rtgait.sweep`) and writes
``map.png`` and ``map.pdf``. One panel per method (real-time, quasi-real-time, auto, preview control) and single-
support time: the signed minimum ZMP margin of every case as a colour (red: the ZMP leaves the support polygon),
the region where it stays inside outlined by its boundary (margin 0), the paper's four cases marked where they fall,
and, when the sweep walked its cases in physics, each case's outcome as a marker. A last panel per single-support
time compares the two connections: how much more margin the quasi-real-time connection keeps than the real-time
one, with the crossover (1 mm better) drawn, beyond which deciding one double support earlier pays.

The step change on the x axis is the new step length minus the walk's own (m): the paper's fig6 changes 0.11 to
0.12 m, the others 0.05 to 0.15 m, so fig6 sits at +0.01 m on a map whose base steps are 0.05 m long.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

PAPER_CASES = (
    # name, method, single support (s), double support (s), step change (m), the paper's outcome, label offset (pt)
    ("fig4", "real-time", 0.8, 0.2, 0.10, "falls", (8, -12)),
    ("fig6", "real-time", 0.8, 0.2, 0.01, "walks", (-62, 8)),
    ("fig7", "real-time", 0.8, 1.5, 0.10, "walks", (8, -12)),
    ("fig8", "quasi-real-time", 0.7, 0.1, 0.10, "keeps balance", (8, 6)),
)
"""The paper's Section 5 cases, in map coordinates."""
METHOD_ORDER = ("real-time", "quasi-real-time", "auto", "preview")
TITLES = {"real-time": "real-time connection", "quasi-real-time": "quasi-real-time connection",
          "auto": "auto (chosen per change)", "preview": "preview control (Kajita 2003)"}  # fmt: skip
MARGIN_RANGE = (-0.2, 0.08)
GAIN_RANGE = 0.2
"""Top of the colour range of the margin quasi-real-time gains over real-time (m)."""
DOUBLE_TICKS = (0.05, 0.1, 0.2, 0.5, 1.0, 1.5)
"""Colour range of the margin (m): beyond 20 cm outside every case looks the same."""
CROSSOVER = 0.001
"""How much more margin (m) quasi-real-time must keep than real-time to count as better on the crossover line."""


def write_map(folder: Path, physics_from: Path | None = None) -> list[Path]:
    """Draw the map of the sweep in ``folder`` into ``folder/map.png`` and ``map.pdf``; returns the paths (none when
    the sweep has no double-support or step-change axis to map). ``physics_from``: another sweep folder (of the same
    base, coarser, walked with ``--physics``) whose physics outcomes are drawn over this one's margins."""
    from rtgait.outputs import write_atomic
    from rtgait.sweep.store import read_results

    folder = Path(folder)
    meta = json.loads((folder / "sweep.json").read_text(encoding="utf-8"))
    rows = read_results(folder)
    physics = None
    if physics_from is not None:
        physics = read_results(physics_from)
        meta = {
            **meta,
            "physics": True,
            "robot": json.loads((Path(physics_from) / "sweep.json").read_text(encoding="utf-8")).get("robot"),
        }
    figure = plot_map(rows, meta, physics)
    if figure is None:
        return []
    paths = []
    for name, fmt in (("map.png", "png"), ("map.pdf", "pdf")):
        write_atomic(folder / name, lambda path, fmt=fmt: figure.savefig(path, format=fmt, dpi=150))
        paths.append(folder / name)
    import matplotlib.pyplot as plt

    plt.close(figure)
    return paths


def _x_values(row: dict[str, Any], meta: dict[str, Any]) -> float:
    """A case's step change (m): its new length minus its walk's step length."""
    base = row.get("walk.step_length", meta["step_length"])
    new = row.get("change.length", meta["change_length"])
    return float(new) - float(base)


def plot_map(rows: list[dict[str, Any]], meta: dict[str, Any], physics: list[dict[str, Any]] | None = None):
    """The map figure (matplotlib) for the rows of ``results.csv`` and the sweep's ``sweep.json`` (physics markers
    from ``physics`` rows if given, else from ``rows``); ``None`` when the sweep does not vary both the change and
    the double support."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import TwoSlopeNorm

    axes = meta["axes"]
    if not rows or "timing.double_support" not in axes or not ({"change.length", "walk.step_length"} & set(axes)):
        return None
    rows = _first_of_other_axes(rows, axes)
    methods = [m for m in METHOD_ORDER if any(r.get("connection", meta["connection"]) == m for r in rows)]
    singles = sorted({float(r.get("timing.single_support", meta["single_support"])) for r in rows})
    compare = {"real-time", "quasi-real-time"} <= set(methods)
    columns = len(methods) + compare
    figure, grid = plt.subplots(len(singles), columns, figsize=(3.6 * columns + 1.2, 3.3 * len(singles) + 0.9),
                                squeeze=False, sharex=True, sharey=True, layout="constrained")  # fmt: skip
    norm = TwoSlopeNorm(vmin=MARGIN_RANGE[0] * 1e3, vcenter=0.0, vmax=MARGIN_RANGE[1] * 1e3)
    image = None
    for i, single in enumerate(singles):
        fields = {}
        for j, method in enumerate(methods):
            ax = grid[i, j]
            x, y, margin, picked = _field(rows, meta, method, single)
            fields[method] = (x, y, margin)
            image = ax.pcolormesh(x, y, margin * 1e3, cmap="RdYlBu", norm=norm, shading="nearest")
            if np.nanmin(margin) < 0.0 < np.nanmax(margin):
                ax.contour(x, y, margin, levels=[0.0], colors="k", linewidths=1.6)
            _physics(ax, picked if physics is None else _panel_rows(physics, meta, method, single), meta)
            _paper_cases(ax, method, single, singles)
            ax.set_title(f"{TITLES[method]}\nT_s = {single:g} s", fontsize=9)
        if compare:
            _comparison(grid[i, -1], fields, single)
    for ax in grid[-1]:
        ax.set_xlabel("step change [m]")
    for ax in grid[:, 0]:
        ax.set_ylabel("double support T_dbl [s]")
    from matplotlib.ticker import FixedLocator, NullLocator

    ticks = [t for t in DOUBLE_TICKS if min(axes["timing.double_support"]) <= t <= max(axes["timing.double_support"])]
    for ax in grid.ravel():
        ax.set_yscale("log")
        ax.yaxis.set_major_locator(FixedLocator(ticks))
        ax.yaxis.set_minor_locator(NullLocator())
        ax.set_yticklabels([f"{t:g}" for t in ticks])
        ax.tick_params(labelsize=8)
    bar = figure.colorbar(image, ax=grid[:, : len(methods)].ravel().tolist(), shrink=0.85, extend="both")
    bar.set_label("minimum ZMP margin (mm), < 0: outside the sole", fontsize=9)
    handles = _legend_handles(meta)
    figure.legend(handles=handles, loc="outside lower center", ncol=len(handles), fontsize=8, frameon=False)
    figure.suptitle(f"Where the ZMP stays inside: {meta['base']}, change at step {meta['change_step']} "
                    f"({len(rows)} cases; black line: margin 0)", fontsize=11)  # fmt: skip
    return figure


def _first_of_other_axes(rows: list[dict[str, Any]], axes: dict[str, list]) -> list[dict[str, Any]]:
    """Rows at the first value of every axis the map does not show (change.step, a second length axis)."""
    shown = {"timing.double_support", "timing.single_support", "connection", "change.length"}
    if "change.length" not in axes:
        shown.add("walk.step_length")
    keep = {name: values[0] for name, values in axes.items() if name not in shown}
    return [r for r in rows if all(r.get(name) == value for name, value in keep.items())]


def _panel_rows(rows, meta, method: str, single: float) -> list[dict[str, Any]]:
    return [r for r in rows if r.get("connection", meta["connection"]) == method
            and float(r.get("timing.single_support", meta["single_support"])) == single]  # fmt: skip


def _field(rows, meta, method: str, single: float):
    """Grid ``x`` (change, m), ``y`` (double support, s) and the margin (m, NaN where missing) of one panel."""
    picked = _panel_rows(rows, meta, method, single)
    xs = np.array([_x_values(r, meta) for r in picked])
    ys = np.array([float(r.get("timing.double_support", meta["double_support"])) for r in picked])
    x, y = np.unique(np.round(xs, 9)), np.unique(np.round(ys, 9))
    margin = np.full((len(y), len(x)), np.nan)
    for r, xv, yv in zip(picked, xs, ys, strict=True):
        margin[np.searchsorted(y, round(yv, 9)), np.searchsorted(x, round(xv, 9))] = r["zmp_margin_min"]
    return x, y, margin, picked


def _physics(ax, picked, meta) -> None:
    """Each case walked in physics as a marker: fell (x), tipped (triangle), walked (dot), failed to run (grey)."""
    walked = [r for r in picked if r.get("physics") in ("ok", "failed")]
    if not walked:
        return
    for test, style in _PHYSICS_STYLES:
        chosen = [r for r in walked if test(r)]
        if chosen:
            ax.scatter([_x_values(r, meta) for r in chosen], [float(r.get("timing.double_support",
                       meta["double_support"])) for r in chosen], **style)  # fmt: skip


_HOLLOW = {"facecolors": "none", "edgecolors": "k"}
_PHYSICS_STYLES = (
    (lambda r: r.get("physics") == "failed", {"marker": "s", "s": 14, "facecolors": "none", "edgecolors": "0.4"}),
    (lambda r: r.get("fell") is True, {"marker": "x", "s": 22, "c": "k", "linewidths": 1.2}),
    (lambda r: r.get("fell") is False and r.get("tipped") is True, {"marker": "^", "s": 16, **_HOLLOW}),
    (lambda r: r.get("fell") is False and r.get("tipped") is False, {"marker": "o", "s": 9, "c": "k"}),
)


def _paper_cases(ax, method: str, single: float, singles: list[float]) -> None:
    """The paper's cases of this method, on the row of their single-support time (else the nearest one)."""
    for name, case_method, case_single, double, change, outcome, offset in PAPER_CASES:
        nearest = min(singles, key=lambda s: abs(s - case_single))
        if case_method != method or nearest != single:
            continue
        note = "" if abs(nearest - case_single) < 1e-9 else f", T_s {case_single:g}"
        ax.plot(change, double, marker="*", ms=13, mfc="gold", mec="k", mew=0.8, zorder=5, ls="none")
        ax.annotate(f"{name}: {outcome}{note}", (change, double), xytext=offset, textcoords="offset points",
                    fontsize=8, weight="bold",
                    bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": "none", "alpha": 0.8})  # fmt: skip


def _comparison(ax, fields, single: float) -> None:
    """Margin gained by the quasi-real-time connection over the real-time one, with the crossover line."""
    (x, y, rt), (xq, yq, qrt) = fields["real-time"], fields["quasi-real-time"]
    if rt.shape != qrt.shape or not (np.array_equal(x, xq) and np.array_equal(y, yq)):
        ax.set_visible(False)
        return
    gain = (qrt - rt) * 1e3
    mesh = ax.pcolormesh(x, y, gain, cmap="Greens", vmin=0.0, vmax=GAIN_RANGE * 1e3, shading="nearest")
    if np.nanmin(gain) < CROSSOVER * 1e3 < np.nanmax(gain):
        lines = ax.contour(x, y, gain, levels=[CROSSOVER * 1e3], colors="purple", linewidths=1.8)
        ax.clabel(lines, fmt={CROSSOVER * 1e3: "crossover"}, fontsize=8)
    for field, style in ((rt, "-"), (qrt, "--")):
        if np.nanmin(field) < 0.0 < np.nanmax(field):
            ax.contour(x, y, field, levels=[0.0], colors="k", linewidths=1.0, linestyles=style)
    ax.set_title(f"quasi-real-time minus real-time\nT_s = {single:g} s (solid/dashed: their boundaries)", fontsize=9)
    bar = ax.figure.colorbar(mesh, ax=ax, shrink=0.85, extend="max")
    bar.set_label("margin gained [mm]", fontsize=8)


def _legend_handles(meta: dict[str, Any]) -> list:
    from matplotlib.lines import Line2D

    handles = [
        Line2D([], [], color="k", lw=1.6, label="ZMP boundary (margin 0)"),
        Line2D([], [], marker="*", ms=11, mfc="gold", mec="k", ls="none", label="the paper's cases"),
        Line2D([], [], color="purple", lw=1.8, label=f"crossover: quasi-real-time {CROSSOVER * 1e3:g} mm better"),
    ]
    if meta.get("physics"):
        robot = meta.get("robot") or "robot"
        handles += [
            Line2D([], [], marker="o", ms=4, c="k", ls="none", label=f"{robot} walks (MuJoCo)"),
            Line2D([], [], marker="^", ms=5, mfc="none", mec="k", ls="none", label="a foot tips"),
            Line2D([], [], marker="x", ms=6, c="k", ls="none", label="falls"),
        ]
    return handles


__all__ = ["CROSSOVER", "PAPER_CASES", "plot_map", "write_map"]
