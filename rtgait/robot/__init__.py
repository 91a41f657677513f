"""Whole-body motion of a real humanoid model (Pinocchio + example-robot-data): robot descriptions, whole-body
inverse kinematics, multibody ZMP and angular-momentum compensation."""
