"""A kinematic-inertial state estimator: the walking state from the robot's own sensors (encoders, IMU, the feet's
force sensors or the joints' torques), for a robot without the simulator's truth.

**Which estimator, and why.** It is the kinematic-inertial kind the walking controllers that carry real humanoids
use (mc_rtc's KinematicInertial observer with lipm_walking_controller and BWC, auto_stabilizer's): the IMU's filter
gives the tilt, the feet in contact anchor the base through the leg kinematics, a complementary filter blends the
kinematic velocity with the integrated accelerometer. A contact-aided invariant EKF (Hartley 2020) estimates the same
quantities plus the IMU's biases, with covariances to tune and a 15-state update a tick; for a position-controlled
robot on flat, no-slip contact whose IMU filter already gives roll and pitch, the simpler observer reaches the
accuracy the controller needs (``docs/estimation.md``) in a fraction of the cost, and each of its parts can be
checked against the simulator's truth on its own.

Each tick, with the base frame's kinematics (:class:`~rtgait.estimation.kinematics.RobotKinematics`):

1. **Orientation.** The IMU's ``R_WI`` and its mount ``R_BI`` give the base's ``R' = R_WI R_BI^T``; roll and pitch
   are the IMU filter's, smoothed with the gyro (:mod:`rtgait.estimation.attitude_filter`, 0.8 Hz). Yaw
   (``yaw="feet"``, default) is anchored on the feet in contact, whose sole headings are remembered from their
   landings (:mod:`rtgait.estimation.anchors`): an IMU's yaw drifts without a magnetometer and the feet on the ground
   do not turn; ``yaw="imu"`` keeps the IMU's yaw, turned once at the start into the world frame. The gyro measures
   the IMU's body, so the base's angular velocity is ``R_BI w_I`` less the IMU's turn relative to the base.
2. **Feet wrenches.** The ground's wrench on each sole (:mod:`rtgait.estimation.sole_wrenches`): from the foot
   force sensors when the readings have them, less each sensor's zero learnt with its foot in the air
   (:mod:`rtgait.estimation.sensor_zero`; the load detection reads their vertical force with the foot's inertia
   taken out, :mod:`rtgait.estimation.foot_inertia`), else from the legs' joint torques and inverse dynamics, low-passed
   (:mod:`rtgait.estimation.torque_wrenches`); from joint torques, a foot the load detection has in the air is
   reported without load (what is left of a swinging leg's wrench is the estimate's error).
3. **Base position.** ``p = sum_i w_i (a_i - R p_i)`` over the feet anchors ``a_i``, weighted by the feet's vertical
   forces (:mod:`rtgait.estimation.anchors`); with no foot loaded (a flight, a bounce), ``p`` moves on from its last
   value at the base's estimated velocity (step 4).
4. **Velocity.** With ``w`` the gyro's angular velocity in the world, a foot ``i`` held still gives the base
   origin's velocity ``-(w x R p_i) - R p_i'`` (``p_i'`` from the joint velocities); their force-weighted mean, moved
   to the IMU (``+ w x R p_I + R p_I'``), is blended with the IMU's acceleration ``R_WI f + g`` by the complementary
   filter of :mod:`rtgait.estimation.velocity_filter` (3.5 Hz). A loaded foot that turns in the world rocks about its
   centre of pressure, not its origin: that point is held still instead (:mod:`rtgait.estimation.contact_point`).
5. **COM and DCM.** ``c = p + R c_B``, ``c' = v_B + w x R c_B + R c_B'`` (``c_B``, ``c_B'`` from the joints),
   ``xi = c + c'/w0`` with the planner's ``w0``.
6. **Feet states, ZMP, landings** from the soles' estimated poses and wrenches (:mod:`rtgait.estimation.feet`,
   :mod:`rtgait.estimation.load`), with the ground-truth estimator's thresholds; an unloaded foot is loaded (lands)
   only when its sole is near the stance sole's height (:mod:`rtgait.estimation.landing_gate`).
   ``contacts`` is 1 for a foot that carries more than the release force (a force sensor does not count contact
   points), ``other_contacts`` 0 (not sensed).
"""

from __future__ import annotations

import math
from typing import Literal

