"""Walking in physics: the planner, the whole-body IK and a MuJoCo model of the robot in closed loop at 1 kHz.

Modules (import them directly; this package imports nothing, so importing it needs neither MuJoCo nor Pinocchio):

* :mod:`rtgait.sim.model`: ``build_sim_model(robot)``, the MuJoCo model built at run time from the robot
  description's URDF (free-floating base, sole contact boxes, floor, position actuators, half-sitting start).
* :mod:`rtgait.sim.loop`: ``run_closed_loop(...)``, planner + IK + physics per tick, the measured ZMP (centre of
  pressure of the sole contacts), fall detection, pushes, an optional stabiliser; ``SimResult``.
* :mod:`rtgait.sim.run`: ``simulate(scenario, robot)``, ``write_sim_outputs(result, out_dir)`` and
  ``write_sim_replay(result, robot, path)`` (the 3D replay of the simulated motion) for the CLI.
* :mod:`rtgait.sim.guided`: ``simulate_guided(sim, walk)``, a walk led by the hand (the paper's Section 6): a
  person pulls the hand along the scenario's ``[guide]`` path, the wrist reading sets the steps.
"""
