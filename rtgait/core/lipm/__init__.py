"""The linear inverted pendulum in closed form: the ZMP spline, the COG over it, the boundary-value solve, the
connection of plans and the precomposed operators.

Its modules are mapped in ``docs/architecture.md``.
"""