from rtgait.core.geometry.footsteps import SoleRect
from rtgait.core.geometry.hull import sole_extents
from rtgait.estimation.anchors import FootAnchors, Pose, Vector
from rtgait.estimation.attitude_filter import DEFAULT_ATTITUDE_CUTOFF, AttitudeFilter
from rtgait.estimation.contact_point import rocking_correction
from rtgait.estimation.feet import FeetFromWrenches
from rtgait.estimation.foot_inertia import FootInertia
from rtgait.estimation.joint_friction import JointFriction
from rtgait.estimation.kinematics import RobotKinematics
from rtgait.estimation.landing_gate import (
    DEFAULT_LANDING_CLEARANCE,
    DEFAULT_SUSTAIN_TIME,
    lowest_sole_height,
    near_ground,
)
from rtgait.estimation.load import DEFAULT_LANDING_FRACTION, DEFAULT_MIN_UNLOADED_TIME, LoadHysteresis
from rtgait.estimation.rotations import mat_mul, mat_mul_t, mat_vec, quat_matrix, turned, yaw_of
from rtgait.estimation.sensor_zero import AirborneZero
from rtgait.estimation.sole_wrenches import SoleWrench, sensor_wrench
from rtgait.estimation.state import FootState, Landing, Measurement
from rtgait.estimation.torque_wrenches import DEFAULT_WRENCH_CUTOFF, TorqueWrenches
from rtgait.estimation.velocity_filter import DEFAULT_VELOCITY_CUTOFF, ComplementaryVelocity
from rtgait.interface.readings import SensorReadings
from rtgait.interface.sensor_spec import YAW_SOURCES, YawSource
from rtgait.interface.truth import GroundTruth

__all__ = ["TORQUE_LANDING_FRACTION", "WRENCH_SOURCES", "YAW_SOURCES", "KinematicInertialEstimator"]

WrenchSource = Literal["sensors", "torques"]
WRENCH_SOURCES: tuple[WrenchSource, ...] = ("sensors", "torques")

TORQUE_LANDING_FRACTION = 0.08
"""Landing threshold, as a fraction of the weight, of feet wrenches estimated from joint torques: five standard
deviations of the filtered estimate's error on a swinging leg at G1's described sensor noise (5.0 N, 1.5 % of the
weight; 21 N, 6.5 %, at most over three noise seeds of fig8, ``docs/estimation.md``), so that a swing is not taken
for a landing: Gaussian noise crosses 5 sigma about once in 300 minutes of swing at 500 Hz."""

_NO_LANDINGS: tuple[Landing, ...] = ()
_ZERO3 = (0.0, 0.0, 0.0)
_NAN2 = (math.nan, math.nan)
_new_tuple = tuple.__new__  # a NamedTuple made from a tuple at once, without its generated __new__'s argument parsing


