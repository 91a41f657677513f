"""Offline analysis above the planner: rollouts, batched walk families and the preview-control baseline.

Its modules are mapped in ``docs/architecture.md``.
"""
