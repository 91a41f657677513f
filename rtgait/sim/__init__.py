"""Walking in physics: the planner, a controller level, the whole-body IK and a MuJoCo model of the robot in closed
loop, one tick per control period.

Modules (import them directly; this package imports nothing, so importing it needs neither MuJoCo nor Pinocchio):

* :mod:`rtgait.sim.model`: ``build_sim_model(robot)``, the MuJoCo model built at run time from the robot
  description's URDF (free-floating base, sole contact boxes, floor, PD servos, half-sitting start);
  :mod:`rtgait.sim.urdf_import` the URDF as MuJoCo reads it, :mod:`rtgait.sim.actuation` and
  :mod:`rtgait.sim.contact_model` its servos and contacts.
* :mod:`rtgait.sim.measure`: what a controller measures each tick (per-foot wrench, CoP, foot poses, COM, DCM,
  landings); :mod:`rtgait.control.foot_control`: ankle damping and foot force-difference control.
* :mod:`rtgait.control.controller` (settings in :mod:`rtgait.control.settings`): the levels ``open-loop``,
  ``stabilized`` and ``adaptive``.
* :mod:`rtgait.sim.loop`: ``run_sim_loop(sim, controller)``, measure -> controller -> IK -> servos -> physics,
  and ``ClosedLoop``, the same one tick per ``step()`` for callers that act between ticks (its settings in
  :mod:`rtgait.sim.loop_options`, its record, whole or a ring, in :mod:`rtgait.sim.loop_record`, pushes given live
  in :mod:`rtgait.sim.loop_push`; level switches fade in :mod:`rtgait.control.level_fade`);
  :mod:`rtgait.sim.contact`: the per-tick contact record, falls, landings, pushes; :mod:`rtgait.sim.tick_log`: the
  complete per-tick log (velocities, wrenches, targets), written as ``sim.parquet`` by :mod:`rtgait.sim.log_file`;
  :mod:`rtgait.sim.result`: ``SimResult`` and its measures (ZMP errors, slip, rest).
* :mod:`rtgait.io.sim_run`: ``simulate(scenario, robot, controller=...)`` for the CLI; :mod:`rtgait.io.sim_files`
  (``sim.csv``, ``summary.json``, the replay, the printed summary) and :mod:`rtgait.viz.sim_figure` (``zmp_sim``).
* :mod:`rtgait.sim.live`: ``rtgait play``, the walk in real time in MuJoCo's viewer driven from the keyboard (the
  viewer, its markers and text in :mod:`rtgait.viz.live_view`).
* :mod:`rtgait.sim.guided`: ``simulate_guided(sim, walk)``, a walk led by the hand (the paper's Section 6): a
  person pulls and twists the hand along the scenario's ``[guide]`` path, the wrist reading sets the steps.
"""
