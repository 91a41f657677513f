"""A scenario's walk on the point-mass pendulum, in closed loop (:mod:`rtgait.core.pendulum.loop`), and its files.

``simulate_pendulum(scenario, controller, pushes)`` walks the scenario as ``rtgait simulate --model lipm`` does:
the scenario's strides, its footstep changes handed to the planner at their connection mode's deadlines (as
``rtgait plan`` does), the planner of the scenario's robot, timing and connection mode, a controller level and
a point mass on the linear inverted pendulum at the scenario's COG height. ``write_pendulum_outputs(result, folder)``
writes ``sim.csv`` and ``summary.json``.

``sim.csv`` has one row per control tick, the state at the tick's time and the ZMPs held over the tick, all in SI
units (s, m, m/s), columns :data:`PENDULUM_CSV_COLUMNS`:

* ``t``: time (s) from the start of the walk;
* ``cog_planned_x, _y``, ``dcm_planned_x, _y``, ``zmp_planned_x, _y``: the plan's COM, DCM and ZMP at ``t`` (m);
* ``zmp_reference_x, _y``: the tick's reference ZMP, the hold-equivalent of the planned ZMP over the tick (m);
* ``zmp_command_x, _y``: the controller's ZMP (m); ``zmp_real_x, _y``: what the feet produced, the command clipped
  to the support polygon (m); both ``nan`` on the tick the mass was found fallen (the last);
* ``cog_x, _y``, ``cog_vx, _vy``, ``dcm_x, _y``: the point mass's COM (m), velocity (m/s) and DCM (m);
* ``support``: ``double``, ``left`` or ``right`` (the foot on the ground), ``phase``: the planner's phase index;
* ``saturated``: 1 when the ZMP the controller wanted lay outside the support polygon (the command is then on its
  boundary), else 0.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import numpy as np

from rtgait.core.geometry.support import SUPPORT_NAMES
from rtgait.core.laws.feedback import DcmFeedbackGains
from rtgait.core.laws.stepping import StepAdjustment
from rtgait.core.pendulum.loop import DEFAULT_DT, DEFAULT_MASS, ClosedLoopResult, run_pendulum_loop
from rtgait.core.planner.levels import DEFAULT_REPLAN_DCM_ERROR, ControllerLevel, check_level
from rtgait.core.push import Push
from rtgait.io.summary_json import summary_text
from rtgait.outputs import write_atomic, write_text_atomic
from rtgait.scenario.scenario import Scenario

__all__ = [
    "DEFAULT_MASS",
    "PENDULUM_CSV_COLUMNS",
    "PENDULUM_FILES",
    "PushLike",
    "as_push",
    "scenario_mass",
    "simulate_pendulum",
    "write_pendulum_outputs",
]

PENDULUM_CSV_COLUMNS = (
    "t", "cog_planned_x", "cog_planned_y", "dcm_planned_x", "dcm_planned_y", "zmp_planned_x", "zmp_planned_y",
    "zmp_reference_x", "zmp_reference_y", "zmp_command_x", "zmp_command_y", "zmp_real_x", "zmp_real_y",
    "cog_x", "cog_y", "cog_vx", "cog_vy", "dcm_x", "dcm_y", "support", "phase", "saturated",
)  # fmt: skip
"""Columns of the pendulum's ``sim.csv`` (module docstring)."""

PENDULUM_FILES = ("sim.csv", "summary.json")
"""Files written by :func:`write_pendulum_outputs`."""

PushLike = Push | tuple[float, float, float, float]
"""A :class:`~rtgait.core.pendulum.plant.Push`, or ``(start, duration, fx, fy)`` in s, s, N, N (the CLI's
``--push``)."""

_FLOAT_FORMAT = "%.10g"  # as the other CSV files: sub-micrometre for positions within 100 m


def as_push(push: PushLike) -> Push:
    """``push`` as a :class:`Push`; a tuple is ``(start, duration, fx, fy)`` (s, s, N, N)."""
    if isinstance(push, Push):
        return push
    try:
        start, duration, fx, fy = push
    except (TypeError, ValueError):
        raise ValueError(f"a push is a Push or (start, duration, fx, fy) in s, s, N, N; got {push!r}") from None
    return Push(float(start), float(duration), (float(fx), float(fy)))


def scenario_mass(scenario: Scenario, mass: float | None = None) -> float:
    """The point mass (kg): ``mass`` if given, else the scenario's ``[robot] mass`` if it has one, else
    :data:`DEFAULT_MASS` (57 kg, HRP-2-like)."""
    if mass is None:
        mass = getattr(scenario, "mass", None)  # scenario files may not carry a mass
    if mass is None:
        return DEFAULT_MASS
    mass = float(mass)
    if not (math.isfinite(mass) and mass > 0.0):
        raise ValueError(f"mass must be a finite mass > 0 kg, got {mass}")
    return mass


