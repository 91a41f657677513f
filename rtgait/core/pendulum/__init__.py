"""The linear inverted pendulum test bench: a point-mass plant, the closed loop around it, and its result.

Its modules are mapped in ``docs/architecture.md``.
"""
