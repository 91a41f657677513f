"""Sole levelling: the tilt each foot's sole shows while it stands flat, learnt and given back to its ankle.

A robot's leg kinematics are off by its joints' calibration errors: an encoder that reads ``q + o`` makes the leg
that the IK commands to ``q_ref`` stand at ``q_ref - o``, so a sole the model has level is tilted by ``-J o`` (``J``:
the sole's rotation per joint angle; the pitch joints of a leg are parallel, so its sole pitch error is the sum of
their offsets, its roll error that of the hip and ankle roll offsets; 0.5 degrees each give up to 1.5 degrees). A
swing foot then lands on an edge of its sole, and a stance foot presses one edge under a stiff servo: on a narrow
sole (G1's is 6 cm wide) that is where the centre of pressure goes.

The estimator sees the same error from the other side. A sole standing flat on level ground is level; the estimate
of its orientation, the IMU's base attitude composed with the leg's kinematics at the encoders' readings, shows it
tilted by ``delta = J o`` (roll and pitch, rad). Commanding each sole at ``delta`` in the model's terms puts the real
one level. Per foot and axis, while the foot is *flat and loaded*, a first-order low-pass over the stance time:

    delta' = (theta_measured - delta) / T_s                                    (1)

with ``theta_measured`` the estimate's sole roll or pitch and ``T_s`` the learning time constant (s). Elsewhere
(``delta`` held) the foot is in the air, lightly loaded (its sole need not lie flat), or its centre of pressure is
within ``edge_margin`` of the sole's edge (it may be rolling onto that edge). ``delta`` is clamped to ``max_tilt``:
a calibration error, not a slope. The same offline, whole-body, is a geometric calibration with the sole on a plane
(Nguyen et al., "Humanoid robot whole-body geometric calibration with embedded sensors and a single plane", arXiv
2507.16369); here only the sole's two tilts, online, which is what landing flat needs.

The sole is then commanded at ``delta``; a foot in the air is also steered to read ``delta``: its command ``u``
moves as

    u' = (delta - theta_measured) / T_w,        |u - delta| <= max_tilt                            (2)

(``T_w`` = ``swing_time_constant``), which takes out what tilts a swinging sole besides its own leg's error: the
stance leg's error and its compliance under the load roll the whole body, and the swing foot with it (on G1, by
0.3 degrees without any model error). While a foot stands flat, ``u`` returns to ``delta`` over ``T_s``; when it is
loaded but not flat (landing, rolling onto an edge) ``u`` holds, and the ankle damping has the foot.

What it cannot tell apart: a ground that is not level (taken for a calibration error of the foot that stood on it,
up to ``max_tilt``) and an error of the IMU's roll and pitch (seen by both soles alike). Both are small on the flat
floors walked here; the foot force control's ankle damping (:mod:`rtgait.control.foot_control`) acts on top of it.
On a walk with sloped footholds or toe-offs the walking stack turns it off (``Controller.off_level_ground``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING

from rtgait.core.geometry.footsteps import SoleRect

if TYPE_CHECKING:
    from rtgait.estimation.state import FootState

__all__ = ["SoleLevel", "SoleLevelSettings"]


@dataclass(frozen=True)
class SoleLevelSettings:
    """Settings of :class:`SoleLevel` (module docstring).

    Attributes:
        time_constant: ``T_s`` of eq. (1), s, in (0, 1e4]: how long a foot stands flat to learn its tilt.
        min_load: least share of the robot's weight a foot carries for its tilt to be learnt, in [0, 1].
        edge_margin: least distance of the foot's centre of pressure from its sole's edges (m), in [0, 0.1].
        max_tilt: largest learnt tilt on each axis, and largest swing correction about it (rad), in [0, 0.1].
        swing_time_constant: ``T_w`` of eq. (2) (s), in [0, 1e4]; 0: a foot in the air holds its command.
    """

    time_constant: float = 0.5
    min_load: float = 0.3
    edge_margin: float = 0.01
    max_tilt: float = math.radians(3.0)
    swing_time_constant: float = 0.05

    def __post_init__(self) -> None:
        ranges = {"time_constant": (0.0, 1e4), "min_load": (0.0, 1.0), "edge_margin": (0.0, 0.1),
                  "max_tilt": (0.0, 0.1), "swing_time_constant": (0.0, 1e4)}  # fmt: skip
        for field in fields(self):
            low, high = ranges[field.name]
            value = getattr(self, field.name)
            number = isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)
            low_ok = number and (value > low if field.name == "time_constant" else value >= low)
            if not (low_ok and value <= high):
                raise ValueError(f"SoleLevelSettings.{field.name} must be within [{low:g}, {high:g}], got {value!r}")
            object.__setattr__(self, field.name, float(value))


class SoleLevel:
    """The learnt sole tilts of both feet (eq. (1)) and the commands of eq. (2); :attr:`command` is what to add to
    their commanded roll and pitch.

    Args:
        sole: the sole rectangle (m), for the centre of pressure's edge margin.
        weight: the robot's weight (N), for the least load.
        dt: the control period (s).
        settings: :class:`SoleLevelSettings`.
    """

    def __init__(self, sole: SoleRect, weight: float, dt: float, settings: SoleLevelSettings | None = None) -> None:
        if not (math.isfinite(weight) and weight > 0.0):
            raise ValueError(f"weight must be > 0 N, got {weight}")
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f"dt must be a period > 0 s, got {dt}")
        self.settings = s = settings or SoleLevelSettings()
        self._gain = -math.expm1(-dt / s.time_constant)
        self._swing_gain = 0.0 if s.swing_time_constant == 0.0 else -math.expm1(-dt / s.swing_time_constant)
        self._min_force = s.min_load * weight
        m = s.edge_margin
        # The inside of the sole by the margin, in the sole frame (x forward; y to the left, `inner` toward the
        # other foot): empty along an axis when the margin exceeds the sole's half-size (then nothing is learnt).
        self._x = (-sole.back + m, sole.front - m)
        self._y_left = (-sole.inner + m, sole.outer - m)
        self._y_right = (-sole.outer + m, sole.inner - m)
        self.reset()

    def reset(self) -> None:
        """Forget the learnt tilts."""
        self._tilts = [0.0, 0.0, 0.0, 0.0]  # left roll, left pitch, right roll, right pitch (rad)
        self._command = [0.0, 0.0, 0.0, 0.0]  # the same order

    def restart_command(self) -> None:
        """Start the command from zero (the plan's soles) again, the learnt tilts kept: after a level switch that
        did not apply it."""
        self._command = [0.0, 0.0, 0.0, 0.0]

    @property
    def tilts(self) -> tuple[float, float, float, float]:
        """The learnt ``(left roll, left pitch, right roll, right pitch)`` (rad)."""
        lr, lp, rr, rp = self._tilts
        return lr, lp, rr, rp

    @property
    def command(self) -> tuple[float, float, float, float]:
        """The tilts to add to the soles' commanded roll and pitch (rad), same order as :attr:`tilts`."""
        lr, lp, rr, rp = self._command
        return lr, lp, rr, rp

    def update(self, left: FootState, right: FootState, support: str) -> tuple[float, float, float, float]:
        """One tick: eq. (1) for each foot meant to carry load (``support``: ``"double"``, ``"left"``,
        ``"right"``) that stands flat, eq. (2) for each foot in the air; returns :attr:`command`."""
        for index, foot, y_range, carries in ((0, left, self._y_left, support != "right"),
                                              (2, right, self._y_right, support != "left")):  # fmt: skip
            flat = carries and self._learn(index, foot, y_range)
            command, tilts = self._command, self._tilts
            if flat:  # on the ground: the learnt tilt
                for k in (index, index + 1):
                    command[k] += self._gain * (tilts[k] - command[k])
            elif not foot.loaded and self._swing_gain > 0.0 and math.isfinite(foot.roll + foot.pitch):
                # In the air: steer the sole to read its learnt tilt, i.e. to be level.
                limit = self.settings.max_tilt
                for k, measured in ((index, foot.roll), (index + 1, foot.pitch)):
                    value = command[k] + self._swing_gain * (tilts[k] - measured)
                    low, high = tilts[k] - limit, tilts[k] + limit
                    command[k] = low if value < low else (high if value > high else value)
        return self.command

    def _learn(self, index: int, foot: FootState, y_range: tuple[float, float]) -> bool:
        cx, cy = foot.cop_local
        x_low, x_high = self._x
        flat = (
            foot.loaded
            and foot.normal_force >= self._min_force
            and x_low <= cx <= x_high  # False for a NaN CoP
            and y_range[0] <= cy <= y_range[1]
        )
        if not flat or not (math.isfinite(foot.roll) and math.isfinite(foot.pitch)):
            return False
        limit = self.settings.max_tilt
        tilts, gain = self._tilts, self._gain
        for k, measured in ((index, foot.roll), (index + 1, foot.pitch)):
            value = tilts[k] + gain * (measured - tilts[k])
            tilts[k] = -limit if value < -limit else (limit if value > limit else value)
        return True
