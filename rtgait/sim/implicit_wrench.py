"""The feet's force sensors read with the acceleration the physics step integrates, not the one MuJoCo's sensor uses.

MuJoCo's ``force`` and ``torque`` sensors give the wrench between a site's body and its parent from the recursive
Newton-Euler pass of ``mj_forward``, with the acceleration ``qacc`` of the forward dynamics. The ``implicitfast``
integrator then moves the state with another one: it integrates the servos' damping at the step's end velocity,
``qacc_step = (qvel_end - qvel) / h``. On a stiff leg the two differ by up to hundreds of rad/s^2, enough for a
swinging foot to read as landed (``docs/estimation.md``, "The simulated ankle sensors read the step's acceleration").
A real strain gauge reads the wrench that moves the foot. The wrench changes with the acceleration
linearly, the velocity terms being those of the same state, so for each body ``i`` below the sensor (mass ``m_i``,
world inertia ``I_i`` about its centre of mass ``c_i``, Jacobians ``J_v,i``, ``J_w,i`` there) and
``dqacc = qacc_step - qacc``:

    df = sum_i m_i J_v,i dqacc
    dt = sum_i I_i J_w,i dqacc + (c_i - p) x m_i J_v,i dqacc

about the sensor's site ``p``, added to MuJoCo's reading in the site's frame (MuJoCo's sign: the wrench the parent
exerts on the body). The kinematics, Jacobians and ``qacc`` in ``MjData`` after ``mj_step`` are those of the state the
step started from, the one the sensor read.
"""

from __future__ import annotations

import mujoco
import numpy as np

__all__ = ["ImplicitStepWrench"]


class ImplicitStepWrench:
    """The correction of the force sensors at ``sites`` to the step's acceleration (module docstring).

    Args:
        model: the MuJoCo model.
        sites: the force sensors' sites, each measuring the subtree of its body.
    """

    def __init__(self, model: mujoco.MjModel, sites: tuple[int, ...]) -> None:
        self._model = model
        parents = model.body_parentid
        pairs = []  # (where the sensor's six numbers start, its site, a body below it)
        for k, site in enumerate(sites):
            subtree = [int(model.site_bodyid[site])]
            for body in range(subtree[0] + 1, model.nbody):  # MuJoCo numbers a body after its parent
                if int(parents[body]) in subtree:
                    subtree.append(body)
            pairs += [(6 * k, site, body) for body in subtree]
        self._sites = sites
        self._pairs = tuple(pairs)
        self._mass = [float(model.body_mass[body]) for _, _, body in pairs]
        self._inertia = [model.body_inertia[body].tolist() for _, _, body in pairs]  # about the principal axes
        # Each body's translational then rotational Jacobian at its COM, stacked: one product gives all accelerations.
        self._jacobians = np.zeros((len(pairs), 6, model.nv))
        self._rate = 1.0 / model.opt.timestep
        self.qvel_before = np.zeros(model.nv)
        """The velocities the last physics step started from (rad/s, m/s): set before the step that the sensors'
        reading belongs to (:meth:`keep_velocity`)."""

    def keep_velocity(self, data: mujoco.MjData) -> None:
        """Keep the velocities of the state the coming physics step starts from."""
        self.qvel_before[:] = data.qvel

    def correction(self, data: mujoco.MjData) -> np.ndarray:
        """What to add to MuJoCo's readings of the sensors (force then torque, 6 a site, in the sites' frames, N and
        N m) after the step :meth:`keep_velocity` preceded."""
        model, jacobians = self._model, self._jacobians
        change = data.qvel - self.qvel_before
        change *= self._rate
        change -= data.qacc
        for jacobian, (_, _, body) in zip(jacobians, self._pairs, strict=True):
            mujoco.mj_jacBodyCom(model, data, jacobian[:3], jacobian[3:], body)
        accelerations = (jacobians @ change).tolist()  # each body's COM and angular acceleration changes, world axes
        out = [0.0] * (6 * len(self._sites))
        xipos, ximat, site_xpos, site_xmat = data.xipos, data.ximat, data.site_xpos, data.site_xmat
        for (at, site, body), mass, (ix, iy, iz), (ax, ay, az, wx, wy, wz) in zip(
            self._pairs, self._mass, self._inertia, accelerations, strict=True
        ):
            fx, fy, fz = mass * ax, mass * ay, mass * az
            # I w' = A diag(I) A^T w', A the body's principal axes of inertia (its columns).
            a0, a1, a2, a3, a4, a5, a6, a7, a8 = ximat[body].tolist()
            u0 = ix * (a0 * wx + a3 * wy + a6 * wz)
            u1 = iy * (a1 * wx + a4 * wy + a7 * wz)
            u2 = iz * (a2 * wx + a5 * wy + a8 * wz)
            rx, ry, rz = (xipos[body] - site_xpos[site]).tolist()  # the body's COM from the sensor
            tx = a0 * u0 + a1 * u1 + a2 * u2 + ry * fz - rz * fy
            ty = a3 * u0 + a4 * u1 + a5 * u2 + rz * fx - rx * fz
            tz = a6 * u0 + a7 * u1 + a8 * u2 + rx * fy - ry * fx
            r0, r1, r2, r3, r4, r5, r6, r7, r8 = site_xmat[site].tolist()  # into the sensor's frame: R^T v
            out[at] += r0 * fx + r3 * fy + r6 * fz
            out[at + 1] += r1 * fx + r4 * fy + r7 * fz
            out[at + 2] += r2 * fx + r5 * fy + r8 * fz
            out[at + 3] += r0 * tx + r3 * ty + r6 * tz
            out[at + 4] += r1 * tx + r4 * ty + r7 * tz
            out[at + 5] += r2 * tx + r5 * ty + r8 * tz
        return np.array(out)