def simulate_pendulum(
    scenario: Scenario,
    controller: ControllerLevel = "adaptive",
    pushes: Iterable[PushLike] = (),
    mass: float | None = None,
    dt: float | None = None,
    progress: Callable[[float], None] | None = None,
    step_adjustment: StepAdjustment | None = None,
    gains: DcmFeedbackGains | None = None,
    replan_dcm_error: float = DEFAULT_REPLAN_DCM_ERROR,
) -> ClosedLoopResult:
    """Walk ``scenario`` on the point-mass pendulum with the controller level ``controller``.

    Args:
        scenario: the walk (strides, footstep changes, robot's COG height and sole, timing, connection mode).
        controller: ``"open-loop"``, ``"stabilized"`` or ``"adaptive"`` (:mod:`rtgait.core.pendulum.loop`).
        pushes: forces on the mass, each a :class:`~rtgait.core.pendulum.plant.Push` or ``(start, duration, fx, fy)``
            (s from the start of the walk, s, N, N).
        mass: of the point mass (kg); default the scenario's ``[robot] mass`` if any, else 57 kg
            (:func:`scenario_mass`).
        dt: control period (s); default 1 ms (the scenario's ``dt`` is the rollout's sampling period, not a
            controller's).
        progress: called now and then with the fraction done.
        step_adjustment: ``"adaptive"``'s step adjustment; default ``StepAdjustment(sole=scenario.sole)`` (a robot's
            ``[stepping]`` limits: ``robot.description.stepping.adjustment(scenario.sole)``).
        gains: the DCM law's gains (``"stabilized"``, ``"adaptive"``); default
            :class:`~rtgait.core.laws.feedback.DcmFeedbackGains`.
        replan_dcm_error: ``"adaptive"``: the DCM error that replans at once (m).

    Returns:
        :class:`~rtgait.core.pendulum.loop.ClosedLoopResult`; its :meth:`~ClosedLoopResult.summary` carries the
        scenario's name.

    Raises:
        ValueError: an unknown controller, a bad push, mass or period.
    """
    check_level(controller)
    result = run_pendulum_loop(
        scenario.planner_config(),
        scenario.strides(),
        scenario.sole,
        controller=controller,
        mass=scenario_mass(scenario, mass),
        dt=DEFAULT_DT if dt is None else float(dt),
        pushes=[as_push(p) for p in pushes],
        changes=scenario.changes,
        progress=progress,
        gains=gains,
        replan_dcm_error=replan_dcm_error,
        step_adjustment=step_adjustment,
    )
    result.extra["scenario"] = scenario.name
    return result


def _write_csv(result: ClosedLoopResult, path: Path) -> None:
    numeric = np.column_stack(
        [
            result.times, result.cog_planned, result.dcm_planned, result.zmp_planned, result.zmp_reference,
            result.zmp_command, result.zmp_real, result.cog, result.cog_vel, result.dcm,
        ]
    )  # fmt: skip
    # Vectorised formatting: a Python loop over every value would dominate a long run.
    text = np.char.mod(_FLOAT_FORMAT, numeric)
    support = np.array([SUPPORT_NAMES[int(code)] for code in result.support], dtype=object)
    phase = result.phase.astype(str)
    saturated = result.saturated.astype(int).astype(str)
    table = np.column_stack([text.astype(object), support, phase, saturated])
    with open(path, "w", encoding="utf-8", newline="") as stream:
        stream.write(",".join(PENDULUM_CSV_COLUMNS) + "\n")
        stream.writelines(",".join(row) + "\n" for row in table.tolist())


def write_pendulum_outputs(
    result: ClosedLoopResult, folder: str | Path, extra: dict[str, Any] | None = None
) -> dict[str, Any]:
    """Write ``sim.csv`` (:data:`PENDULUM_CSV_COLUMNS`) and ``summary.json`` into ``folder`` (created if missing;
    files of the same names are replaced whole, others left alone).

    Returns:
        The summary, also written as ``summary.json``: ``model`` (``"lipm"``), ``controller``, ``scenario``,
        ``mass`` (kg), ``dt`` (s), ``fell``, ``fall_time`` (s or null), ``steps_completed``, ``steps_planned``,
        ``step_adjustments`` (how many) and ``step_adjustment_log`` (each: time, step, nominal and new landing in m,
        ZMP margins before and after in m, emergency, reason), ``ended_at_rest``, ``pushes`` (each ``start``,
        ``duration`` in s, ``force`` in N, ``impulse`` in N s and its norm ``impulse_norm``),
        ``zmp_tracking_error_rms`` and ``_max`` (m), ``zmp_saturated_ticks``, ``replans``, ``walk_end``,
        ``simulated_time``, ``wall_time``, ``tick_time`` (s), ``real_time_factor``, then ``rows`` and ``files``;
        ``extra`` entries come first.
    """
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    write_atomic(out / "sim.csv", lambda path: _write_csv(result, path))
    summary: dict[str, Any] = {
        **(extra or {}),
        **result.summary(),
        "rows": result.ticks,
        "files": list(PENDULUM_FILES),
    }
    write_text_atomic(out / "summary.json", summary_text(summary))
    return summary
