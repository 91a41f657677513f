"""The estimate's errors against the truth from per-tick columns (rtgait.sim.estimation_errors), against the
tick-by-tick load hysteresis and landing rule of rtgait.estimation.load and against errors built by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.estimation.load import DEFAULT_LANDING_FRACTION, DEFAULT_MIN_UNLOADED_TIME, LoadHysteresis
from rtgait.sim.estimation_errors import StateTrack, estimation_errors, landing_times, liftoff_times, loaded_states

WEIGHT = 900.0
"""The robot's weight in these tests (N): landing at 25 N, release at 12.5 N."""


def _forces(seed: int, n: int = 3000) -> np.ndarray:
    """Vertical forces on two feet (N) that cross both thresholds often, linger between them, and stay in the air
    for flights longer and shorter than the landing rule's least time."""
    rng = np.random.default_rng(seed)
    levels = np.array([0.0, 10.0, 13.0, 20.0, 24.0, 26.0, 300.0])  # around release (12.5) and landing (25)
    runs = rng.integers(1, 80, size=(n, 2))  # ticks each level is held
    forces = np.empty((n, 2))
    for side in (0, 1):
        k = 0
        while k < n:
            forces[k : k + runs[k, side], side] = rng.choice(levels)
            k += runs[k, side]
    return forces


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_load_states_and_landings_are_the_hysteresis_tick_by_tick(seed):
    forces = _forces(seed)
    dt = 0.002
    times = 0.3 + dt * np.arange(len(forces))
    landing = DEFAULT_LANDING_FRACTION * WEIGHT
    load = LoadHysteresis(landing, 0.5 * landing, DEFAULT_MIN_UNLOADED_TIME)  # the ground-truth estimator's
    states, landings = np.zeros_like(forces, dtype=bool), []
    for k, t in enumerate(times):
        for side in (0, 1):
            state = load.update(side, float(forces[k, side]), float(t))
            states[k, side] = state is None or state
            if state is None:
                landings.append((float(t), side))
        load.prime()  # as the estimators do after their first tick
    assert np.array_equal(loaded_states(forces, WEIGHT), states)
    assert [(t, side) for t, side, _ in landing_times(times, states)] == sorted(landings)
    assert len(landings) > 10  # the forces did land, and were in the air long enough