class KinematicInertialEstimator:
    """The walking state from the robot's sensors (module docstring).

    Args:
        kinematics: the robot's kinematics (:class:`~rtgait.estimation.kinematics.RobotKinematics`).
        omega: pendulum frequency ``w = sqrt(g / z_c)`` of the planner (1/s), for the DCM.
        gravity: the gravity's magnitude (m/s^2).
        wrenches: where the feet's wrenches come from: ``"sensors"`` (the feet's force sensors) or ``"torques"`` (the
            legs' joint torques); default the sensors when the kinematics place them.
        landing_force, release_force, min_unloaded_time, min_force, ground_height: as the ground-truth estimator's
            (:class:`~rtgait.estimation.ground_truth.GroundTruthEstimator`), the weight ``kinematics.mass * gravity``;
            the landing force's default is :data:`TORQUE_LANDING_FRACTION` of the weight for ``"torques"``, the release
            force's the ground-truth estimator's for both sources (at most the landing force).
        velocity_cutoff: the complementary velocity filter's cut-off (Hz); ``inf``: kinematics alone.
        attitude_cutoff: the attitude filter's cut-off (Hz); ``inf``: the IMU filter's attitude as it is.
        wrench_cutoff: the cut-off of the low-pass on wrenches from joint torques (Hz); ``inf``: none.
        yaw: where the base's yaw comes from: ``"feet"`` (the feet in contact) or ``"imu"``.
        start_feet: the standing soles' world poses ``(x, y, z, yaw)``, left then right, that fix the world frame
            at the first update (the plan's standing feet); ``None``: the feet's midpoint at the origin.
        rocking: hold each loaded foot's centre of pressure still in the kinematic velocity, not its sole origin
            (:mod:`rtgait.estimation.contact_point`: a foot rocking on an edge turns about it); ``False``: the origin.
        sole: the sole rectangle that bounds the centre of pressure there and gives the soles' lowest corners;
            ``None``: unbounded, the sole origins' heights.
        landing_clearance: highest an unloaded foot's sole may be above a loaded one's to become loaded (m);
            ``inf``: no gate (:mod:`rtgait.estimation.landing_gate`).
        sustain_time: how long an unloaded foot's load must last to count (s).
        joint_friction: with ``"torques"``, the joints' identified friction, which the measured torques carry and
            the links do not get (:mod:`rtgait.estimation.torque_wrenches`, "Friction"); ``None``: none.
        momentum_observer: with ``"torques"``, the generalized-momentum observer instead of the filtered
            accelerations' residual (:mod:`rtgait.estimation.torque_wrenches`, "Momentum observer").
        foot_inertia: with ``"sensors"``, the load detection reads the ground's force with the inertia of the foot
            below each sensor removed (:mod:`rtgait.estimation.foot_inertia`); ``False``: the sensors' force as it is.
        sensor_zero_time: with ``"sensors"``, the airborne time (s) over which each foot sensor's zero is learnt
            while its foot is in the air (:mod:`rtgait.estimation.sensor_zero`, e.g. its ``DEFAULT_ZERO_TIME``);
            ``None`` (default): the readings as they are. Off by default: on Talos's 60 s forward walk in closed loop
            the learnt zeros (under 2.5 N) took the estimated DCM 2-4 times further from the true one, for a reason
            not yet found (``docs/estimation.md``).
    """

    reads_truth = False

    def __init__(
        self,
        kinematics: RobotKinematics,
        omega: float,
        *,
        gravity: float = 9.81,
        wrenches: WrenchSource | None = None,
        landing_force: float | None = None,
        release_force: float | None = None,
        min_unloaded_time: float = DEFAULT_MIN_UNLOADED_TIME,
        min_force: float | None = None,
        ground_height: float | None = None,
        velocity_cutoff: float = DEFAULT_VELOCITY_CUTOFF,
        attitude_cutoff: float = DEFAULT_ATTITUDE_CUTOFF,
        wrench_cutoff: float = DEFAULT_WRENCH_CUTOFF,
        yaw: YawSource = "feet",
        start_feet: tuple[Pose, Pose] | None = None,
        rocking: bool = True,
        sole: SoleRect | None = None,
        landing_clearance: float = DEFAULT_LANDING_CLEARANCE,
        sustain_time: float = DEFAULT_SUSTAIN_TIME,
        joint_friction: JointFriction | None = None,
        momentum_observer: bool = False,
        sensor_zero_time: float | None = None,
        foot_inertia: bool = True,
    ) -> None:
        if not (math.isfinite(omega) and omega > 0.0):
            raise ValueError(f"omega must be > 0 (1/s), got {omega}")
        if math.isnan(landing_clearance) or landing_clearance < 0.0:
            raise ValueError(f"landing_clearance must be >= 0 m (inf: no gate), got {landing_clearance}")
        if not (math.isfinite(gravity) and gravity > 0.0):
            raise ValueError(f"gravity must be > 0 m/s^2, got {gravity}")
        weight = kinematics.mass * gravity
        if not (math.isfinite(weight) and weight > 0.0):
            raise ValueError(f"the robot's weight must be > 0 N, got {weight}")
        if yaw not in YAW_SOURCES:
            raise ValueError(f"yaw must be one of {', '.join(YAW_SOURCES)}, got {yaw!r}")
        if start_feet is not None and (
            len(start_feet) != 2 or any(len(f) != 4 or not all(map(math.isfinite, f)) for f in start_feet)
        ):
            raise ValueError(f"start_feet must be two finite poses (x, y, z, yaw), got {start_feet!r}")
        self.kinematics, self.omega, self.gravity, self.yaw = kinematics, float(omega), float(gravity), yaw
        self.rocking = bool(rocking)
        self._extents = (None, None) if sole is None else (sole_extents(sole, True), sole_extents(sole, False))
        self.start_feet = start_feet
        if wrenches is None:
            wrenches = "torques" if kinematics.foot_sensors is None else "sensors"
        if wrenches not in WRENCH_SOURCES:
            raise ValueError(f"wrenches must be one of {', '.join(WRENCH_SOURCES)}, got {wrenches!r}")
        if wrenches == "sensors" and kinematics.foot_sensors is None:
            raise ValueError("wrenches='sensors' needs the kinematics to place the feet's force sensors")
        self.wrenches: WrenchSource = wrenches
        fraction = DEFAULT_LANDING_FRACTION if wrenches == "sensors" else TORQUE_LANDING_FRACTION
        landing = fraction * weight if landing_force is None else float(landing_force)
        # The release force is the ground-truth estimator's by default (half its landing force), from either source:
        # the quasi-static estimate of an unloading stance leg is as good as a sensor's; only a swinging leg's errs.
        release = 0.5 * DEFAULT_LANDING_FRACTION * weight if release_force is None else float(release_force)
        release = min(release, landing)
        self.load = LoadHysteresis(landing, release, min_unloaded_time, sustain_time)
        self.landing_clearance = float(landing_clearance)
        self.ground_rise = 0.0
        """The planned ground height under the left foot less under the right one (m), which the landing gate allows
        on top of its clearance: set by whoever knows the walk (the walking stack, from its footholds) each tick."""
        self._release = release
        self.min_force = 1e-3 * weight if min_force is None else float(min_force)
        self.feet = FeetFromWrenches(self.load, self.min_force, ground_height)
        self.velocity = ComplementaryVelocity(velocity_cutoff)
        self.attitude = AttitudeFilter(attitude_cutoff)
        self.anchors = FootAnchors()
        self._mounts = kinematics.foot_sensors if wrenches == "sensors" else None
        self._zero = AirborneZero(sensor_zero_time) if wrenches == "sensors" and sensor_zero_time is not None else None
        mounts = self._mounts
        self._inertia = FootInertia(mounts, gravity) if mounts is not None and foot_inertia else None
        self._torques = (
            TorqueWrenches(kinematics, wrench_cutoff, friction=joint_friction, momentum=momentum_observer)
            if wrenches == "torques"
            else None
        )
        self._kinematics_update = kinematics.update
        self.reset()

    def reset(self) -> None:
        """Forget every state: the next update starts the world frame, the filter and the feet's loads afresh."""
        self.load.reset()
        self.velocity.reset()
        self.attitude.reset()
        self.anchors.reset()
        if self._torques is not None:
            self._torques.reset()
        if self._zero is not None:
            self._zero.reset()
        if self._inertia is not None:
            self._inertia.reset()
        self._loaded = (True, True)  # the first tick's feet anchor the world frame
        self._weight_left = 0.5
        self._yaw_offset = 0.0
        self._last_motion: tuple[tuple[float, ...], Vector, Vector, Vector] | None = None
        self._t: float | None = None

    def update(self, readings: SensorReadings | None, truth: GroundTruth | None = None) -> Measurement:
        """The walking state from this tick's ``readings`` (``truth`` is not read).

        Raises:
            ValueError: no readings, no IMU reading, or readings without the wrenches' source.
        """
        if readings is None or readings.imu is None:
            raise ValueError("the kinematic-inertial estimator needs the robot's readings with an IMU")
        t, imu = readings.t, readings.imu
        kin = self._kinematics_update(readings.joint_positions, readings.joint_velocities)
        left_sole, right_sole, imu_frame = kin.left_sole, kin.right_sole, kin.imu
        dt = 0.0 if self._t is None else t - self._t
        self._t = t
        # 1. The base's orientation as the IMU has it (its yaw the IMU's), R' = R_WI R_BI^T, the IMU filter's attitude
        # smoothed with the gyro.
        r_imu = quat_matrix(*self.attitude.update(dt, imu.orientation, imu.angular_velocity))
        r_base = mat_mul_t(r_imu, imu_frame.rotation)
        r_left, r_right = mat_mul(r_base, left_sole.rotation), mat_mul(r_base, right_sole.rotation)
        # The gyro measures the IMU's body: the base turns at w_B = R_BI w_I less the IMU's turn relative to the base;
        # the accelerometer's specific force in the base frame, R_BI f_I.
        # R_BI v written out on the mount's nine entries, as R v below.
        m00, m01, m02, m10, m11, m12, m20, m21, m22 = imu_frame.rotation
        (gx, gy, gz), (fx, fy, fz) = imu.angular_velocity, imu.linear_acceleration
        rwx, rwy, rwz = imu_frame.angular_velocity
        wx = m00 * gx + m01 * gy + m02 * gz - rwx
        wy = m10 * gx + m11 * gy + m12 * gz - rwy
        wz = m20 * gx + m21 * gy + m22 * gz - rwz
        specific = (m00 * fx + m01 * fy + m02 * fz, m10 * fx + m11 * fy + m12 * fz, m20 * fx + m21 * fy + m22 * fz)
        # 2. The ground's wrenches on the soles, in the sole frames.
        torques, zero = self._torques, self._zero
        if torques is None:  # each less its sensor's zero, learnt in the air (step 6)
            wrench_left, wrench_right = self._sensor_wrenches(readings, r_left, r_right)
        else:
            if readings.joint_torques is None:
                raise ValueError("the estimator reads the joint torques, the readings have none")
            wrench_left, wrench_right = torques.update(
                dt, readings.joint_velocities, readings.joint_torques, (wx, wy, wz), specific, imu_frame.position,
                imu_frame.velocity,
            )  # fmt: skip
        # The vertical forces (yaw does not change them) and the weights of the feet in contact (loaded at the last
        # tick): a swinging foot, whatever its estimated force, anchors nothing.
        fz_left = r_left[6] * wrench_left[0] + r_left[7] * wrench_left[1] + r_left[8] * wrench_left[2]
        fz_right = r_right[6] * wrench_right[0] + r_right[7] * wrench_right[1] + r_right[8] * wrench_right[2]
        loaded_left, loaded_right = self._loaded
        positive_left = fz_left if loaded_left and fz_left > 0.0 else 0.0
        positive_right = fz_right if loaded_right and fz_right > 0.0 else 0.0
        if positive_left + positive_right > self.min_force:
            self._weight_left = positive_left / (positive_left + positive_right)
        wl = self._weight_left
        # 3. Yaw and base position from the anchors.
        anchors = self.anchors
        if anchors.poses is None:
            self._yaw_offset = anchors.start(
                mat_vec(r_base, left_sole.position), mat_vec(r_base, right_sole.position),
                (yaw_of(r_left), yaw_of(r_right)), self.start_feet,
            )  # fmt: skip
        feet_yaw = self.yaw == "feet"
        delta = anchors.yaw_correction(wl, yaw_of(r_left), yaw_of(r_right)) if feet_yaw else self._yaw_offset
        c, s = math.cos(delta), math.sin(delta)
        rot, r_left, r_right = turned(c, s, r_base), turned(c, s, r_left), turned(c, s, r_right)
        # R v is written out for the six vectors R turns below: a call each would cost as much as its arithmetic.
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = rot
        (lx, ly, lz), (lvx, lvy, lvz) = left_sole.position, left_sole.velocity
        (rx, ry, rz), (rvx, rvy, rvz) = right_sole.position, right_sole.velocity
        left_rel = (r00 * lx + r01 * ly + r02 * lz, r10 * lx + r11 * ly + r12 * lz, r20 * lx + r21 * ly + r22 * lz)
        right_rel = (r00 * rx + r01 * ry + r02 * rz, r10 * rx + r11 * ry + r12 * rz, r20 * rx + r21 * ry + r22 * rz)
        # Without a foot on the ground (a flight, a fall), no anchor holds: both follow their soles, and the base keeps
        # the yaw the last tick gave it and moves on from its last place at its estimated velocity (the inertial
        # estimate alone, below), whatever the legs do: the anchors, taken at the soles' last poses, would add the
        # feet's motion relative to the base to it (a foot still on the ground through a 1-15 ms bounce would count
        # the base's motion twice).
        standing = loaded_left or loaded_right
        if not standing and self._last_motion is not None:
            # The base origin's velocity at the last tick, v_I - R (w_B x p_I + p_I').
            last_rot, relative, (vx, vy, vz), (px, py, pz) = self._last_motion
            mx, my, mz = mat_vec(last_rot, relative)
            px, py, pz = px + dt * (vx - mx), py + dt * (vy - my), pz + dt * (vz - mz)
        else:
            px, py, pz = anchors.base_position(wl, left_rel, right_rel)
        left_pos = (px + left_rel[0], py + left_rel[1], pz + left_rel[2])
        right_pos = (px + right_rel[0], py + right_rel[1], pz + right_rel[2])
        anchors.settle(wl, (*left_pos, yaw_of(r_left)), (*right_pos, yaw_of(r_right)), standing)
        # 4. Velocity, worked out in the base frame (B) and turned into the world once: the base origin's with each
        # stance foot held still, u = -sum_i w_i (w_B x p_i + p_i'), moved to the IMU (+ w_B x p_I + p_I'), blended
        # with the IMU's acceleration.
        (ox, oy, oz), (ovx, ovy, ovz) = imu_frame.position, imu_frame.velocity
        wr = 1.0 - wl
        # The soles' velocities relative to the base origin, w_B x p_i + p_i' (base frame).
        flx, fly, flz = wy * lz - wz * ly + lvx, wz * lx - wx * lz + lvy, wx * ly - wy * lx + lvz
        frx, fry, frz = wy * rz - wz * ry + rvx, wz * rx - wx * rz + rvy, wx * ry - wy * rx + rvz
        # A loaded foot that rocks turns about its centre of pressure, not its sole origin (contact_point).
        bx = by = bz = 0.0
        if self.rocking:
            w_base, extents = (wx, wy, wz), self._extents
            if positive_left > 0.0:
                bx, by, bz = rocking_correction(
                    w_base, left_sole.rotation, left_sole.angular_velocity, wrench_left, wl, extents[0]
                )
            if positive_right > 0.0:
                ax, ay, az = rocking_correction(
                    w_base, right_sole.rotation, right_sole.angular_velocity, wrench_right, wr, extents[1]
                )
                bx, by, bz = bx + ax, by + ay, bz + az
        # The IMU's velocity relative to the base origin, w_B x p_I + p_I' (base frame).
        sx, sy, sz = wy * oz - wz * oy + ovx, wz * ox - wx * oz + ovy, wx * oy - wy * ox + ovz
        ux = sx - wl * flx - wr * frx + bx
        uy = sy - wl * fly - wr * fry + by
        uz = sz - wl * flz - wr * frz + bz
        kinematic = (r00 * ux + r01 * uy + r02 * uz, r10 * ux + r11 * uy + r12 * uz, r20 * ux + r21 * uy + r22 * uz)
        qx, qy, qz = specific
        acceleration = (r00 * qx + r01 * qy + r02 * qz, r10 * qx + r11 * qy + r12 * qz,
                        r20 * qx + r21 * qy + r22 * qz - self.gravity)  # fmt: skip
        # In flight no foot is held still: the accelerometer alone carries the velocity.
        velocity = self.velocity.update(dt, kinematic if standing else None, acceleration)
        vix, viy, viz = velocity
        self._last_motion = (rot, (sx, sy, sz), velocity, (px, py, pz))  # for a flight's next tick (step 3)
        # 5. COM and its velocity: c = p + R c_B, c' = v_I + R (w_B x (c_B - p_I) + c_B' - p_I').
        (cx, cy, cz), (cvx, cvy, cvz) = kin.com, kin.com_velocity
        dx, dy, dz = cx - ox, cy - oy, cz - oz
        ux, uy, uz = wy * dz - wz * dy + cvx - ovx, wz * dx - wx * dz + cvy - ovy, wx * dy - wy * dx + cvz - ovz
        com = (px + (r00 * cx + r01 * cy + r02 * cz), py + (r10 * cx + r11 * cy + r12 * cz),
               pz + (r20 * cx + r21 * cy + r22 * cz))  # fmt: skip
        com_vel = (vix + (r00 * ux + r01 * uy + r02 * uz), viy + (r10 * ux + r11 * uy + r12 * uz),
                   viz + (r20 * ux + r21 * uy + r22 * uz))  # fmt: skip
        # 6. The feet's states, the ZMP and the landings.
        # A force sensor does not count contact points: 1 while the foot carries more than the release force.
        sole_foot, release, inertia = self.feet.sole_foot, self._release, self._inertia
        load_left = load_right = None
        if torques is not None:  # the load detection reads the faster-filtered forces (torque_wrenches)
            (flx, fly, flz), (frx, fry, frz) = torques.contact_forces
            load_left = r_left[6] * flx + r_left[7] * fly + r_left[8] * flz
            load_right = r_right[6] * frx + r_right[7] * fry + r_right[8] * frz
        elif inertia is not None:  # the load detection reads the ground's force, the foot's inertia removed
            # From the IMU's vertical acceleration and the soles' vertical velocities relative to the IMU, as above.
            vs = r20 * sx + r21 * sy + r22 * sz
            inertia_left, inertia_right = inertia.from_motion(
                dt, (r20, r21, r22), (wx, wy, wz), acceleration[2], r20 * flx + r21 * fly + r22 * flz - vs,
                r20 * frx + r21 * fry + r22 * frz - vs, left_sole, right_sole,
            )  # fmt: skip
            load_left, load_right = fz_left + inertia_left, fz_right + inertia_right
        # A swinging foot lands only near the stance sole's height (landing_gate).
        extents = self._extents
        near_left, near_right = near_ground(self.landing_clearance, self._loaded, (
            lowest_sole_height(left_pos[2], r_left, extents[0]), lowest_sole_height(right_pos[2], r_right, extents[1])
        ), self.ground_rise)  # fmt: skip
        left, left_landing = sole_foot(
            0, t, wrench_left, 1 if fz_left > release else 0, left_pos, r_left, load_left, near_left
        )  # fmt: skip
        right, right_landing = sole_foot(
            1, t, wrench_right, 1 if fz_right > release else 0, right_pos, r_right, load_right, near_right
        )  # fmt: skip
        if torques is not None:
            # A foot the load detection has in the air carries nothing: what the torques give a swinging leg is the
            # estimate's error, not a contact (it would move the ZMP by that force times the foot's distance).
            if not left.loaded:
                left = _new_tuple(FootState, (_ZERO3, _ZERO3, 0.0, _NAN2, _NAN2, *left[5:10], 0))
            if not right.loaded:
                right = _new_tuple(FootState, (_ZERO3, _ZERO3, 0.0, _NAN2, _NAN2, *right[5:10], 0))
        self._loaded = (left.loaded, right.loaded)
        if zero is not None and not (left.loaded and right.loaded):
            # A foot in the air reads its sensor's zero (sensor_zero): the corrected wrench is what is left of it.
            settle, air_time = zero.settle_time, self.load.air_time
            if not left.loaded and air_time(0, t) >= settle:
                if inertia is not None:  # less the foot's vertical inertia (sole frame): an unbiased mean
                    il = inertia_left
                    wrench_left = (wrench_left[0] + il * r_left[6], wrench_left[1] + il * r_left[7],
                                   wrench_left[2] + il * r_left[8], *wrench_left[3:])  # fmt: skip
                zero.learn(0, wrench_left, dt, math.inf)
            if not right.loaded and air_time(1, t) >= settle:
                if inertia is not None:
                    ir = inertia_right
                    wrench_right = (wrench_right[0] + ir * r_right[6], wrench_right[1] + ir * r_right[7],
                                    wrench_right[2] + ir * r_right[8], *wrench_right[3:])  # fmt: skip
                zero.learn(1, wrench_right, dt, math.inf)
        landings = _NO_LANDINGS
        if left_landing is not None or right_landing is not None:
            landings = tuple(landing for landing in (left_landing, right_landing) if landing is not None)
        self.load.prime()
        zmp, total = self.feet.zmp(left, right)
        w = self.omega
        dcm = (com[0] + com_vel[0] / w, com[1] + com_vel[1] / w)
        return _new_tuple(Measurement, (t, com, com_vel, dcm, zmp, total, left, right, landings, 0))

    def _sensor_wrenches(
        self, readings: SensorReadings, r_left: tuple[float, ...], r_right: tuple[float, ...]
    ) -> tuple[SoleWrench, SoleWrench]:
        """The ground's wrenches on the soles in their frames from the feet's force sensors."""
        if readings.left_foot is None or readings.right_foot is None:
            raise ValueError("the estimator reads the feet's force sensors, the readings have none")
        g, mounts, zero = self.gravity, self._mounts, self._zero
        assert mounts is not None  # the kinematics place them when the sensors are the source
        zero_left, zero_right = (None, None) if zero is None else zero.zeros
        # Gravity in each sole frame: R_WS^T (0, 0, -g), the third row of R_WS times -g (yaw does not change it).
        return (
            sensor_wrench(readings.left_foot, mounts[0], (-g * r_left[6], -g * r_left[7], -g * r_left[8]), zero_left),
            sensor_wrench(
                readings.right_foot, mounts[1], (-g * r_right[6], -g * r_right[7], -g * r_right[8]), zero_right
            ),
        )
