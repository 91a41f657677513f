"""The online planner: a control loop samples it every tick, observes the robot and changes footsteps while walking."""
