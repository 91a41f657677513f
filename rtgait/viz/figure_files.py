"""The figures' file names: each figure by its file stem, in the formats ``--format`` offers (png, pdf, svg)."""

from __future__ import annotations

__all__ = ["FIGURE_FORMATS", "OBSTACLE_FIGURE", "PENDULUM_FIGURE", "PLAN_FIGURES", "figure_file", "plan_figure_files"]

FIGURE_FORMATS = ("png", "pdf", "svg")
"""File formats of the figures (``--format``); png is the default."""

PLAN_FIGURES = ("zmp_cog", "zmp_deviation", "top_view", "zmp_margin")
"""The figures of ``rtgait plan``, by file stem, in the order they are written and listed."""

OBSTACLE_FIGURE = "obstacle"
"""The figure of a plan with obstacles (:mod:`rtgait.viz.obstacle_figure`), by file stem."""

PENDULUM_FIGURE = "pendulum"
"""The figure of ``rtgait simulate --model lipm``, by file stem."""


def figure_file(stem: str, fmt: str = "png") -> str:
    """The file name of the figure ``stem`` in the format ``fmt`` (:data:`FIGURE_FORMATS`)."""
    if fmt not in FIGURE_FORMATS:
        raise ValueError(f"figure format must be one of {', '.join(FIGURE_FORMATS)}, got {fmt!r}")
    return f"{stem}.{fmt}"


def plan_figure_files(fmt: str = "png") -> list[str]:
    """The file names of the four plan figures (:data:`PLAN_FIGURES`) in the format ``fmt``."""
    return [figure_file(stem, fmt) for stem in PLAN_FIGURES]