def _track(n: int, com_offset=(0.0, 0.0, 0.0), sole_offset=(0.0, 0.0, 0.0), velocity_offset=(0.0, 0.0, 0.0)):
    """A walk-like track of ``n`` ticks (the left foot carrying more on even halves), shifted by the offsets (m,
    m/s)."""
    t = np.arange(n) * 0.001
    com = np.column_stack([0.1 * t, 0.02 * np.sin(t), 0.8 + 0.0 * t]) + com_offset
    velocity = np.column_stack([0.1 + 0.0 * t, 0.02 * np.cos(t), 0.0 * t]) + velocity_offset
    soles = np.zeros((n, 2, 3))
    soles[:, 0, 1], soles[:, 1, 1] = 0.1, -0.1
    soles += sole_offset
    left_more = (np.arange(n) // 100) % 2 == 0
    force = np.column_stack([np.where(left_more, 600.0, 300.0), np.where(left_more, 300.0, 600.0)])
    w = 3.4
    return StateTrack(com, velocity, com[:, :2] + velocity[:, :2] / w, soles, force, np.ones((n, 2), dtype=bool))


def test_errors_of_known_offsets():
    n = 1000
    truth = _track(n)
    # The COM 5 mm off (3-4-5), the soles 5 mm off the same way: relative to the sole, no error; the velocity
    # 0.012 m/s off along y: the DCM 5 mm + 0.012 / 3.4 m off along y... added as vectors.
    estimate = _track(n, com_offset=(0.003, 0.004, 0.0), sole_offset=(0.003, 0.004, 0.0), velocity_offset=(0, 0.012, 0))
    errors = estimation_errors(np.arange(n) * 0.001, estimate, truth, WEIGHT)
    assert errors.ticks == n
    assert errors.com_rms == pytest.approx(0.005)
    assert errors.com_relative_rms == pytest.approx(0.0, abs=1e-15)
    assert errors.com_velocity_rms == pytest.approx(0.012)
    assert errors.dcm_rms == pytest.approx(math.hypot(0.003, 0.004 + 0.012 / 3.4))
    assert errors.dcm_max == pytest.approx(errors.dcm_rms)
    assert errors.dcm_relative_rms == pytest.approx(0.012 / 3.4)  # the soles took the offset of the COM along
    assert errors.contact_agreement == 1.0 and errors.landings == 0 and errors.landing_delay_worst is None
    # Only the sole of the foot that carries more counts: the left one moved alone, half the ticks see it.
    moved = _track(n, com_offset=(0.0, 0.0, 0.0))
    moved.soles[:, 0] += (0.0, 0.006, 0.0)
    assert estimation_errors(np.arange(n) * 0.001, moved, truth, WEIGHT).com_relative_rms == pytest.approx(
        0.006 / math.sqrt(2.0)
    )
    # Only the rows asked for.
    assert estimation_errors(np.arange(n) * 0.001, estimate, truth, WEIGHT, np.arange(10)).ticks == 10


def test_landings_are_matched_once_and_their_delays_signed():
    n = 2000
    times = np.arange(n) * 0.001
    truth, estimate = _track(n), _track(n)
    truth_loaded = np.ones((n, 2), dtype=bool)
    truth_loaded[300:600, 0] = False  # the left foot lands at 0.6 s ...
    truth_loaded[1200:1500, 1] = False  # ... the right one at 1.5 s
    truth_loaded[1510:1570, 1] = False  # and bounces: lands again at 1.57 s
    seen = np.ones((n, 2), dtype=bool)
    seen[305:596, 0] = False  # seen 4 ms early
    seen[1200:1507, 1] = False  # seen 7 ms late, and the bounce not at all
    truth = StateTrack(truth.com, truth.com_velocity, truth.dcm, truth.soles, truth.normal_force, truth_loaded)
    estimate = StateTrack(estimate.com, estimate.com_velocity, estimate.dcm, estimate.soles, estimate.normal_force,
                          seen)  # fmt: skip
    errors = estimation_errors(times, estimate, truth, WEIGHT)
    # Two step landings seen, a re-landing 60 ms after a bounce not seen apart.
    assert errors.landings == 2 and errors.landings_missed == 0 and errors.landings_extra == 0
    assert errors.relandings == 1 and errors.relandings_missed == 1
    assert errors.landing_delay_worst == pytest.approx(0.007)
    assert errors.landing_delay_median == pytest.approx(0.5 * (0.007 - 0.004))
    assert errors.landing_delays == pytest.approx((-0.004, 0.007)) and "landing_delays" not in errors.summary()
    assert errors.contact_agreement == pytest.approx(1.0 - (5 + 4 + 7 + 60) / n)
    # Loaded too long: the left foot 5 ticks at its lift-off and 4 before its landing, the right one through its
    # bounce; unloaded too long: the right foot the 7 ticks its landing was late.
    assert errors.contact_false_loaded == pytest.approx((5 + 4 + 60) / n)
    assert errors.contact_false_unloaded == pytest.approx(7 / n)
    assert errors.landing_delay_p95 == pytest.approx(-0.004 + 0.95 * 0.011)
    # The step lift-offs (0.3 s in the air after them; the bounce's 60 ms is not one): left seen 5 ms late, right on
    # time.
    assert liftoff_times(times, truth_loaded) == [(0.3, 0), (1.2, 1)]
    assert errors.liftoff_delay_worst == pytest.approx(0.005)
    assert errors.liftoff_delay_median == pytest.approx(0.0025)
    # Seen apart, 3 ms late: matched, not an extra landing.
    seen[1510:1573, 1] = False
    estimate = StateTrack(estimate.com, estimate.com_velocity, estimate.dcm, estimate.soles, estimate.normal_force,
                          seen)  # fmt: skip
    errors = estimation_errors(times, estimate, truth, WEIGHT)
    assert errors.relandings == 1 and errors.relandings_missed == 0 and errors.landings_extra == 0
    assert errors.contact_agreement == pytest.approx(1.0 - (5 + 4 + 7 + 3) / n)


def test_a_track_of_another_length_is_refused():
    truth = _track(10)
    with pytest.raises(ValueError, match="one row per tick"):
        estimation_errors(np.arange(9) * 0.001, _track(10), truth, WEIGHT)
