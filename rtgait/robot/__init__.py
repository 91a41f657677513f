"""Whole-body motion of a real humanoid model (Pinocchio + example-robot-data): robot descriptions, whole-body
inverse kinematics, multibody ZMP and angular-momentum compensation.

Modules (import them directly; this package imports nothing, so ``rtgait.robot.description`` and
``rtgait.robot.data`` work without Pinocchio):

* :mod:`rtgait.robot.data`: where example-robot-data's files are.
* :mod:`rtgait.robot.description`: robot description TOML files, ``load_robot(name_or_path)``.
* :mod:`rtgait.robot.description_checks`: the readers and checks of a description's parts, and ``RobotError``.
* :mod:`rtgait.robot.model`: ``RobotModel.load(description)``, full and reduced Pinocchio models, half-sitting.
* :mod:`rtgait.robot.ik`: ``WholeBodyIK``, one control tick of whole-body inverse kinematics.
* :mod:`rtgait.robot.motion`: ``whole_body_motion(robot, rollout)``, a planned walk as joint trajectories.
* :mod:`rtgait.robot.dynamics`: ``multibody_check``, centroidal momentum and the multibody ZMP.
"""
