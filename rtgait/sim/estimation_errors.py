"""How far an estimated walking state was from the simulator's truth over a run, computed at once from per-tick
columns (numpy; nothing runs per tick).

Both sides are of the same instant at each tick (the state the estimator measured, one physics step before the
tick's time, :mod:`rtgait.sim.loop`). Over the ticks compared (``k`` of them), with ``e`` the estimate and ``g`` the
truth:

* ``com_rms``: ``sqrt(mean |c_e - c_g|^2)``, the COM's absolute error (m); the estimate's world frame is anchored on
  the feet, so it carries their slips;
* ``com_relative_rms``: the COM relative to the stance sole, ``(c_e - s_e) - (c_g - s_g)`` with ``s`` the sole frame's
  origin of the foot that carries more of the true load (m): what the balance controller feeds back;
* ``zmp_rms``: the ZMP of both feet (m), over the ticks both have one (``None`` if a track has none);
* ``com_velocity_rms`` (m/s), ``dcm_rms`` and ``dcm_max`` (m, the horizontal ``xi = c + c'/w``), and
  ``dcm_relative_rms``, the DCM relative to the stance sole likewise: on a long walk the absolute errors grow with the
  estimate's drift (its landings are placed by the legs' kinematics, step after step), which the controller, whose
  plan is re-anchored on those landings, does not feel;
* ``contact_agreement``: the share of ticks at which both feet's load states (loaded or not, after the landing
  hysteresis) are the truth's. The truth's are the ground-truth estimator's: the true vertical forces through
  :class:`~rtgait.estimation.load.LoadHysteresis` with its default thresholds (:func:`loaded_states`).
  ``contact_false_loaded`` and ``contact_false_unloaded`` split the disagreement by foot and tick: the share of
  ticks with a foot loaded in the estimate and not in the truth, and the other way round (their sum is at least
  ``1 - contact_agreement``: a tick may be wrong on both feet);
* landings: a foot's load state turning on after at least ``min_unloaded_time`` in the air (the rule of
  :mod:`rtgait.estimation.load`), on each side. The truth's are *step landings* after at least
  :data:`RELANDING_AIR_TIME` in the air, and *re-landings* after less: a foot that touched, bounced off for longer
  than the load detection's least flight and came down again, which an estimate may see as part of the step's
  landing. In time order, each true step landing is matched with the estimate's nearest landing of the same foot
  within :data:`LANDING_WINDOW` not matched yet; its delay is the estimate's time minus the truth's (s, negative:
  seen early). ``landing_delay_worst`` is the delay of largest magnitude, ``landing_delay_median`` and
  ``landing_delay_p95`` the median and 95th percentile of the delays, ``landings_missed`` the step landings
  without a match; the re-landings are then matched likewise (``relandings_missed``), and ``landings_extra`` counts
  the estimate's landings matched with none;
* lift-offs: a foot's load state turning off before at least :data:`RELANDING_AIR_TIME` in the air (a step's
  lift-off, not a bounce), matched with the estimate's nearest turn-off of the same foot within
  :data:`LANDING_WINDOW`; ``liftoff_delay_median`` and ``liftoff_delay_worst`` as the landings' (s).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np

from rtgait.estimation.load import DEFAULT_LANDING_FRACTION, DEFAULT_MIN_UNLOADED_TIME

__all__ = [
    "LANDING_WINDOW", "RELANDING_AIR_TIME", "EstimationErrors", "StateTrack", "estimation_errors", "landing_times",
    "liftoff_times", "loaded_states",
]  # fmt: skip

LANDING_WINDOW = (-0.05, 0.3)
"""How much earlier and later than a true landing (s) an estimated landing of the same foot may come to be its
detection: a landing seen 0.3 s late is a missed one in all but name, and the next step's is further away."""
RELANDING_AIR_TIME = 0.2
"""A true landing after less time than this in the air (s) is a re-landing after a bounce, not a step's: the
shortest swing of the built-in walks is 0.7 s."""


