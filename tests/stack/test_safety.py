"""The stack's safety layer: joint limits against the URDF's, the watchdog on readings and estimates, the catch at the
tick's boundary, and the latched damping command (no physics: a stand-in estimator feeds the stack)."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Callable

import numpy as np
import pytest

pytest.importorskip("pinocchio")

from rtgait.estimation.state import FootState, Measurement
from rtgait.interface.command import JointCommand
from rtgait.interface.joint_limits import JointLimits
from rtgait.interface.readings import ImuReading, SensorReadings
from rtgait.robot.joint_inertia import carried_inertia, damping_gains
from rtgait.robot.joint_limits import joint_limits
from rtgait.robot.model import RobotModel
from rtgait.robot.motion import robot_scenario
from rtgait.scenario import load_scenario
from rtgait.stack.command_limits import POSITION_MARGIN
from rtgait.stack.safety import SafetyLayer, SafetySettings
from rtgait.stack.setup import start_pose, walking_stack

DT = 0.001
STALE = SafetySettings().stale_periods


@pytest.fixture(scope="module")
def talos() -> RobotModel:
    return RobotModel.load("talos")


def urdf_limits(robot: RobotModel) -> dict[str, dict[str, float]]:
    """Each joint's ``<limit>`` read straight from the URDF file."""
    root = ET.parse(robot.description.urdf).getroot()
    return {
        joint.get("name"): {key: float(value) for key, value in joint.find("limit").attrib.items()}
        for joint in root.iter("joint")
        if joint.find("limit") is not None
    }


class StandIn:
    """An estimator that reports Talos standing still at the walk's start, or what ``spoil`` makes of it."""

    reads_truth = False

    def __init__(self, standing: Measurement) -> None:
        self.standing = standing
        self.spoil: Callable[[Measurement], Measurement] | None = None

    def reset(self) -> None:
        pass

    def update(self, readings: SensorReadings | None, truth: object) -> Measurement:
        t = readings.t if readings is not None else 0.0
        m = self.standing._replace(t=t)
        return self.spoil(m) if self.spoil is not None else m


def standing_measurement(stack, weight: float) -> Measurement:
    cog, left, right = start_pose(stack.controller.planner)

    def foot(pose: list[float]) -> FootState:
        x, y, z, yaw = pose
        return FootState((0.0, 0.0, weight / 2), (0.0, 0.0, 0.0), weight / 2, (x, y), (0.0, 0.0), (x, y, z, yaw),
                         0.0, 0.0, 0.0, True, 4)  # fmt: skip

    com = (cog[0], cog[1], cog[2])
    return Measurement(0.0, com, (0.0, 0.0, 0.0), com[:2], com[:2], weight, foot(left), foot(right), (), 0)


def new_stack(talos: RobotModel):
    """fig8's stack on Talos, fed by the stand-in estimator, not started."""
    walk = robot_scenario(load_scenario("fig8"), talos)
    stack = walking_stack(talos, walk, dt=DT, estimator=StandIn.__new__(StandIn))
    stack.estimator = StandIn(standing_measurement(stack, talos.mass * 9.81))
    return stack


@pytest.fixture
def stack(talos):
    """:func:`new_stack`, started on upright readings."""
    stack = new_stack(talos)
    stack.start(0.0, stack.estimate(readings(stack, 0.0)))
    return stack


def readings(stack, t: float, **changes: object) -> SensorReadings:
    """Readings of the robot standing at its start configuration, stamped ``t``, the IMU upright."""
    q = stack.q[7:].copy()
    imu = ImuReading((1.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 9.81))
    return SensorReadings(t, q, np.zeros_like(q), np.zeros_like(q), imu)._replace(**changes)


def nan_at(values: np.ndarray, i: int) -> np.ndarray:
    values = values.copy()
    values[i] = math.nan
    return values


def assert_damping(stack, out, kind: str) -> None:
    """``out`` is the damping command and the layer tripped once, for ``kind``."""
    command = out.command
    assert out.targets is None and out.measurement is None
    np.testing.assert_array_equal(command.kp, 0.0)
    np.testing.assert_array_equal(command.velocities, 0.0)
    np.testing.assert_array_equal(command.torques, 0.0)
    np.testing.assert_array_equal(command.kd, stack.safety.damping_kd)
    assert (command.kd > 0.0).all()
    assert stack.safety.damping
    assert [e.kind for e in stack.safety.events] == [kind]
    assert stack.safety.counts[kind] == 1


