"""Walking scenarios: the scenario model and its files, footstep plans, guide paths, checks and TOML helpers.

Its modules are mapped in ``docs/architecture.md``; the names a user needs are here: ``load_scenario("fig8")`` (a
built-in name or a TOML file), ``builtin_scenarios()``, :class:`Scenario` and :class:`ScenarioError`.
"""

from rtgait.scenario.checks import ScenarioError
from rtgait.scenario.loading import builtin_scenarios, load_scenario
from rtgait.scenario.scenario import Scenario

__all__ = ["Scenario", "ScenarioError", "builtin_scenarios", "load_scenario"]
