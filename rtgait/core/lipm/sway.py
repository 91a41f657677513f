"""How far the COG sways toward the feet in steady walking: a number of the timing alone.

Stepping in place with the planner's reference ZMP, the ZMP rests on each foot in turn for a single support ``Ts``
and travels to the other foot over a double support ``Td`` along the cubic with zero end velocities
(:mod:`rtgait.core.lipm.pattern`): with the feet at ``+-a`` across the walk, ``p(t) = +-a`` in single support and
``p = a (1 - 2 s(u))``, ``s(u) = 3u^2 - 2u^3``, ``u = (t - Ts) / Td``, in double support; it repeats with period
``2 (Ts + Td)``. The COG's bounded (periodic) solution of ``c'' = w^2 (c - p)`` is the average of the ZMP under
the kernel ``(w/2) exp(-w |t - s|)``, so ``|c| <= a``; its largest value as a share of ``a``,

    sway = max_t |c(t)| / a,    0 <= sway < 1,

depends on ``w Ts`` and ``w Td`` alone (not on the stance width: the pendulum is linear). Short steps keep the COG
near the middle (the paper's fig8 timing, 0.7 s + 0.1 s at ``w = 3.9/s``: 0.60); a long double support or single
support lets it follow the ZMP onto each foot (fig7, 0.8 s + 1.5 s: 0.95). The more it sways, the farther the COG
is from the other foot while that foot still bears weight, and the more of the legs' reach the stance itself uses:
a robot's bounds on walks by velocity command are given per sway
(:class:`~rtgait.core.planner.config.VelocityLimits`).

It is computed as the sum of the convergent and divergent components ``zeta' = -w (zeta - p)`` and
``xi' = w (xi - p)``, ``c = (zeta + xi) / 2``, each filtered exactly over one period of a sampled ``p`` (the
trapezoidal rule between samples) and made periodic in closed form.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from scipy.signal import lfilter

SAMPLES = 4000
"""Samples of the ZMP over one period (two steps): the sway is good to about ``(w T / SAMPLES)^2``."""


def _periodic_filter(p: np.ndarray, decay: float) -> np.ndarray:
    """The periodic solution of ``y[n] = decay y[n-1] + (1 - decay) (p[n-1] + p[n]) / 2`` for ``p`` one period of a
    periodic sequence: one pass from zero, then the start value that repeats after a period added, decayed."""
    gain = 0.5 * (1.0 - decay)
    previous = np.roll(p, 1)
    once = lfilter([gain], [1.0, -decay], p + previous)
    start = once[-1] / (1.0 - decay ** len(p))  # y[-1] = y[N-1]: the value one period back
    return once + start * decay ** np.arange(1, len(p) + 1)


@lru_cache(maxsize=64)
def cog_sway(w: float, single_support: float, double_support: float) -> float:
    """The COG's largest excursion toward a foot as a share of half the stance (module docstring), stepping in place
    with phases of ``single_support`` and ``double_support`` (s) at pendulum frequency ``w`` (1/s)."""
    if not (math.isfinite(w) and w > 0.0):
        raise ValueError(f"w must be finite and > 0 (1/s), got {w}")
    if not (math.isfinite(single_support) and single_support > 0.0):
        raise ValueError(f"single_support must be finite and > 0 s, got {single_support}")
    if not (math.isfinite(double_support) and double_support >= 0.0):
        raise ValueError(f"double_support must be finite and >= 0 s, got {double_support}")
    step = single_support + double_support
    t = np.arange(SAMPLES) * (2.0 * step / SAMPLES)
    phase = np.mod(t, step)
    u = np.clip((phase - single_support) / double_support, 0.0, 1.0) if double_support > 0.0 else phase * 0.0
    one_step = 1.0 - 2.0 * (3.0 * u * u - 2.0 * u**3)  # from +1 (this foot) to -1 (the other one)
    p = np.where(t < step, one_step, -one_step)
    decay = math.exp(-w * 2.0 * step / SAMPLES)
    convergent = _periodic_filter(p, decay)
    divergent = _periodic_filter(p[::-1], decay)[::-1]  # the same filter backward in time
    return float(np.max(np.abs(0.5 * (convergent + divergent))))


__all__ = ["cog_sway"]
