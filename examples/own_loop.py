"""rtgait's controller stack in a control loop of your own: read the sensors, tick the stack, write the joints.

fig8's footsteps without its step change (a loop of yours hands changes to ``stack.controller.planner``).

The robot here is Talos in MuJoCo (:class:`rtgait.sim.robot.SimRobot`); a real robot's driver implements the same
two calls, ``read()`` (its sensor readings) and ``write(command)`` (its joint references), and brings its own
estimator in place of the simulator's ground truth (:class:`rtgait.estimation.estimator.Estimator`).

Run: ``python examples/own_loop.py [--seconds S]``; it prints where the COM and the feet are each second.
"""

from __future__ import annotations

import argparse

from rtgait.robot.description import load_robot
from rtgait.robot.model import RobotModel
from rtgait.robot.motion import robot_scenario
from rtgait.scenario import load_scenario
from rtgait.sim.model import build_sim_model
from rtgait.sim.robot import SimRobot
from rtgait.stack.setup import walking_stack


def walk(seconds: float) -> SimRobot:
    robot = RobotModel.load(load_robot("talos"))
    sim = build_sim_model(robot)  # the simulated robot; on hardware, your driver
    stack = walking_stack(robot, robot_scenario(load_scenario("fig8"), robot), dt=sim.control_dt)
    body = SimRobot(sim, sim.new_data(q=stack.q), stack.q[7:])  # standing at the walk's start

    stack.start(0.0, stack.estimate(body.read(), body.ground_truth(t=0.0)))
    for k in range(round(seconds / sim.control_dt)):
        t = k * sim.control_dt
        out = stack.tick(t, body.read(), body.ground_truth(t=t))  # sensors -> estimate -> control -> IK -> joints
        body.write(out.command)
        body.first_substep()  # the physics of one control period (a real robot just runs)
        for i in range(1, body.substeps):
            body.substep(i)
        if out.targets is None:  # the safety layer tripped: its damping command from then on (rtgait.stack.safety)
            event = stack.safety.events[-1]
            if event.t == t:
                print(f"t {t:5.2f} s  damping: {event.kind}, {event.detail}")
            continue
        if k % round(1.0 / sim.control_dt) == 0:
            com, planned = out.measurement.com, out.targets.com
            print(f"t {t:5.2f} s  COM ({com[0]:+.3f}, {com[1]:+.3f}, {com[2]:.3f}) m, "
                  f"planned ({planned[0]:+.3f}, {planned[1]:+.3f}) m, support {out.targets.support}")
    return body


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=14.0, help="how long to walk (s, default 14: all of fig8)")
    walk(parser.parse_args().seconds)
