"""The largest and smallest things a user may ask of the planner, checked where the values enter.

Every size a caller controls (steps, phases, horizon, ticks, durations) is bounded so that no accepted input can
exhaust memory or time, and every physical quantity is bounded so that the closed form stays well conditioned.

Why these numbers:

* ``MAX_PHASE_W_T``: on a phase of duration ``T`` the COG is ``V cosh(w tau) + W sinh(w tau) + ...``; the two
  homogeneous terms grow like ``e^{w T}`` and cancel, so round-off in the COG grows like ``|V| e^{w T} eps``. With
  ``w T <= 20`` that is at most ``5e8 * 2.2e-16 ~ 1e-7`` of ``|V|``, i.e. well below a micrometre for a COG that
  moves a few centimetres. (At 0.8 m COG height, ``w = 3.5 /s``: phases up to 5.7 s.)
* ``MIN_PHASE_DURATION``: double-support transfers are cubics with coefficients ``~ 1/T^3``; below a millisecond
  they carry ZMP accelerations no robot has, and the pendulum residual grows past 1e-8 m.
* ``MAX_STEPS`` / ``MAX_ROLLOUT_TICKS``: a walk's footprints and a rollout's arrays are held in memory
  (``MAX_ROLLOUT_TICKS`` rows of 22 floats is about 200 MB).
* ``MAX_REPLANS_PER_SAMPLE``: one :meth:`~rtgait.core.planner.online.OnlinePlanner.sample` call replans at every
  double-support start it passes; each costs tens of microseconds, so this keeps one call under ~2 ms. A loop
  samples at least once per step anyway.
"""

from __future__ import annotations

import math

MIN_COG_HEIGHT = 0.05
"""Lowest COG height accepted (m)."""
MAX_COG_HEIGHT = 10.0
"""Highest COG height accepted (m)."""
MIN_GRAVITY = 0.1
"""Weakest gravity accepted (m/s^2)."""
MAX_GRAVITY = 100.0
"""Strongest gravity accepted (m/s^2)."""
MIN_PHASE_DURATION = 1e-3
"""Shortest phase (single, double support, start, end, settle) accepted (s)."""
MAX_PHASE_DURATION = 60.0
"""Longest phase accepted before the pendulum frequency is known (s); see also :data:`MAX_PHASE_W_T`."""
MAX_PHASE_W_T = 20.0
"""Largest ``w * T`` of any phase (dimensionless): the closed form's conditioning (module docstring)."""
MAX_STEPS = 10_000
"""Most steps in one finite walk (the closing step included)."""
MAX_HORIZON_STEPS = 20
"""Most steps one plan may look ahead."""
MIN_DT = 1e-5
"""Shortest control period of a rollout (s)."""
MAX_ROLLOUT_TICKS = 1_000_000
"""Most samples in one rollout (duration / dt + 1)."""
MAX_REPLANS_PER_SAMPLE = 64
"""Most double-support starts one ``sample()`` call may pass (it replans at each)."""
MAX_STRIDE = 2.0
"""Largest stride length or width accepted (m): no humanoid steps farther."""
MAX_SURFACE_TILT = 0.5
"""Largest pitch or roll of a foothold's support surface accepted (rad, about 29 degrees): steeper than any ramp a
walking humanoid stands on with a flat sole."""


def check_range(name: str, value: float, low: float, high: float, unit: str) -> float:
    """``value`` as a float if finite and within ``[low, high]``; otherwise a :class:`ValueError` naming ``name``
    and the allowed range."""
    value = float(value)
    if not (math.isfinite(value) and low <= value <= high):
        raise ValueError(f"{name} must be within [{low:g}, {high:g}] {unit}, got {value}")
    return value
