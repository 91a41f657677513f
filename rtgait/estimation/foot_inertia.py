"""The inertia of the mass below a foot force sensor, from the robot's kinematics and its IMU.

An ankle sensor carries the foot below it: with the foot's mass ``m`` (centred at ``c``) accelerating at ``a_c``, the
ground's force on the foot is the sensor's plus the force that accelerates the foot against gravity,

    f_ground = f_s + m (a_c - g)                                                           (N)

of which :func:`rtgait.estimation.sole_wrenches.sensor_wrench` takes the static part, ``-m g``. The rest, ``m a_c``,
is what the sensor reads as a swinging foot is whipped and as the stiff leg stops a landing one: 100-300 N on Talos's
1.6 kg foot, ringing at 250-500 Hz, several times the 25 N landing force. Here the vertical part, which the load
detection reads. The foot's specific force ``a_c - g`` is the IMU's plus the foot's acceleration relative to the IMU
(both in the world, ``R`` the base's rotation, ``w`` its angular velocity, ``d = c - p_I`` in the base frame from the
joints):

    u = R (w x d + d'),        a_c - g = R f_I + (u_k - u_(k-1)) / dt                     (m/s^2)

the difference of one tick, as the IMU's specific force is the mean of the period that ends at the tick
(:mod:`rtgait.sim.sensors`): both are the period's; the first tick has no difference (taken as nil). Its noise is the
joint velocities' differenced (``sqrt(2) sigma_v / dt`` through the legs' lever arms): :data:`INERTIA_NOISE` on a
still foot. Where a foot stands, or rests lightly for long (a long double support's 13-25 N, between the load
thresholds), that noise is all the removal would add; so what lies within twice it of nil is taken as nil and the
rest is moved towards nil by as much (a soft threshold, ``sign(x) max(|x| - 2 sigma, 0)``): a whipped or ringing
foot's tens to hundreds of newtons pass, less 5 N. mc_rtc and auto_stabilizer remove the mass below their feet's
sensors likewise.
"""

from __future__ import annotations

from rtgait.interface.body_kinematics import BodyKinematics, ForceSensorMount, FrameMotion

__all__ = ["INERTIA_NOISE", "FootInertia"]

INERTIA_NOISE = 2.5
"""Standard deviation (N) of the removed inertia on a foot that stands still: the joint velocities' noise
differenced, measured on Talos at its described sensor noise (fig7's long double supports, 2.45 N with more than
300 N on the foot)."""


class FootInertia:
    """The vertical force that accelerates each foot below its sensor (module docstring).

    Args:
        mounts: the left and right feet's sensor mounts (the mass below each and its centre, sole frame).
        gravity: the gravity's magnitude (m/s^2).
    """

    def __init__(self, mounts: tuple[ForceSensorMount, ForceSensorMount], gravity: float) -> None:
        self.mounts = mounts
        self.gravity = float(gravity)
        self._masses = (float(mounts[0].mass), float(mounts[1].mass))
        self._coms = (mounts[0].com, mounts[1].com)
        self.reset()

    def reset(self) -> None:
        """Forget the last tick's velocities: the next update has no acceleration."""
        self._last: tuple[float, float] | None = None

    def update(
        self, dt: float, up: tuple[float, float, float], w: tuple[float, float, float],
        specific: tuple[float, float, float], kin: BodyKinematics,
    ) -> tuple[float, float]:  # fmt: skip
        """``m a_c,z`` of the left and right feet (N), soft-thresholded at twice its noise (module docstring): the
        ground's vertical force on a foot is the sensor's, static weight removed
        (:func:`~rtgait.estimation.sole_wrenches.sensor_wrench`), plus this.

        Args:
            dt: the tick's length (s); 0 at the first tick.
            up: the world's vertical in the base frame, the third row of ``R`` (yaw does not change it).
            w: the base's angular velocity (rad/s, base frame).
            specific: the IMU's specific force in the base frame (m/s^2).
            kin: this tick's kinematics (base frame).
        """
        ux, uy, uz = up
        wx, wy, wz = w
        vertical = []
        for frame in (kin.left_sole, kin.right_sole, kin.imu):
            # The frame's velocity relative to the base origin, w x p + p' (base frame), its vertical part.
            (px, py, pz), (vx, vy, vz) = frame.position, frame.velocity
            vertical.append(
                ux * (wy * pz - wz * py + vx) + uy * (wz * px - wx * pz + vy) + uz * (wx * py - wy * px + vz)
            )
        acceleration = ux * specific[0] + uy * specific[1] + uz * specific[2] - self.gravity
        return self.from_motion(dt, up, w, acceleration, vertical[0] - vertical[2], vertical[1] - vertical[2],
                                kin.left_sole, kin.right_sole)  # fmt: skip

    def from_motion(
        self, dt: float, up: tuple[float, float, float], w: tuple[float, float, float], acceleration: float,
        left: float, right: float, left_sole: FrameMotion, right_sole: FrameMotion,
    ) -> tuple[float, float]:  # fmt: skip
        """:meth:`update` from what the estimator has already worked out: the IMU's vertical acceleration
        ``acceleration`` (``(R f_I)_z - g``, m/s^2) and the world-vertical velocities ``left`` and ``right`` of the
        sole origins relative to the IMU, ``up . (w x (p_s - p_I) + p_s' - p_I')`` (m/s); the soles' motions (base
        frame) turn the foot's centre about its sole origin."""
        left += _centre_rise(up, w, left_sole, self._coms[0])
        right += _centre_rise(up, w, right_sole, self._coms[1])
        last = self._last
        self._last = (left, right)
        mass_left, mass_right = self._masses
        if last is None or dt <= 0.0:
            force_left, force_right = mass_left * acceleration, mass_right * acceleration
        else:
            force_left = mass_left * (acceleration + (left - last[0]) / dt)
            force_right = mass_right * (acceleration + (right - last[1]) / dt)
        # The soft threshold, sign(x) max(|x| - core, 0), without branches.
        core = _CORE
        force_left = max(force_left - core, 0.0) + min(force_left + core, 0.0)
        force_right = max(force_right - core, 0.0) + min(force_right + core, 0.0)
        return force_left, force_right


_CORE = 2.0 * INERTIA_NOISE


def _centre_rise(
    up: tuple[float, float, float], w: tuple[float, float, float], sole: FrameMotion, com: tuple[float, float, float]
) -> float:
    """The world-vertical velocity (m/s) of a foot's centre ``com`` (sole frame) relative to its sole origin: with
    ``r = R_s c`` (base frame) turning at the sole's world rate ``w + w_s``, ``up . ((w + w_s) x r)``."""
    cx, cy, cz = com
    m0, m1, m2, m3, m4, m5, m6, m7, m8 = sole.rotation
    rx, ry, rz = m0 * cx + m1 * cy + m2 * cz, m3 * cx + m4 * cy + m5 * cz, m6 * cx + m7 * cy + m8 * cz
    ax, ay, az = sole.angular_velocity
    ax, ay, az = ax + w[0], ay + w[1], az + w[2]
    ux, uy, uz = up
    return ux * (ay * rz - az * ry) + uy * (az * rx - ax * rz) + uz * (ax * ry - ay * rx)
