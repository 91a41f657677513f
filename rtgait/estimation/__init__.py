"""From what the robot senses to the walking state a controller acts on: the estimated state types, wrench, CoP and ZMP
maths, contact and landing detection."""