# ----- limits ----------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["talos", "g1"])
def test_the_joint_limits_are_the_urdfs(name, talos):
    robot = talos if name == "talos" else RobotModel.load(name)
    limits, urdf = joint_limits(robot), urdf_limits(robot)
    assert limits.names == tuple(robot.joint_names)
    for i, joint in enumerate(limits.names):
        assert limits.lower[i] == urdf[joint]["lower"] and limits.upper[i] == urdf[joint]["upper"]
        assert limits.velocity[i] == urdf[joint]["velocity"] and limits.torque[i] == urdf[joint]["effort"]


def test_commands_out_of_range_are_clipped_and_counted(talos):
    limits = joint_limits(talos)
    safety = SafetyLayer(limits, np.ones(len(limits.names)), 0.84)
    inside = 0.5 * (limits.lower + limits.upper)
    command = JointCommand(inside.copy(), np.zeros_like(inside), np.zeros_like(inside))
    assert safety.limit(command) is command  # within every limit: passed as it is, no copy

    knee = limits.names.index("leg_left_4_joint")  # range [0, 2.618] rad, 7 rad/s, 300 N m in the URDF
    hip = limits.names.index("leg_right_1_joint")
    q, dq, tau = inside.copy(), np.zeros_like(inside), np.zeros_like(inside)
    q[knee], q[hip] = -0.2, 3.0  # below the knee's stop, above the hip's
    dq[knee], tau[hip] = -9.0, 1000.0
    out = safety.limit(JointCommand(q, dq, tau))
    assert out.positions[knee] == pytest.approx(0.0 + POSITION_MARGIN)
    assert out.positions[hip] == pytest.approx(0.349 - POSITION_MARGIN, abs=1e-3)
    assert out.velocities[knee] == -7.0 and out.torques[hip] == 100.0
    others = np.ones(len(q), bool)
    others[[knee, hip]] = False
    np.testing.assert_array_equal(out.positions[others], inside[others])
    safety.limit(JointCommand(q, dq, tau))  # a second clipped tick
    counted = safety.clip.counted()
    assert counted == {
        "position": {"leg_left_4_joint": 2, "leg_right_1_joint": 2},
        "velocity": {"leg_left_4_joint": 2},
        "torque": {"leg_right_1_joint": 2},
    }
    assert safety.clip.torque_ticks == 2  # the ticks with a clipped torque, as they happen
    tau[knee] = -1000.0  # two joints clipped in one tick: one tick more
    safety.limit(JointCommand(inside.copy(), np.zeros_like(inside), tau))
    assert safety.clip.torque_ticks == 3
    safety.clip.reset()
    assert safety.clip.torque_ticks == 0


def test_joint_limits_refuse_inconsistent_values():
    with pytest.raises(ValueError, match="lower limit"):
        JointLimits(("a",), np.array([1.0]), np.array([0.0]), np.array([1.0]), np.array([1.0]))
    with pytest.raises(ValueError, match="velocity limit must be > 0"):
        JointLimits(("a",), np.array([0.0]), np.array([1.0]), np.array([0.0]), np.array([1.0]))
    with pytest.raises(ValueError, match="one value per joint"):
        JointLimits(("a", "b"), np.zeros(2), np.ones(2), np.ones(3), np.ones(2))


def test_damping_gains_scale_with_the_carried_inertia(talos):
    kd = damping_gains(talos, time_constant=0.5)
    _, carried = carried_inertia(talos)
    np.testing.assert_allclose(kd * 0.5, carried)
    knee, hip_yaw = talos.joint_names.index("leg_left_4_joint"), talos.joint_names.index("leg_left_1_joint")
    assert kd[knee] > 5 * kd[hip_yaw]  # the knee carries the robot, the hip's yaw turns a leg
    with pytest.raises(ValueError, match="time constant"):
        damping_gains(talos, 0.0)


def test_the_default_damping_of_g1s_legs_is_unitrees():
    """Unitree's damping command gives every G1 motor kd = 8 N m s/rad: the default gains of its legs average that."""
    g1 = RobotModel.load("g1")
    kd = damping_gains(g1)
    legs = [kd[i] for i, name in enumerate(g1.joint_names) if not name.startswith("waist")]
    assert len(legs) == 12 and np.mean(legs) == pytest.approx(8.0, rel=0.1)


# ----- the watchdog ----------------------------------------------------------------------------------------------
def test_a_normal_stream_never_trips(stack):
    for k in range(1, 200):
        out = stack.tick(k * DT, readings(stack, k * DT))
        assert out.targets is not None and out.command.kp is None
    assert not stack.safety.damping and stack.safety.events == []


