"""Figures in the style of the paper and the 3D replay (matplotlib, meshcat).

Its modules are mapped in ``docs/architecture.md``.
"""
