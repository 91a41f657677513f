"""The walking controller: estimated state and the online planner in, task targets for the whole-body IK out.

Its modules are mapped in ``docs/architecture.md``.
"""
