"""Scenario files for the tests, written from one template (``write_scenario`` in conftest.py uses it)."""

from __future__ import annotations


def header_text(
    name: str = "probe",
    connection: str = "real-time",
    single_support: float = 0.8,
    double_support: float = 0.2,
    dt: float = 0.01,
) -> str:
    """The tables every scenario and footstep plan of the tests share: name, connection, the HRP-2-like robot of
    the built-ins and the timing."""
    return f"""name = "{name}"
connection = "{connection}"
[robot]
cog_height = 0.8
[robot.sole]
front = 0.13
back = 0.10
inner = 0.07
outer = 0.07
[timing]
single_support = {single_support}
double_support = {double_support}
dt = {dt}
horizon_steps = 3
"""


def scenario_text(
    name: str = "probe",
    connection: str = "real-time",
    single_support: float = 0.8,
    double_support: float = 0.2,
    dt: float = 0.01,
    steps: int = 3,
    step_length: float = 0.1,
    short_ends: bool = False,
) -> str:
    """A complete scenario TOML with the HRP-2-like robot of the built-ins; ``short_ends`` shortens the start,
    end and settling phases to 0.8 s for quick simulations."""
    ends = "start = 0.8\nend = 0.8\nsettle = 0.8\n" if short_ends else ""
    return (
        header_text(name, connection, single_support, double_support, dt)
        + f"""{ends}[walk]
steps = {steps}
step_length = {step_length}
step_width = 0.19
step_height = 0.05
"""
    )
