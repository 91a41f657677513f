"""Parameters of the online planner, checked where they enter (ranges in :mod:`rtgait.core.limits`)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import InitVar, dataclass, field
from typing import Literal

from rtgait.core.geometry.footsteps import Side, SoleRect, Timing
from rtgait.core.laws.stepping import StepAdjustment
from rtgait.core.limits import MAX_HORIZON_STEPS, MAX_PHASE_W_T, MAX_STRIDE, check_range
from rtgait.core.lipm.closed_form import GRAVITY, omega
from rtgait.core.lipm.connect import MIN_REST_W_T
from rtgait.core.lipm.sway import cog_sway

ConnectionMode = Literal["real-time", "quasi-real-time", "auto"]
CONNECTION_MODES: tuple[ConnectionMode, ConnectionMode] = ("real-time", "quasi-real-time")
"""The paper's two connection modes (Section 4.1)."""
ALL_CONNECTION_MODES: tuple[ConnectionMode, ...] = (*CONNECTION_MODES, "auto")
"""Every accepted ``connection``: the paper's two and ``"auto"``, which chooses per change
(:mod:`rtgait.core.planner.auto`)."""
MAX_AUTO_MARGIN = 0.5
"""Largest ``auto_margin`` accepted (m): no sole is a metre wide."""
FeedbackMode = Literal["planned", "measured"]
FEEDBACK_MODES: tuple[FeedbackMode, FeedbackMode] = ("planned", "measured")


