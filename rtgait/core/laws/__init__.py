"""Feedback and decision laws: the DCM law, step adjustment, the hip strategy, capturability and hand guidance.

Its modules are mapped in ``docs/architecture.md``.
"""
