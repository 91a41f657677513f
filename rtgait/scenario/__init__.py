"""Walking scenarios: the scenario model and its files, footstep plans, guide paths, checks and TOML helpers.

Its modules are mapped in ``docs/architecture.md``.
"""
