"""Offline analysis above the planner: rollouts, batched walk families and the preview-control baseline."""
