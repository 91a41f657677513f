"""Sweeps: a scenario over a grid of variants, at the pendulum level and in physics (``docs/sweeps.md``).

Its modules are mapped in ``docs/architecture.md``.
"""
