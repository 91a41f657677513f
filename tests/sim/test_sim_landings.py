"""The touch-down count that judges a walk (rtgait.sim.contact.Landings), on scripted foot forces.

A single support is phase 1 of the planner here (the left foot standing, the right one swinging), from 0 to 0.5 s;
the double support after it, phase 2, lasts the rest. The loop's window is 0.1 s, the force threshold 20 N."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from rtgait.sim.contact import Landings

DT, END, WINDOW, THRESHOLD = 0.001, 0.5, 0.1, 20.0


def count(right_force: Callable[[float], float], until: float = 0.8) -> Landings:
    """Run the counter over a single support and the double support after it; the left foot carries 300 N."""
    landings = Landings(WINDOW, THRESHOLD)
    landings.update(-DT, 0, 0, 150.0, 150.0)  # the double support before: both feet down
    for k in range(round(until / DT)):
        t = k * DT
        single = t < END
        landings.update(t, 1 if single else 2, 1 if single else 0, 300.0, right_force(t))
    return landings


def lifted_then(landing: Callable[[float], float]) -> Callable[[float], float]:
    """The right foot leaves the floor at 0.02 s and comes back as ``landing`` says from 0.3 s on (0 before)."""
    return lambda t: 150.0 if t < 0.02 else (0.0 if t < 0.3 else landing(t))


@pytest.mark.parametrize(
    ("name", "force", "landed"),
    [
        ("on time", lifted_then(lambda t: 200.0 if t >= END else 0.0), True),
        ("late, within the window", lifted_then(lambda t: 200.0 if t >= END + 0.06 else 0.0), True),
        ("after the window", lifted_then(lambda t: 200.0 if t >= END + 0.15 else 0.0), False),
        ("never", lifted_then(lambda t: 0.0), False),
        ("early", lifted_then(lambda t: 200.0 if t >= 0.45 else 0.0), True),
        # Down at 0.45 s, off the floor again from 0.48 to 0.65 s (past the window): it landed all the same.
        ("early, then bouncing through the window", lifted_then(lambda t: 200.0 if 0.45 <= t < 0.48 else 0.0), True),
    ],
)
def test_a_swing_foot_that_came_down_is_counted_once_and_one_that_did_not_is_missed(name, force, landed):
    landings = count(force)
    assert (landings.count, landings.missed) == ((1, 0) if landed else (0, 1)), name


def test_the_stance_foot_still_loaded_at_the_start_is_not_a_landing():
    """The swing foot carries weight for the first ticks of its single support (it has not lifted yet): that is
    the lift-off, not a touch-down; if it then never comes down, the step is missed."""
    landings = count(lambda t: 150.0 if t < 0.05 else 0.0)
    assert (landings.count, landings.missed) == (0, 1)