@dataclass(frozen=True, eq=False)
class StateTrack:
    """One side of the comparison, one row per tick (world frame, SI units).

    Attributes:
        com: centre of mass (m), shape ``(k, 3)``.
        com_velocity: its velocity (m/s), shape ``(k, 3)``.
        dcm: horizontal DCM (m), shape ``(k, 2)``.
        soles: each sole frame's origin, left then right (m), shape ``(k, 2, 3)``.
        normal_force: each foot's vertical contact force (N), shape ``(k, 2)``.
        loaded: each foot's load state after the landing hysteresis, shape ``(k, 2)``; ``None`` for the truth's
            from its forces (:func:`loaded_states`, from the first tick compared on).
        zmp: the ZMP of both feet (m), shape ``(k, 2)``, NaN where there is none; ``None``: not known.
    """

    com: np.ndarray
    com_velocity: np.ndarray
    dcm: np.ndarray
    soles: np.ndarray
    normal_force: np.ndarray
    loaded: np.ndarray | None
    zmp: np.ndarray | None = None


@dataclass(frozen=True)
class EstimationErrors:
    """The errors of the module docstring (m, m/s, s; the contact agreement a fraction).

    Attributes:
        ticks: ticks compared.
        com_rms, com_relative_rms, com_velocity_rms, dcm_rms, dcm_relative_rms, dcm_max, zmp_rms: the state's
            errors.
        contact_agreement: share of ticks with both feet's load states right.
        landings: true step landings.
        landings_missed: true step landings the estimate did not see within :data:`LANDING_WINDOW`.
        relandings: true re-landings after a bounce.
        relandings_missed: those the estimate did not see apart from the step's landing.
        landings_extra: the estimate's landings matched with none of the truth's.
        landing_delay_worst: the detection delay of largest magnitude (s), ``None`` without a matched landing.
        landing_delay_median: the median detection delay (s), ``None`` likewise.
        landing_delay_p95: the delays' 95th percentile (s), ``None`` likewise.
        contact_false_loaded: share of foot-ticks loaded in the estimate and not in the truth (per tick).
        contact_false_unloaded: share of foot-ticks loaded in the truth and not in the estimate (per tick).
        liftoff_delay_median, liftoff_delay_worst: the step lift-offs' detection delays (s), ``None`` without a
            matched one.
        landing_delays: every matched step landing's detection delay (s), in time order (not in :meth:`summary`).
    """

    ticks: int
    com_rms: float
    com_relative_rms: float
    com_velocity_rms: float
    dcm_rms: float
    dcm_relative_rms: float
    dcm_max: float
    zmp_rms: float | None
    contact_agreement: float
    landings: int
    landings_missed: int
    relandings: int
    relandings_missed: int
    landings_extra: int
    landing_delay_worst: float | None
    landing_delay_median: float | None
    landing_delay_p95: float | None = None
    contact_false_loaded: float = math.nan
    contact_false_unloaded: float = math.nan
    liftoff_delay_median: float | None = None
    liftoff_delay_worst: float | None = None
    landing_delays: tuple[float, ...] = ()

    def summary(self) -> dict[str, Any]:
        """JSON-ready values (``summary.json``'s ``estimation``), the delays' list left out: NaN (no tick compared)
        as ``None``."""
        values = asdict(self)
        del values["landing_delays"]
        return {k: None if isinstance(v, float) and not math.isfinite(v) else v for k, v in values.items()}


