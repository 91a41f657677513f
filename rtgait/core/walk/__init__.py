"""The walk as planned now: footprints, strides, phases, the velocity command and the changes a walk accepts."""
