"""A humanoid model with Pinocchio: robot descriptions, whole-body IK, multibody ZMP, angular-momentum compensation.

This package imports nothing, so ``rtgait.robot.description`` and ``rtgait.robot.data`` work without Pinocchio; its
modules are mapped in ``docs/architecture.md``.
"""