@dataclass(frozen=True)
class PlannerConfig:
    """Parameters of the online planner.

    Attributes:
        cog_height: constant COG height above the ground ``zc`` (m), within [0.05, 10].
        timing: phase durations (s); every phase must also satisfy ``w * T <= 20`` (see
            :data:`~rtgait.core.limits.MAX_PHASE_W_T`; 5.7 s at the default height).
        step_width: lateral distance between the feet when standing and in straight walking (m).
        step_height: peak swing-foot height (m).
        descent_bend: down a stair, how far the swing foot's path bends toward the other foot at mid-swing (m,
            within [0, step_width / 2]; :func:`~rtgait.core.geometry.swing.swing_pose`): the robot's, for a folded
            swing leg that would otherwise brush the stance leg (0, default: a straight path).
        horizon_steps: steps covered by each plan after its first double support, 1..20.
        connection: ``"real-time"``, ``"quasi-real-time"`` or ``"auto"`` (per change, the latest connection
            predicted to keep the ZMP margin at least ``auto_margin``, else a later step:
            :mod:`rtgait.core.planner.auto`).
        gravity: (m/s^2), within [0.1, 100].
        first_degree: degree of the free ZMP polynomial of the first segment, 4 (default: ZMP position and
            velocity continuous across a replan) or 2 (the paper's minimal variant: ZMP position only).
        first_side: which foot swings first.
        max_step_length: largest forward (or backward) stride a velocity command makes (m).
        max_step_lateral: largest lateral displacement a velocity command makes per pair of steps (m): the step
            toward the motion lands this much wider than the step after it, so ``|vy| <= max_step_lateral / 2T``
            over a step period ``T`` (:meth:`~rtgait.core.walk.walk.Walk.set_velocity`).
        max_step_turn: largest heading change a velocity command makes per pair of steps (rad), half of it per
            step, so ``|wz| <= max_step_turn / 2T``. The three bound one command together: the squares of its
            shares of them add up to at most 1 (an ellipsoid, :mod:`rtgait.core.walk.velocity_command`); a command
            beyond is scaled down onto it, with a warning.
        min_step_width: narrowest stance a sideways walk by command may close to (m), within (0, step_width];
            ``None`` (default): ``step_width``, i.e. the feet only ever open beyond the straight-walking stance.
        history_steps: footprints, strides, plan records and change records kept behind the current step, so an
            endless walk's memory stays flat; ``None`` keeps everything.
        feedback: where each new plan starts: ``"planned"`` (the paper's: from the plan being executed) or
            ``"measured"`` (from the state last given to :meth:`~rtgait.core.planner.online.OnlinePlanner.observe`).
        replan_dcm_error: with ``feedback="measured"``, replan at once
            (:meth:`~rtgait.core.planner.online.OnlinePlanner.replan_now`) when the observed DCM is farther than this
            from the plan's (m); ``None``: only at double-support starts.
        step_adjustment: push recovery by stepping (:mod:`rtgait.core.laws.stepping`); ``None`` (default): off.
        auto_margin: with ``connection="auto"``, the ZMP margin (m, signed) a connection's prediction must reach to
            be taken, within [-0.5, 0.5].
        sole: the sole rectangle (m) of the support polygons the auto connection predicts against; required with
            ``connection="auto"``, unused otherwise.
    """

    cog_height: float = 0.8
    timing: Timing = field(default_factory=lambda: Timing(0.8, 0.2))
    step_width: float = 0.19
    step_height: float = 0.05
    descent_bend: float = 0.0
    horizon_steps: int = 3
    connection: ConnectionMode = "real-time"
    gravity: float = GRAVITY
    first_degree: int = 4
    first_side: Side = "right"
    max_step_length: float = 0.3
    max_step_lateral: float = 0.1
    max_step_turn: float = 0.4
    min_step_width: float | None = None
    history_steps: int | None = 1000
    feedback: FeedbackMode = "planned"
    replan_dcm_error: float | None = None
    step_adjustment: StepAdjustment | None = None
    auto_margin: float = 0.01
    sole: SoleRect | None = None
    com_height: InitVar[float | None] = None
    """``cog_height`` under the name most libraries use (placo, Pinocchio, mc_rtc): ``PlannerConfig(com_height=0.8)``
    sets ``cog_height``; giving both with different values is an error."""

    def __post_init__(self, com_height: float | None) -> None:
        if com_height is not None:
            if self.cog_height != 0.8 and self.cog_height != com_height:
                raise ValueError(f"com_height ({com_height}) and cog_height ({self.cog_height}) disagree: give one")
            object.__setattr__(self, "cog_height", com_height)
        w = omega(self.cog_height, self.gravity)  # validates both ranges
        if not isinstance(self.timing, Timing):
            raise ValueError(f"timing must be a Timing, got {type(self.timing).__name__}")
        for name in ("single_support", "double_support", "start", "end", "settle"):
            duration = getattr(self.timing, name)
            if w * duration > MAX_PHASE_W_T:
                raise ValueError(
                    f"timing {name} must be at most {MAX_PHASE_W_T / w:.3g} s at this COG height and gravity "
                    f"(w T <= {MAX_PHASE_W_T:g}, w = {w:.3g} 1/s), got {duration}"
                )
        if w * self.timing.settle < MIN_REST_W_T:
            raise ValueError(
                f"timing settle must be at least {MIN_REST_W_T / w:.3g} s at this COG height and gravity (w T >= "
                f"{MIN_REST_W_T:g}: shorter, the ZMP would have to leave the feet to bring the COG to rest), "
                f"got {self.timing.settle}"
            )
        if self.connection not in ALL_CONNECTION_MODES:
            raise ValueError(f"connection must be one of {ALL_CONNECTION_MODES}, got {self.connection!r}")
        check_range("auto_margin", self.auto_margin, -MAX_AUTO_MARGIN, MAX_AUTO_MARGIN, "m")
        if self.sole is not None and not isinstance(self.sole, SoleRect):
            raise ValueError(f"sole must be a SoleRect or None, got {type(self.sole).__name__}")
        if self.connection == "auto" and self.sole is None:
            raise ValueError("connection 'auto' needs sole (a SoleRect): it predicts the ZMP margin of each change")
        if self.feedback not in FEEDBACK_MODES:
            raise ValueError(f"feedback must be one of {FEEDBACK_MODES}, got {self.feedback!r}")
        if (
            not isinstance(self.horizon_steps, int)
            or isinstance(self.horizon_steps, bool)
            or not 1 <= self.horizon_steps <= MAX_HORIZON_STEPS
        ):
            raise ValueError(f"horizon_steps must be an integer in 1..{MAX_HORIZON_STEPS}, got {self.horizon_steps!r}")
        if self.first_degree not in (2, 4):
            raise ValueError(f"first_degree must be 2 or 4, got {self.first_degree!r}")
        if self.first_side not in ("left", "right"):
            raise ValueError(f"first_side must be 'left' or 'right', got {self.first_side!r}")
        for name in ("step_width", "max_step_length", "max_step_lateral"):
            value = getattr(self, name)
            if not (math.isfinite(value) and 0.0 < value <= MAX_STRIDE):
                raise ValueError(f"{name} must be within (0, {MAX_STRIDE:g}] m, got {value}")
        if not (math.isfinite(self.max_step_turn) and 0.0 < self.max_step_turn < math.pi / 2):
            raise ValueError(f"max_step_turn must be within (0, pi/2) rad, got {self.max_step_turn}")
        narrowest = self.min_step_width
        if narrowest is not None and not (math.isfinite(narrowest) and 0.0 < narrowest <= self.step_width):
            raise ValueError(
                f"min_step_width must be None or within (0, step_width = {self.step_width:g}] m, got {narrowest}"
            )
        check_range("step_height", self.step_height, 0.0, MAX_STRIDE, "m")
        check_range("descent_bend", self.descent_bend, 0.0, 0.5 * self.step_width, "m")
        if self.replan_dcm_error is not None:
            check_range("replan_dcm_error", self.replan_dcm_error, 1e-4, 1.0, "m")
        if self.step_adjustment is not None and not isinstance(self.step_adjustment, StepAdjustment):
            raise ValueError("step_adjustment must be a StepAdjustment or None")
        history = self.history_steps
        if history is not None and (not isinstance(history, int) or isinstance(history, bool) or history < 8):
            raise ValueError(f"history_steps must be None or an integer >= 8, got {history!r}")

    @property
    def w(self) -> float:
        """Pendulum frequency ``sqrt(g / zc)`` (1/s)."""
        return omega(self.cog_height, self.gravity)


