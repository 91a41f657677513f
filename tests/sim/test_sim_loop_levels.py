"""Switching the controller level mid-walk (:meth:`WalkingController.set_level`): the settings become the new
level's as ``make_controller`` makes them, the feedback's offsets fade out instead of jumping, and Talos walks on
through open-loop -> stabilized -> adaptive."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest

pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")

from rtgait.control.controller import make_controller
from rtgait.control.level_fade import LEVEL_FADE, fade_weight
from rtgait.core.planner.levels import CONTROLLER_LEVELS
from rtgait.robot.controller_info import robot_info
from rtgait.robot.motion import robot_scenario
from rtgait.sim.loop import ClosedLoop, LoopOptions

QUICK = LoopOptions(start_ramp=0.5, start_hold=0.3, after=0.3)


def walk_of(talos, shorten, steps=4):
    return robot_scenario(shorten("fig8", steps), talos)


def made(level, walk, talos, dt=0.001):
    return make_controller(level, walk.planner_config(), walk.strides(), walk.sole, robot_info(talos), dt=dt)


@pytest.mark.parametrize(("start", "to"), list(itertools.permutations(CONTROLLER_LEVELS, 2)))
def test_a_switch_gives_the_settings_make_controller_gives(talos, shorten, start, to):
    walk = walk_of(talos, shorten)
    controller = made(start, walk, talos)
    controller.set_level(to)
    fresh = made(to, walk, talos)
    assert controller.level == to
    assert controller.planner.config == fresh.planner.config
    # The stride box of step adjustment stays in the options after adaptive (for a return to it); it acts in
    # adaptive only.
    assert dataclasses.replace(controller.options, step_adjustment=None) == dataclasses.replace(
        fresh.options, step_adjustment=None
    )
    if to == "adaptive":
        assert controller.options.step_adjustment == fresh.options.step_adjustment is not None
    assert (controller.feedback is None) == (fresh.feedback is None)
    assert (controller.foot is None) == (fresh.foot is None)
    with pytest.raises(ValueError, match="level must be one of"):
        controller.set_level("closed")  # type: ignore[arg-type]


def test_the_offsets_fade_out_and_talos_walks_through_every_level(talos, talos_sim, shorten):
    """stabilized until 1.3 s (single support), open-loop until 2.2 s, stabilized until 3.0 s, then adaptive."""
    walk = walk_of(talos, shorten, steps=5)
    controller = made("stabilized", walk, talos, dt=talos_sim.control_dt)
    targets = []
    tick = controller.tick

    def logged(t, measurement):
        out = tick(t, measurement)
        targets.append(out)
        return out

    controller.tick = logged  # type: ignore[method-assign]
    loop = ClosedLoop(talos_sim, controller, QUICK)
    switches = {1.3: "open-loop", 2.2: "stabilized", 3.0: "adaptive"}
    at = {}
    while not loop.done:
        for time, level in switches.items():
            if level not in at and loop.t >= time:
                controller.set_level(level)
                at[level] = len(targets)
        assert loop.step(), f"fell at {loop.t:.3f} s"
    result = loop.result()
    assert result.steps_completed == result.steps_planned and not result.fell

    # Down to open-loop: the COM offset and the foot offsets held at the switch fade as w(k).
    n = round(LEVEL_FADE / talos_sim.control_dt)
    k0 = at["open-loop"]
    d0 = np.array(targets[k0 - 1].com_offset)
    f0 = np.array(targets[k0 - 1].offsets)
    assert np.hypot(*d0) > 1e-4 and np.abs(f0).max() > 1e-4, "there was something to fade"
    for k in range(1, n + 30):
        out = targets[k0 + k - 1]
        w = fade_weight(k, n)
        assert np.allclose(out.com_offset, w * d0, rtol=0, atol=1e-12), k
        assert np.allclose(out.offsets, w * f0, rtol=0, atol=1e-12), k
        # The COM target is the plan's plus the offset (m); the commanded ZMP is the plan's.
        assert out.zmp_command == out.zmp_planned
    # Back up: the new law starts from zero offsets, so the targets start from the plan's: after its first tick
    # the COM offset is one tick of the admittance d' = -A (p_cmd - p_measured), |d| <= A dt |p_cmd - p_measured|,
    # the ZMP error under 0.4 m on these feet.
    k1 = at["stabilized"]
    admittance = controller.options.dcm.com_admittance
    assert 0.0 < np.hypot(*targets[k1].com_offset) <= admittance * talos_sim.control_dt * 0.4
    assert np.abs(np.array(targets[k1].offsets)).max() < 1e-4
    assert np.hypot(*targets[at["adaptive"] - 1].com_offset) > np.hypot(*targets[k1].com_offset)
    # Adaptive from 3.0 s on: it observes and re-anchors the plan on the landings that follow.
    touchdowns = [e for e in result.events if e.kind == "touchdown"]
    assert touchdowns and all(e.t >= 3.0 for e in touchdowns)
    assert result.controller == "adaptive"
