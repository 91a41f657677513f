"""Pure types at the robot boundary: what a controller knows of its robot and what it asks of the joints."""
