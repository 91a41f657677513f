"""From what the robot senses to the walking state a controller acts on: the estimator protocol, the ground-truth
estimator and the kinematic-inertial estimator (IMU, leg kinematics, feet force sensors or joint torques) with the
kinematics protocol it reads a robot model through, the state types, the feet's wrench, CoP and ZMP maths, and load
and landing detection."""
