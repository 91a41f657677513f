"""A run's title in words: a walk of footsteps by its scenario, a walk by velocity command by its commands."""

from __future__ import annotations

from rtgait.viz.walk_title import velocity_commands, velocity_facts, velocity_text, walk_title


def test_a_walk_of_footsteps_is_named_by_its_scenario() -> None:
    assert walk_title("fig8", "quasi-real-time") == "fig8 (quasi-real-time)"
    assert walk_title("fig8", "quasi-real-time", velocity_commands({"scenario": "fig8"})) == "fig8 (quasi-real-time)"


def test_a_velocity_walk_says_what_it_was_asked() -> None:
    # The demo's walk: forward, then turning on the spot from 5 s (wz > 0 turns left, counter-clockwise from above).
    commands = [(0.0, 0.2, 0.0, 0.0), (5.0, 0.0, 0.0, 0.2)]
    assert walk_title("fig8", "quasi-real-time", commands) == (
        "velocity walk 0.2 m/s forward, from 5 s turning left 0.2 rad/s on the spot (fig8's timing, quasi-real-time)"
    )
    # Each component by its sign (vy > 0 is to the left), in the order vx, vy, wz; a zero command stands.
    backing = velocity_text([(0.0, -0.1, -0.05, -0.3)])
    assert backing == "0.1 m/s backward, 0.05 m/s to the right, turning right 0.3 rad/s"
    assert velocity_text([(0.0, 0.0, 0.1, 0.0), (2.5, 0.0, 0.0, 0.0)]) == "0.1 m/s to the left, from 2.5 s standing"


def test_the_commands_travel_through_the_summary() -> None:
    commands = [(0.0, 0.2, 0.0, 0.0), (5.0, 0.0, 0.0, 0.2)]
    facts = {"velocity": velocity_facts(commands)}
    assert facts["velocity"][1] == {"t": 5.0, "vx": 0.0, "vy": 0.0, "wz": 0.2}
    assert velocity_commands(facts) == commands
