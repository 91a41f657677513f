"""The landing threshold of feet wrenches estimated from joint torques at a given scale of the sensors' noise.

A swinging foot's vertical force estimated from the legs' torques (:mod:`rtgait.estimation.torque_wrenches`) errs by
noise that is almost all the sensors': on G1's fig8 walked on the truth (the estimator in its shadow, stiff gains,
seed 0) the swinging legs' contact force errs by 0.83 N RMS with noise-free sensors, 5.09 N at the described noise
and 10.06 N at twice it (10.18 N, seed 1): ``sigma(s) = sqrt(sigma_0^2 + (s sigma_1)^2)``, ``sigma_0 << sigma_1``,
linear in the factor ``s`` on every noise of the description. The threshold
:data:`~rtgait.estimation.kinematic_inertial.TORQUE_LANDING_FRACTION` of the weight is five standard deviations at the
described noise; at a larger factor it keeps five standard deviations by scaling with it:

    F_land(s) = TORQUE_LANDING_FRACTION * m g * max(1, s)                                                    (N)

Below the described noise it stays put: what is left then (the model's and the dynamics' error, the impacts' force
after a lift-off) is not noise and does not shrink with it.
"""

from __future__ import annotations

import math

from rtgait.estimation.kinematic_inertial import TORQUE_LANDING_FRACTION

__all__ = ["torque_landing_force"]


def torque_landing_force(weight: float, noise_scale: float) -> float:
    """The landing force (N) of torque-estimated feet wrenches for a robot of ``weight`` (N) whose sensors read with
    ``noise_scale`` times their described noise (module docstring).

    Raises:
        ValueError: a weight that is not > 0 or a noise scale that is not a finite number >= 0.
    """
    if not (math.isfinite(weight) and weight > 0.0):
        raise ValueError(f"the robot's weight must be > 0 N, got {weight}")
    if not (math.isfinite(noise_scale) and noise_scale >= 0.0):
        raise ValueError(f"the noise scale must be a finite number >= 0, got {noise_scale}")
    return TORQUE_LANDING_FRACTION * weight * max(1.0, noise_scale)