def test_readings_stale_for_more_than_n_periods_put_the_robot_in_damping(stack):
    for k in range(1, 10):
        stack.tick(k * DT, readings(stack, k * DT))
    frozen = readings(stack, 9 * DT)
    for k in range(10, 10 + STALE):  # the stamp still for N periods: tolerated
        out = stack.tick(k * DT, frozen)
        assert out.targets is not None, k
    out = stack.tick((10 + STALE) * DT, frozen)  # the (N+1)th
    assert_damping(stack, out, "stale-readings")
    event = stack.safety.events[0]
    assert event.t == pytest.approx((10 + STALE) * DT) and f"{STALE + 1} periods" in event.detail
    # Latched: fresh readings do not bring the controller back; a reset does.
    out = stack.tick(20 * DT, readings(stack, 20 * DT))
    assert out.targets is None and len(stack.safety.events) == 1
    stack.safety.reset()
    assert stack.tick(21 * DT, readings(stack, 21 * DT)).targets is not None


@pytest.mark.parametrize(
    "spoil",
    [
        pytest.param(lambda r: r._replace(joint_positions=nan_at(r.joint_positions, 3)), id="joint-nan"),
        pytest.param(lambda r: r._replace(joint_velocities=np.full_like(r.joint_velocities, np.inf)), id="dq-inf"),
        pytest.param(lambda r: r._replace(imu=r.imu._replace(orientation=(math.nan, 0.0, 0.0, 0.0))), id="imu-nan"),
        pytest.param(lambda r: r._replace(imu=r.imu._replace(angular_velocity=(0.0, math.inf, 0.0))), id="gyro-inf"),
        pytest.param(lambda r: r._replace(t=math.nan), id="stamp-nan"),
    ],
)
def test_non_finite_readings_put_the_robot_in_damping_without_an_exception(stack, spoil):
    good = readings(stack, DT)
    stack.tick(DT, good)
    out = stack.tick(2 * DT, spoil(readings(stack, 2 * DT)))
    assert_damping(stack, out, "bad-readings")
    assert "NaN or infinite" in stack.safety.events[0].detail
    # The damping command holds the last finite encoder reading as its (unused) position reference.
    np.testing.assert_array_equal(out.command.positions, good.joint_positions)


def test_a_non_finite_estimate_puts_the_robot_in_damping(stack):
    stack.tick(DT, readings(stack, DT))
    stack.estimator.spoil = lambda m: m._replace(com_vel=(math.nan, 0.0, 0.0))
    assert_damping(stack, stack.tick(2 * DT, readings(stack, 2 * DT)), "bad-estimate")


@pytest.mark.parametrize(
    ("spoil", "kind", "words"),
    [
        (lambda m: m._replace(com=(m.com[0] + 0.06, m.com[1], m.com[2])), "estimate-diverged", "in one tick"),
        (lambda m: m._replace(com=(m.com[0], m.com[1], 0.3)), "fall", "above the lower sole"),
    ],
)
def test_an_estimate_that_jumps_or_drops_puts_the_robot_in_damping(stack, spoil, kind, words):
    stack.tick(DT, readings(stack, DT))
    stack.estimator.spoil = spoil
    assert_damping(stack, stack.tick(2 * DT, readings(stack, 2 * DT)), kind)
    assert words in stack.safety.events[0].detail


def test_a_com_far_from_both_soles_is_a_diverged_estimate(talos):
    limits = joint_limits(talos)
    safety = SafetyLayer(limits, np.ones(len(limits.names)), 0.84, SafetySettings(com_jump=10.0))
    foot = FootState((0, 0, 0), (0, 0, 0), 0, (0, 0), (0, 0), (0.0, 0.1, 0.0, 0.0), 0, 0, 0, True, 4)
    right = foot._replace(pose=(0, -0.1, 0, 0))
    m = Measurement(0.0, (0.0, 0.0, 0.8), (0, 0, 0), (0, 0), (0, 0), 0, foot, right, (), 0)
    assert safety.check_measurement(m) is None
    assert safety.check_measurement(m._replace(com=(0.8, 0.0, 0.8))) is None  # 0.806 m from the soles: a leg reaches
    kind, detail = safety.check_measurement(m._replace(com=(0.9, 0.0, 0.8)))
    assert kind == "estimate-diverged" and "from the nearer sole" in detail


