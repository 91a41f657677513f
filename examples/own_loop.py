"""rtgait's controller stack in a control loop of your own: read the sensors, tick the stack, write the joints.

The stack estimates the walking state from the sensors alone (IMU, encoders, feet force sensors or joint torques:
``state="estimated"``), plans and controls the walk, solves the whole-body IK and writes one joint command per
period, through its safety layer. fig8's footsteps without its step change (a loop of yours hands changes to
``stack.controller.planner``). The robot here is Talos in MuJoCo (:class:`rtgait.sim.robot.SimRobot`); a real robot's
driver implements the same two calls, ``read()`` and ``write(command)`` (docs/on_your_robot.md maps them to Unitree's
LowState/LowCmd and to ros2_control).

Run: ``python examples/own_loop.py [--robot talos|g1] [--seconds S]``; it prints the estimated COM each second.
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


def walk(seconds: float, robot_name: str = "talos") -> SimRobot:
    robot = RobotModel.load(load_robot(robot_name))
    sim = build_sim_model(robot)  # the simulated robot; on hardware, your driver
    dt = sim.control_dt
    stack = walking_stack(robot, robot_scenario(load_scenario("fig8"), robot), dt=dt, state="estimated")
    body = SimRobot(sim, sim.new_data(q=stack.q), stack.q[7:])  # standing at the walk's start, clock at 0

    stack.start(0.0, stack.estimate(body.read()))
    for k in range(round(seconds / dt)):
        readings = body.read()  # encoders, IMU, force sensors: stamped with the robot's clock (s)
        out = stack.tick(readings.t, readings)  # sensors -> estimate -> control -> IK -> safety -> joints
        body.write(out.command)
        body.first_substep()  # the physics of one control period (a real robot just runs)
        for i in range(1, body.substeps):
            body.substep(i)
        if out.targets is None:  # the safety layer tripped: its damping command from then on (rtgait.stack.safety)
            event = stack.safety.events[-1]
            if event.t == readings.t:
                print(f"t {readings.t:5.2f} s  damping: {event.kind}, {event.detail}")
            continue
        if k % round(1.0 / dt) == 0:
            com, planned = out.measurement.com, out.targets.com
            print(
                f"t {readings.t:5.2f} s  COM ({com[0]:+.3f}, {com[1]:+.3f}, {com[2]:.3f}) m, "
                f"planned ({planned[0]:+.3f}, {planned[1]:+.3f}) m, support {out.targets.support}"
            )
    return body


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="talos", help="a built-in robot or a robot description file")
    parser.add_argument("--seconds", type=float, default=14.0, help="how long to walk (s, default 14: all of fig8)")
    arguments = parser.parse_args()
    walk(arguments.seconds, arguments.robot)
