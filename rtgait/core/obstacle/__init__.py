"""Obstacles seen while walking and the footstep changes that avoid them (the paper's Fig. 1): the box
(:mod:`~rtgait.core.obstacle.box`), the least change of the remaining footsteps
(:mod:`~rtgait.core.obstacle.detour`) and the reaction that hands it to the online planner
(:mod:`~rtgait.core.obstacle.avoid`)."""
