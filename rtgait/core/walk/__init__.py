"""The walk as planned now: footprints, strides, phases, the velocity command and the changes a walk accepts.

Its modules are mapped in ``docs/architecture.md``.
"""
