"""The simulated robot's sensor readings, as its real sensors report them: noisy, biased, quantized and late.

MuJoCo's sensors (:mod:`rtgait.sim.sensor_sites`) give the true values, all of one state: read after ``mj_step``,
the state that step started from (one physics step before ``data.time``), the same state as the simulator's truth
(:mod:`rtgait.sim.ground_truth`); read after ``mj_forward``, the state now. MuJoCo does not apply a sensor's
``noise`` attribute; the errors are added here, with the values of the description's ``[sensors]``
(:class:`~rtgait.interface.sensor_spec.SensorSpec`) times the run's noise factor (:class:`~rtgait.sim.config.
SensorSettings`), one reading per control tick of period ``dt``:

* white noise of standard deviation ``sigma`` on each joint position (then quantized to the encoder's step
  ``r``: ``r round(q / r)``), velocity and torque, and on each force and torque of the feet's sensors, to which
  an offset drawn once per run is added;
* gyro ``w_m = w + b + n``, accelerometer ``f_m = R^T (a - g) + b + n``: white noise of standard deviation
  ``N / sqrt(dt)`` for a density ``N``, and a bias drawn once per run that walks by ``N_b sqrt(dt)`` a tick;
* the accelerometer's ``a`` is the IMU's mean acceleration over the sample period, the change of the IMU site's
  velocity since the last reading, ``a = (v_k - v_k-1) / (t_k - t_k-1)``, and ``R`` its orientation at the reading:
  what a real IMU outputs, whose accelerometer is sampled through an anti-aliasing filter or integrated into a
  velocity increment over the period (with the sculling correction that expresses it in the frame at the period's
  end). MuJoCo's own accelerometer is the acceleration of one instant, one physics step of the period, computed
  before the step integrates the servos' damping implicitly: it disagrees with the velocity the simulation goes on
  to have by about 0.3 m/s^2 RMS on a walk (``docs/robots.md``, "Sensors"). The first reading, which has no period
  before it, is MuJoCo's;
* the joint torque is the one the drive applied over the physics step that starts at the reading's state: MuJoCo's
  actuator force of that state, ``kp e - kd dq``, is integrated with its damping at the step's end velocity
  (``implicitfast``), so the torque that moved the joint is ``kp e - kd dq_end``, the reading's plus
  ``kd (dq - dq_end)`` (nothing while the drive saturates: the integrator drops the damping then). A real drive's
  torque (a strain gauge's, a motor current's) is the one that moves the joint; MuJoCo's reading differs from it by
  the damping's change over one step, which on G1's stiff legs made the legs' wrench from their torques err by 6 N
  RMS on a swinging foot with noise-free sensors (``docs/estimation.md``);
* the feet's force sensors, likewise, read the wrench of the step's acceleration, not of MuJoCo's forward dynamics
  (:mod:`rtgait.sim.implicit_wrench`);
* the IMU filter's orientation ``q_m = q_e q``, an error rotation in the world frame: white roll and pitch, and a yaw
  that drifts at a rate drawn once per run (``yaw = rate t``, ``t`` from the first reading).

With a model error (:mod:`rtgait.sim.model_error`) each encoder also reads its joint's zero offset, ``q + o``, at
any noise factor: the offset belongs to the robot's calibration, not to its sensors' noise.

All the white noise and walks of a tick come from one call of the run's seeded generator, so a seed fixes the
readings. A latency of ``L`` control periods delivers at each tick the reading sampled ``L`` ticks before (the first
one until then), stamped with its sampling time. Noise factor 0: the truth, exactly (not quantized either), but for
the encoder offsets of a model error.

Each :meth:`SensorModel.read` is one control tick: call it once a tick.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from rtgait.interface.readings import ImuReading, SensorReadings, Wrench
from rtgait.sim.config import SensorSettings
from rtgait.sim.sensor_sites import IMU_SIZE

if TYPE_CHECKING:
    from rtgait.interface.sensor_spec import SensorSpec
    from rtgait.sim.model import SimModel

__all__ = ["SensorModel", "applied_damping"]

_new_tuple = tuple.__new__  # a NamedTuple made from a tuple at once, without its generated __new__'s argument parsing


class SensorModel:
    """The readings of a simulated robot's sensors (module docstring).

    Args:
        sim: the simulated robot's model (its sensors' layout, its description's ``[sensors]``, its control period).
        settings: noise factor, latency and seed; default ``sim.config.sensors``.
        spec: the sensors' noise levels and latency; default the description's ``[sensors]`` (their frames are the
            model's in any case).

    Attributes:
        latency: control periods between sampling and reading.
        noise: the noise factor.
    """

    def __init__(self, sim: SimModel, settings: SensorSettings | None = None, spec: SensorSpec | None = None) -> None:
        layout = sim.sensors
        if layout is None:  # pragma: no cover - build_sim_model always lays them out
            raise ValueError("the simulated robot's model has no sensors")
        settings = settings or sim.config.sensors
        spec = spec or sim.robot.description.sensors
        if (spec.imu is None) == layout.imu or (spec.feet is None) == layout.feet:
            raise ValueError("the sensor spec must have the IMU and foot sensors the model has")
        self.layout, self.spec, self.noise = layout, spec, settings.noise
        self.latency = spec.latency if settings.latency is None else settings.latency
        self.dt = dt = sim.control_dt
        n, size = layout.joints, layout.size
        self.joint_torques = spec.joint_torques
        s = settings.noise
        self._rng = np.random.default_rng(settings.seed)

        # One reading's white noise (standard deviations, in the layout of the readings), then the bias walks.
        white = np.zeros(size)
        white[0:n], white[n : 2 * n], white[2 * n : 3 * n] = spec.encoder_noise, spec.velocity_noise, spec.torque_noise
        offset = np.zeros(size)  # biases and offsets, added to each reading
        walk = np.zeros(6)  # the gyro's and accelerometer's bias walk per tick
        imu, feet = spec.imu, spec.feet
        k = 3 * n
        self._imu_at = self._rp = -1
        self._yaw_rate = self._tilt_noise = 0.0
        if imu is not None:
            self._imu_at = k
            root = 1.0 / math.sqrt(dt)
            white[k + 4 : k + 7], white[k + 7 : k + 10] = imu.gyro_noise_density * root, imu.accel_noise_density * root
            walk[0:3], walk[3:6] = imu.gyro_bias_walk * math.sqrt(dt), imu.accel_bias_walk * math.sqrt(dt)
            self._tilt_noise = s * imu.orientation_noise
            k += IMU_SIZE
        if feet is not None:
            self._feet_at = k
            for side in (k, k + 6):
                white[side : side + 3], white[side + 3 : side + 6] = feet.force_noise, feet.torque_noise
        white *= s
        walk *= s
        # The per-run draws, before any tick: the IMU's biases and yaw drift rate, the force sensors' offsets.
        if imu is not None:
            k = self._imu_at
            start = self._rng.standard_normal(7) * s
            offset[k + 4 : k + 7] = start[0:3] * imu.gyro_bias
            offset[k + 7 : k + 10] = start[3:6] * imu.accel_bias
            self._yaw_rate = float(start[6]) * imu.yaw_drift
        if feet is not None:
            k = self._feet_at
            start = self._rng.standard_normal(12) * s
            for side in (k, k + 6):
                offset[side : side + 3] = start[side - k : side - k + 3] * feet.force_offset
                offset[side + 3 : side + 6] = start[side - k + 3 : side - k + 6] * feet.torque_offset
        if sim.encoder_offsets is not None:
            offset[0:n] = sim.encoder_offsets
        self._white, self._offset, self._walk = white, offset, walk
        self._resolution = spec.encoder_resolution if s > 0.0 else 0.0
        # The draws of one tick: white noise for every reading, the bias walks, roll and pitch of the filter.
        self._draws = np.empty(size + (8 if imu is not None else 0))
        self._gravity = tuple(sim.model.opt.gravity.tolist())
        self._last_velocity: tuple[float, float, float, float] | None = None  # sampling time, the IMU's velocity
        self._ring = np.empty((self.latency + 1, size))
        self._stamps = [0.0] * (self.latency + 1)
        self.ticks = 0

    def read(
        self, sensordata: np.ndarray, t: float, damping: np.ndarray | None = None, feet: np.ndarray | None = None
    ) -> SensorReadings:
        """The reading of this control tick from MuJoCo's ``sensordata`` (true values, see the module docstring),
        sampled at ``t`` (s), delivered :attr:`latency` ticks late; ``damping``: each joint's ``kd (dq - dq_end)``
        over the physics step from the sampled state (N m, joint order; 0 where the drive saturates), added to the
        torques (:func:`applied_damping`); ``feet``: added to the feet's force sensors (12 numbers, MuJoCo's sign;
        :mod:`rtgait.sim.implicit_wrench`)."""
        layout = self.layout
        size, ring, k = layout.size, self._ring, self.ticks
        slot = k % len(ring)
        values = ring[slot]
        values[:] = sensordata[layout.start : layout.stop]
        if damping is not None:
            n = layout.joints
            values[2 * n : 3 * n] += damping
        if feet is not None:
            values[size - 12 :] += feet
        if self._imu_at >= 0:
            self._mean_specific_force(values, t)
        values += self._offset
        if self.noise > 0.0:
            draws = self._draws
            self._rng.standard_normal(out=draws)
            values += self._white * draws[:size]
            if self._imu_at >= 0:
                self._walk_biases(draws[size : size + 6])
                self._tilt(values, float(draws[size + 6]), float(draws[size + 7]), k * self.dt)
            resolution = self._resolution
            if resolution > 0.0:
                counts = values[: layout.joints]
                counts *= 1.0 / resolution
                np.rint(counts, out=counts)
                counts *= resolution
        self._stamps[slot] = t
        if k == 0:  # until a reading `latency` ticks old exists, the first one is delivered
            ring[1:] = values
            self._stamps[1:] = [t] * (len(ring) - 1)
        self.ticks = k + 1
        delivered = (k + 1) % len(ring)  # the oldest slot: written `latency` ticks ago
        return self._readings(ring[delivered].copy(), self._stamps[delivered])

    def _mean_specific_force(self, values: np.ndarray, t: float) -> None:
        """The accelerometer's true reading in ``values``, sampled at ``t``: the IMU's mean specific force since the
        last reading, ``R^T ((v - v_last) / (t - t_last) - g)``, ``R`` the IMU's orientation now (module docstring);
        MuJoCo's instantaneous one where no earlier reading is."""
        k = self._imu_at
        vx, vy, vz = values[k + 10 : k + 13].tolist()
        last, self._last_velocity = self._last_velocity, (t, vx, vy, vz)
        if last is None or not t > last[0]:
            return
        rate = 1.0 / (t - last[0])
        gx, gy, gz = self._gravity
        ax, ay, az = (vx - last[1]) * rate - gx, (vy - last[2]) * rate - gy, (vz - last[3]) * rate - gz
        w, x, y, z = values[k : k + 4].tolist()
        # R^T a, with R the rotation of the unit quaternion (w, x, y, z): the columns of R dotted with a.
        values[k + 7 : k + 10] = (
            (1.0 - 2.0 * (y * y + z * z)) * ax + 2.0 * (x * y + w * z) * ay + 2.0 * (x * z - w * y) * az,
            2.0 * (x * y - w * z) * ax + (1.0 - 2.0 * (x * x + z * z)) * ay + 2.0 * (y * z + w * x) * az,
            2.0 * (x * z + w * y) * ax + 2.0 * (y * z - w * x) * ay + (1.0 - 2.0 * (x * x + y * y)) * az,
        )

    def _walk_biases(self, draws: np.ndarray) -> None:
        """The gyro's and accelerometer's biases walk one tick (after this tick's reading used them)."""
        k = self._imu_at
        self._offset[k + 4 : k + 10] += self._walk * draws

    def _tilt(self, values: np.ndarray, roll: float, pitch: float, elapsed: float) -> None:
        """Rotate the IMU's quaternion in ``values`` by the filter's error: ``q_e q``, ``q_e`` the rotation vector
        (white roll and pitch about the world's x and y, yaw drifted about its z for ``elapsed`` seconds)."""
        ex, ey, ez = self._tilt_noise * roll, self._tilt_noise * pitch, self._yaw_rate * elapsed
        angle = math.sqrt(ex * ex + ey * ey + ez * ez)
        if angle == 0.0:
            return
        scale = math.sin(0.5 * angle) / angle
        ew, ex, ey, ez = math.cos(0.5 * angle), ex * scale, ey * scale, ez * scale
        k = self._imu_at
        w, x, y, z = values[k : k + 4].tolist()
        values[k : k + 4] = (
            ew * w - ex * x - ey * y - ez * z,
            ew * x + ex * w + ey * z - ez * y,
            ew * y - ex * z + ey * w + ez * x,
            ew * z + ex * y - ey * x + ez * w,
        )

    def _readings(self, values: np.ndarray, t: float) -> SensorReadings:
        """The readings of one row of the layout (module docstring of :mod:`rtgait.sim.sensor_sites`)."""
        layout = self.layout
        n = layout.joints
        imu = left = right = None
        row = values[3 * n :].tolist()  # Python floats: the tuples are built from them at once
        k = 0
        if layout.imu:
            imu = _new_tuple(ImuReading, (tuple(row[0:4]), tuple(row[4:7]), tuple(row[7:10])))
            k = IMU_SIZE  # the site's velocity, row[10:13], is not a reading
        if layout.feet:
            # MuJoCo's sign: the wrench on the foot from the leg; the reading's: on the leg from the foot.
            w = [-x for x in row[k : k + 12]]
            left = _new_tuple(Wrench, (tuple(w[0:3]), tuple(w[3:6])))
            right = _new_tuple(Wrench, (tuple(w[6:9]), tuple(w[9:12])))
        torques = values[2 * n : 3 * n] if self.joint_torques else None
        return _new_tuple(SensorReadings, (t, values[:n], values[n : 2 * n], torques, imu, left, right))


def applied_damping(
    kd: np.ndarray, velocity: np.ndarray, velocity_end: np.ndarray, force: np.ndarray, lower: np.ndarray,
    upper: np.ndarray,
) -> np.ndarray:  # fmt: skip
    """``kd (dq - dq_end)`` per joint (N m): what the implicit integration of a drive's damping adds to its actuator
    force of the state at joint velocities ``velocity`` over the step that ends at ``velocity_end`` (rad/s), zero for
    a drive whose ``force`` is at its range ``[lower, upper]`` (module docstring)."""
    free = (force > lower) & (force < upper)
    return np.where(free, kd * (velocity - velocity_end), 0.0)
