"""From what the robot senses to the walking state a controller acts on: the estimator protocol and the ground-truth
estimator, the state types, the feet's wrench, CoP and ZMP maths, and load and landing detection."""