def loaded_states(
    normal_force: np.ndarray, weight: float, landing_fraction: float = DEFAULT_LANDING_FRACTION
) -> np.ndarray:
    """Each foot's load state, shape ``(k, 2)``, from its vertical forces ``normal_force`` (N, ``(k, 2)``): loaded
    above ``landing_fraction`` of ``weight`` (N), unloaded below half of that, kept in between, unloaded before the
    first decision: the ground-truth estimator's :class:`~rtgait.estimation.load.LoadHysteresis`, tick by tick from
    the first row."""
    landing = landing_fraction * weight
    release = 0.5 * landing
    n = len(normal_force)
    decided = np.where(normal_force > landing, 1, np.where(normal_force < release, 0, -1))
    ticks = np.arange(n)[:, None]
    last = np.maximum.accumulate(np.where(decided >= 0, ticks, -1), axis=0)  # the last tick that decided
    states = np.take_along_axis(decided, np.maximum(last, 0), axis=0) == 1
    return states & (last >= 0)


def landing_times(
    times: np.ndarray, loaded: np.ndarray, min_unloaded_time: float = DEFAULT_MIN_UNLOADED_TIME
) -> list[tuple[float, int, float]]:
    """The landings in a run of load states ``loaded`` (``(k, 2)`` at ``times``, s): ``(t, side, air)`` with side 0
    left, 1 right, and the time the foot was unloaded before it (s), in time order. The first tick's states are taken
    as they are (no landing); a foot unloaded at the first tick has been in the air since then."""
    found = []
    for side in (0, 1):
        states = loaded[:, side].astype(np.int8)
        change = np.diff(states)
        rises = np.flatnonzero(change == 1) + 1
        falls = np.flatnonzero(change == -1) + 1
        for rise in rises:
            before = falls[falls < rise]
            lifted = times[before[-1]] if len(before) else times[0]
            if times[rise] - lifted >= min_unloaded_time:
                found.append((float(times[rise]), side, float(times[rise] - lifted)))
    return sorted(found)


def liftoff_times(
    times: np.ndarray, loaded: np.ndarray, min_air_time: float = RELANDING_AIR_TIME
) -> list[tuple[float, int]]:
    """The lift-offs in a run of load states ``loaded`` (``(k, 2)`` at ``times``, s): ``(t, side)`` where a foot's
    state turns off and stays off at least ``min_air_time`` (s; or to the end of the run), in time order."""
    found = []
    for side in (0, 1):
        change = np.diff(loaded[:, side].astype(np.int8))
        rises = np.flatnonzero(change == 1) + 1
        for fall in np.flatnonzero(change == -1) + 1:
            after = rises[rises > fall]
            if not len(after) or times[after[0]] - times[fall] >= min_air_time:
                found.append((float(times[fall]), side))
    return sorted(found)


def _rms(error: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum(error * error, axis=1)))) if len(error) else math.nan


