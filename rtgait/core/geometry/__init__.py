"""Footsteps, sole rectangles, support polygons, swing trajectories and the half-plane tests of ZMP margins.

Its modules are mapped in ``docs/architecture.md``.
"""
