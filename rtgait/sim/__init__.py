"""Walking in MuJoCo: the robot's model, its servos and contacts, the closed loop and its record.

This package imports nothing, so importing it needs neither MuJoCo nor Pinocchio; its modules are mapped in
``docs/architecture.md``.
"""