def estimation_errors(
    times: np.ndarray, estimate: StateTrack, truth: StateTrack, weight: float, rows: np.ndarray | None = None
) -> EstimationErrors:
    """The errors of ``estimate`` against ``truth`` (module docstring) over the ticks ``rows`` (indices or a mask;
    default all) of the tracks at ``times`` (s). ``weight`` (N) sets the thresholds of the truth's load states when
    its track has none.

    Raises:
        ValueError: the estimate has no load states, or a track's length differs from ``times``'.
    """
    if estimate.loaded is None:
        raise ValueError("the estimate's track needs its load states")
    for name, track in (("estimate", estimate), ("truth", truth)):
        columns = [track.com, track.com_velocity, track.dcm, track.soles, track.normal_force]
        columns += [a for a in (track.loaded, track.zmp) if a is not None]
        if any(len(a) != len(times) for a in columns):
            raise ValueError(f"the {name}'s columns must have one row per tick ({len(times)})")
    if rows is not None:
        times, estimate, truth = times[rows], _take(estimate, rows), _take(truth, rows)
    if truth.loaded is None:
        truth = replace(truth, loaded=loaded_states(truth.normal_force, weight))
    assert estimate.loaded is not None and truth.loaded is not None
    n = len(times)
    dcm = estimate.dcm - truth.dcm
    ticks = np.arange(n)
    # The stance sole: the foot with more of the true load (the left one on a tie).
    stance = np.where(truth.normal_force[:, 0] >= truth.normal_force[:, 1], 0, 1)
    estimated_sole, true_sole = estimate.soles[ticks, stance], truth.soles[ticks, stance]
    relative = (estimate.com - estimated_sole) - (truth.com - true_sole)
    dcm_relative = dcm - (estimated_sole[:, 0:2] - true_sole[:, 0:2])
    agree = np.all(estimate.loaded == truth.loaded, axis=1)
    true_landings = landing_times(times, truth.loaded)
    steps = [(t, side) for t, side, air in true_landings if air >= RELANDING_AIR_TIME]
    relandings = [(t, side) for t, side, air in true_landings if air < RELANDING_AIR_TIME]
    seen = [(t, side) for t, side, _ in landing_times(times, estimate.loaded)]
    used: set[int] = set()
    delays = _matched(steps, seen, used)
    relandings_seen = _matched(relandings, seen, used)
    liftoff_delays = _matched(liftoff_times(times, truth.loaded), liftoff_times(times, estimate.loaded, 0.0), set())
    distance = np.hypot(dcm[:, 0], dcm[:, 1])
    zmp_rms = None
    if estimate.zmp is not None and truth.zmp is not None:
        both = np.isfinite(estimate.zmp).all(axis=1) & np.isfinite(truth.zmp).all(axis=1)
        zmp_rms = _rms(estimate.zmp[both] - truth.zmp[both])
    return EstimationErrors(
        ticks=n,
        com_rms=_rms(estimate.com - truth.com),
        com_relative_rms=_rms(relative),
        com_velocity_rms=_rms(estimate.com_velocity - truth.com_velocity),
        dcm_rms=_rms(dcm),
        dcm_relative_rms=_rms(dcm_relative),
        dcm_max=float(distance.max()) if n else math.nan,
        zmp_rms=zmp_rms,
        contact_agreement=float(np.mean(agree)) if n else math.nan,
        landings=len(steps),
        landings_missed=len(steps) - len(delays),
        relandings=len(relandings),
        relandings_missed=len(relandings) - len(relandings_seen),
        landings_extra=len(seen) - len(used),
        landing_delay_worst=float(max(delays, key=abs)) if delays else None,
        landing_delay_median=float(np.median(delays)) if delays else None,
        landing_delay_p95=float(np.percentile(delays, 95.0)) if delays else None,
        contact_false_loaded=float(np.mean(np.sum(estimate.loaded & ~truth.loaded, axis=1))) if n else math.nan,
        contact_false_unloaded=float(np.mean(np.sum(~estimate.loaded & truth.loaded, axis=1))) if n else math.nan,
        liftoff_delay_median=float(np.median(liftoff_delays)) if liftoff_delays else None,
        liftoff_delay_worst=float(max(liftoff_delays, key=abs)) if liftoff_delays else None,
        landing_delays=tuple(float(d) for d in delays),
    )


def _matched(landings: list[tuple[float, int]], seen: list[tuple[float, int]], used: set[int]) -> list[float]:
    """The delays (s) of the ``landings`` that ``seen`` has within :data:`LANDING_WINDOW`, in time order, each of
    ``seen`` matched at most once (``used``: the indices matched so far, updated)."""
    low, high = LANDING_WINDOW
    delays = []
    for t, side in landings:
        near = [(abs(s - t), i) for i, (s, other) in enumerate(seen) if other == side and low < s - t < high]
        near = [pair for pair in near if pair[1] not in used]
        if near:
            i = min(near)[1]
            used.add(i)
            delays.append(seen[i][0] - t)
    return delays


def _take(track: StateTrack, rows: np.ndarray) -> StateTrack:
    """The track at ``rows`` only."""
    loaded = None if track.loaded is None else track.loaded[rows]
    zmp = None if track.zmp is None else track.zmp[rows]
    return StateTrack(track.com[rows], track.com_velocity[rows], track.dcm[rows], track.soles[rows],
                      track.normal_force[rows], loaded, zmp)  # fmt: skip
