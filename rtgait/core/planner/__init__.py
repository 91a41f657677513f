"""The online planner: a control loop samples it every tick, observes the robot and changes footsteps while walking.

Its modules are mapped in ``docs/architecture.md``.
"""