VELOCITY_KEYS = ("max_step_length", "max_step_lateral", "max_step_turn", "min_step_width")
"""The :class:`PlannerConfig` fields that bound the strides of a walk by velocity command, as a robot description's
``[velocity]`` table names them."""
SWAY_KEY = "max_sway"
"""The key of a ``[velocity]`` table (or of one of its ``more_sway`` tables) that says up to which COG sway its
limits hold (:func:`~rtgait.core.lipm.sway.cog_sway`)."""
MORE_SWAY_KEY = "more_sway"
"""The key of the ``[velocity]`` table's list of limits for walks that sway more (``[[velocity.more_sway]]``)."""


@dataclass(frozen=True)
class VelocityLimits:
    """A robot's bounds on the strides of walks by velocity command (a robot description's ``[velocity]`` table):
    each field not ``None`` replaces the :class:`PlannerConfig` field of the same name (m, m, rad, m).

    They are the robot's own: how far its legs reach sideways and how far its feet may turn against each other
    without the soles or legs meeting, and what it walks in physics, so a command within them asks nothing the robot
    cannot step; the planner's defaults (0.3 m, 0.1 m, 0.4 rad, no narrowing) suit no robot in particular.

    What a robot walks depends on the walk's timing through how far its COG sways toward each foot
    (:func:`~rtgait.core.lipm.sway.cog_sway`, a number of the timing and the pendulum alone, below 1): the more it
    sways, the farther the COG is from the other foot while that foot still bears weight. So the limits may be given
    per sway: these hold up to ``max_sway`` (``None``: for every sway), and ``more_sway`` lists the limits of walks
    that sway more, in increasing ``max_sway``, each holding up to its own and the last one for every larger sway too.
    A field a ``more_sway`` entry leaves ``None`` is the one before it (:meth:`from_table` fills them in).
    """

    max_step_length: float | None = None
    max_step_lateral: float | None = None
    max_step_turn: float | None = None
    min_step_width: float | None = None
    max_sway: float | None = None
    more_sway: tuple[VelocityLimits, ...] = ()

    def __post_init__(self) -> None:
        if self.max_sway is not None and not (math.isfinite(self.max_sway) and 0.0 < self.max_sway <= 1.0):
            raise ValueError(f"max_sway must be None or within (0, 1], got {self.max_sway}")
        if not self.more_sway:
            return
        if self.max_sway is None:
            raise ValueError("max_sway is needed with more_sway: up to which sway these limits hold")
        previous = self.max_sway
        for i, entry in enumerate(self.more_sway):
            if not isinstance(entry, VelocityLimits) or entry.more_sway:
                raise ValueError(f"more_sway[{i}] must be a VelocityLimits without more_sway of its own")
            if entry.max_sway is None or entry.max_sway <= previous:
                raise ValueError(
                    f"more_sway[{i}].max_sway must be more than the one before it ({previous:g}), got {entry.max_sway}"
                )
            previous = entry.max_sway

    @classmethod
    def from_table(cls, table: dict, where: str = "velocity") -> VelocityLimits:
        """From a ``[velocity]`` table (keys :data:`VELOCITY_KEYS` and ``max_sway``, all optional, and
        ``more_sway``, a list of tables of the same keys each with its ``max_sway``), each value checked as
        :class:`PlannerConfig` checks it; an error names ``where.key``."""
        base = _limits_from_table(table, where, nested=True)
        entries = table.get(MORE_SWAY_KEY, [])
        if not isinstance(entries, list) or not all(isinstance(entry, dict) for entry in entries):
            raise ValueError(f"{where}.{MORE_SWAY_KEY} must be a list of tables ([[{where}.{MORE_SWAY_KEY}]])")
        more: list[VelocityLimits] = []
        previous = base
        for i, entry in enumerate(entries):
            name = f"{where}.{MORE_SWAY_KEY}[{i}]"
            if SWAY_KEY not in entry:
                raise ValueError(f"{name}: missing key {SWAY_KEY!r} (up to which sway these limits hold)")
            limits = _limits_from_table(entry, name, nested=False)
            # What an entry does not say, it keeps from the one before it.
            filled = {key: getattr(limits, key) if getattr(limits, key) is not None else getattr(previous, key)
                      for key in VELOCITY_KEYS}  # fmt: skip
            previous = cls(**filled, max_sway=limits.max_sway)
            more.append(previous)
        try:
            return dataclasses.replace(base, more_sway=tuple(more))
        except ValueError as error:
            raise ValueError(f"{where}.{error}") from None

    def for_sway(self, sway: float) -> VelocityLimits:
        """The limits of a walk whose COG sways ``sway`` (:func:`~rtgait.core.lipm.sway.cog_sway`): these, or the
        first ``more_sway`` entry that holds up to it, or the last one."""
        if self.max_sway is None or sway <= self.max_sway or not self.more_sway:
            return self
        for entry in self.more_sway:
            if entry.max_sway is not None and sway <= entry.max_sway:
                return entry
        return self.more_sway[-1]

    def apply(self, config: PlannerConfig, where: str = "velocity") -> PlannerConfig:
        """``config`` with these limits, those for its timing's COG sway (:meth:`for_sway`); an error names
        ``where.key`` (e.g. ``min_step_width`` wider than the config's ``step_width``)."""
        limits = self
        if self.more_sway:
            timing = config.timing
            limits = self.for_sway(cog_sway(config.w, timing.single_support, timing.double_support))
        changes = {key: getattr(limits, key) for key in VELOCITY_KEYS if getattr(limits, key) is not None}
        try:
            return dataclasses.replace(config, **changes)
        except ValueError as error:
            raise ValueError(f"{where}.{error}") from None

    def every_table(self) -> tuple[VelocityLimits, ...]:
        """These limits and each ``more_sway`` entry, in increasing sway."""
        return (self, *self.more_sway)


