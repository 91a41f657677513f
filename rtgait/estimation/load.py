"""Loaded feet and landings from the vertical force on each foot, with hysteresis.

A foot becomes *loaded* when its vertical force exceeds ``landing_force`` and *unloaded* when it falls below
``release_force`` (``0 <= release_force <= landing_force``: a foot at the threshold does not chatter). A transition
from unloaded to loaded after at least ``min_unloaded_time`` in the air is a *landing*; a shorter time in the air is a
scuff, not a step. The default threshold is auto_stabilizer's early touch-down force, 25 N on a 90 kg robot, scaled
to the robot's weight (:data:`DEFAULT_LANDING_FRACTION`), the release force half of it.

Once the first tick's feet are known (:meth:`LoadHysteresis.prime`), an unloaded foot becomes loaded only when its
force has stayed above ``landing_force`` for ``sustain_time`` (a ringing sensor's spike is not a load) and the caller
has it near the ground (:mod:`rtgait.estimation.landing_gate`); ``sustain_time = 0`` and no gate: at the first tick
above the threshold.
"""

from __future__ import annotations

import math

__all__ = ["DEFAULT_LANDING_FRACTION", "DEFAULT_MIN_UNLOADED_TIME", "LoadHysteresis"]

DEFAULT_LANDING_FRACTION = 25.0 / (90.0 * 9.81)
"""Landing threshold as a fraction of the robot's weight: auto_stabilizer's 25 N on a 90 kg robot (2.8 %)."""

DEFAULT_MIN_UNLOADED_TIME = 0.05
"""Least time in the air (s) before a load counts as a landing; shorter unloading is a scuff at lift-off."""


class LoadHysteresis:
    """The load state of both feet (module docstring).

    Args:
        landing_force: load at which a foot counts as loaded and, after flight, as landed (N).
        release_force: load below which a foot counts as unloaded (N), within ``[0, landing_force]``.
        min_unloaded_time: least flight time of a landing (s).
        sustain_time: how long an unloaded foot's force must stay above ``landing_force`` before it counts (s).
    """

    def __init__(
        self, landing_force: float, release_force: float, min_unloaded_time: float, sustain_time: float = 0.0
    ) -> None:
        if not 0.0 <= release_force <= landing_force:
            raise ValueError(
                f"release_force must be within [0, landing_force = {landing_force:g}] N, got {release_force}"
            )
        if not (math.isfinite(min_unloaded_time) and min_unloaded_time >= 0.0):
            raise ValueError(f"min_unloaded_time must be a duration >= 0 s, got {min_unloaded_time}")
        if not (math.isfinite(sustain_time) and sustain_time >= 0.0):
            raise ValueError(f"sustain_time must be a duration >= 0 s, got {sustain_time}")
        self.landing_force = float(landing_force)
        self.release_force = float(release_force)
        self.min_unloaded_time = float(min_unloaded_time)
        # Ticks fall on a float grid: a force above the threshold from t0 counts at t0 + sustain_time, not a tick later.
        self.sustain_time = float(sustain_time) - 1e-9 if sustain_time > 0.0 else 0.0
        self.reset()

    def reset(self) -> None:
        """Forget the feet's states: the next update takes them as they are, without landings."""
        self._loaded = [False, False]
        self._unloaded_since = [-math.inf, -math.inf]
        self._above_since = [math.inf, math.inf]
        self._primed = False

    def prime(self) -> None:
        """The first tick's feet are known: from now on a load after flight is a landing."""
        self._primed = True

    def air_time(self, index: int, t: float) -> float:
        """How long foot ``index`` has been unloaded at ``t`` (s): 0 for a loaded foot, ``inf`` for one unloaded since
        before the first tick."""
        return 0.0 if self._loaded[index] else t - self._unloaded_since[index]

    def update(self, index: int, fz: float, t: float, near_ground: bool = True) -> bool | None:
        """Foot ``index``'s (0 left, 1 right) load state after this tick's force ``fz`` (N) at ``t`` (s); ``None`` for a
        landing (then loaded). ``near_ground``: whether an unloaded foot may become loaded (module docstring)."""
        loaded = self._loaded[index]
        if loaded:
            if fz < self.release_force:
                self._loaded[index] = False
                self._unloaded_since[index] = t
                return False
            return True
        if fz > self.landing_force:
            if self._primed:
                if not near_ground:
                    self._above_since[index] = math.inf
                    return False
                if self.sustain_time > 0.0:
                    since = self._above_since[index]
                    if since == math.inf:
                        self._above_since[index] = since = t
                    if t - since < self.sustain_time:
                        return False
            self._above_since[index] = math.inf
            self._loaded[index] = True
            if self._primed and t - self._unloaded_since[index] >= self.min_unloaded_time:
                return None
            return True
        self._above_since[index] = math.inf
        if not self._primed:
            self._unloaded_since[index] = t
        return False