def test_a_tilted_imu_is_a_fall(stack):
    stack.tick(DT, readings(stack, DT))
    upright = readings(stack, 2 * DT)
    tilt = math.radians(44.0)  # about x, from the upright first reading
    slight = upright.imu._replace(orientation=(math.cos(tilt / 2), math.sin(tilt / 2), 0.0, 0.0))
    assert stack.tick(2 * DT, upright._replace(imu=slight)).targets is not None
    tilt = math.radians(46.0)
    fallen = upright.imu._replace(orientation=(math.cos(tilt / 2), math.sin(tilt / 2), 0.0, 0.0))
    assert_damping(stack, stack.tick(3 * DT, readings(stack, 3 * DT, imu=fallen)), "fall")
    assert "46 degrees" in stack.safety.events[0].detail


def test_the_imus_mounting_does_not_count_as_a_tilt(talos):
    """Talos's IMU is mounted upside down: its first attitude is upright, whatever it reads; tilts count from it."""
    stack = new_stack(talos)
    turned = (0.0, 1.0, 0.0, 0.0)  # by pi about x
    mounted = ImuReading(turned, (0.0, 0.0, 0.0), (0.0, 0.0, -9.81))
    stack.start(0.0, stack.estimate(readings(stack, 0.0, imu=mounted)))
    for k in range(1, 20):
        assert stack.tick(k * DT, readings(stack, k * DT, imu=mounted)).targets is not None
    c, s = math.cos(math.radians(23.0)), math.sin(math.radians(23.0))  # then 46 degrees about y, in the IMU frame
    w, x, y, z = turned
    tilted = (w * c - y * s, x * c - z * s, y * c + w * s, z * c + x * s)  # turned * (c, 0, s, 0)
    out = stack.tick(20 * DT, readings(stack, 20 * DT, imu=mounted._replace(orientation=tilted)))
    assert_damping(stack, out, "fall")
    assert "46 degrees" in stack.safety.events[0].detail


# ----- errors at the tick's boundary -------------------------------------------------------------------------------
class MeasuredInputError(ValueError):
    """Stands for the planner's error on a measured input out of its bounds."""


def test_a_planner_error_inside_the_tick_is_caught_logged_and_damps(stack):
    stack.tick(DT, readings(stack, DT))

    def observe(*args: object, **kwargs: object) -> None:
        raise MeasuredInputError("measured COM velocity 40 m/s is out of the planner's bounds")

    stack.controller.planner.observe = observe
    out = stack.tick(2 * DT, readings(stack, 2 * DT))  # no exception
    assert_damping(stack, out, "error")
    assert stack.safety.events[0].detail == (
        "MeasuredInputError: measured COM velocity 40 m/s is out of the planner's bounds"
    )
    assert stack.safety.events[0].t == 2 * DT


def test_an_estimator_error_is_caught_and_damps(stack):
    def refuse(m: Measurement) -> Measurement:
        raise ValueError("the left foot's wrench sensor is not in the readings")

    stack.estimator.spoil = refuse
    out = stack.tick(DT, readings(stack, DT))
    assert_damping(stack, out, "error")
    assert "wrench sensor" in stack.safety.events[0].detail


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_a_non_finite_joint_command_damps(stack, bad):
    stack.tick(DT, readings(stack, DT))
    solve = stack.ik.solve

    def diverged(*args: object, **kwargs: object):
        q, error = solve(*args, **kwargs)
        q = q.copy()
        q[7 + 3] = bad
        return q, error

    stack.ik.solve = diverged
    assert_damping(stack, stack.tick(2 * DT, readings(stack, 2 * DT)), "bad-command")


def test_other_exceptions_are_not_swallowed(stack):
    """Only bad-input errors become damping: a programming error still surfaces."""

    def broken(*args: object, **kwargs: object) -> None:
        raise KeyError("a bug")

    stack.controller.planner.observe = broken
    with pytest.raises(KeyError):
        stack.tick(DT, readings(stack, DT))


def test_a_first_estimate_at_fault_damps_instead_of_starting(talos):
    stack = new_stack(talos)
    first = readings(stack, 0.0)
    measurement = stack.estimate(first._replace(joint_positions=np.full_like(first.joint_positions, np.nan)))
    assert measurement is None
    stack.start(0.0, measurement)
    assert not stack.controller.planner.started
    assert_damping(stack, stack.control(0.0, measurement), "bad-readings")
    np.testing.assert_array_equal(stack.control(DT, None).command.positions, stack.q[7:])  # no finite reading yet