def _limits_from_table(table: dict, where: str, nested: bool) -> VelocityLimits:
    """The four limits and ``max_sway`` of one table (``nested``: it may also hold ``more_sway``, read elsewhere)."""
    known = (*VELOCITY_KEYS, SWAY_KEY, *((MORE_SWAY_KEY,) if nested else ()))
    values: dict[str, float] = {}
    for key, value in table.items():
        if key not in known:
            raise ValueError(f"{where}: unknown key {key!r} (known: {', '.join(known)})")
        if key == MORE_SWAY_KEY:
            continue
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{where}.{key} must be a number, got {value!r}")
        if key == SWAY_KEY:
            if not (math.isfinite(value) and 0.0 < value <= 1.0):
                raise ValueError(
                    f"{where}.{SWAY_KEY} must be within (0, 1] (a share of half the stance), got {value!r}"
                )
        elif key == "min_step_width":  # against the robot's own stance when applied (apply)
            if not (math.isfinite(value) and 0.0 < value <= MAX_STRIDE):
                raise ValueError(f"{where}.min_step_width must be within (0, {MAX_STRIDE:g}] m, got {value!r}")
        else:
            try:
                PlannerConfig(**{key: float(value)})
            except ValueError as error:
                raise ValueError(f"{where}.{error}") from None
        values[key] = float(value)
    return VelocityLimits(**values)
