"""Walking scenarios: a robot, a timing, a walk and the footstep changes made while walking.

A scenario is a small TOML file (every key, its unit and its range in ``docs/cli_and_scenarios.md``, "Scenario
files"). The built-in ones (the paper's Section 5 cases and a few more) ship as package data in ``rtgait/scenarios/``
and are loaded by name; any other file is loaded by path. Its parts, in SI units (m, s, rad):

* ``name``, ``description``, ``connection`` (``"real-time"``, ``"quasi-real-time"`` or ``"auto"``, chosen per change,
  with an optional ``auto_margin``);
* ``[robot]``: ``cog_height``, optional ``gravity`` and ``mass`` (the point mass pushes act on in ``rtgait simulate
  --model lipm``), and ``[robot.sole]``: the sole rectangle ``front``, ``back``, ``inner``, ``outer`` around the foot
  frame; optional ``[robot.velocity]``: the robot's stride limits (a robot description's ``[velocity]`` keys);
* ``[timing]``: ``single_support``, ``double_support``, ``dt`` (the rollout's control period), ``horizon_steps``
  (steps covered by each plan), optional ``start``, ``end`` and ``settle`` durations;
* ``[walk]``: ``steps`` forward steps of ``step_length``, ``step_width`` apart, ``step_height`` high, optional
  ``yaw`` per step and ``first_foot``; one more step then brings the feet side by side;
* ``[[walk.change]]``: a new ``length``, ``width`` or ``yaw`` from ``step`` on (or, with ``only = true``, for that
  step alone), decided while walking;
* ``[guide]`` (optional): a path along which a person leads the robot by the hand in ``rtgait simulate``
  (:class:`~rtgait.scenario.guide_path.GuidePath`, :mod:`rtgait.sim.guided`); the walk's footsteps are then ignored
  and ``walk.steps`` is the most steps the robot may take;
* ``[[obstacle]]`` (optional): boxes seen while walking, which the walk steps around (:mod:`rtgait.scenario.obstacles`);
* ``[terrain]`` (optional): the ground the walk's footsteps are placed on (:mod:`rtgait.scenario.terrain_table`);
* ``[walking.<robot>]`` (optional): the COG height and toe release this walk asks of that robot, in place of its
  description's (:mod:`rtgait.scenario.walking_table`);
* ``[control]`` (optional): the controller's settings for this walk (``docs/cli_and_scenarios.md``, "Controller
  settings"), applied over the robot description's.

A file with ``[[footstep]]`` entries instead of ``walk.steps`` is a footstep plan, absolute footholds each with its
own timing if wanted: :func:`load_scenario` hands it to :mod:`rtgait.scenario.footholds`, which returns a
:class:`Scenario` too (``footholds`` set, per-step timings in ``timing.per_step``).

The TOML tables are read into a :class:`Scenario` by :mod:`rtgait.scenario.scenario_file`. Every problem with a file
raises :class:`ScenarioError` with one line naming the offending field. Sizes and physical
quantities are bounded by :mod:`rtgait.core.limits`, checked here so that the message names the TOML field; two
``[[walk.change]]`` entries for the same step are refused.
"""

from __future__ import annotations

import itertools
import math
import re
from dataclasses import dataclass, field

from rtgait.core.analysis.rollout import ScheduledChange
from rtgait.core.geometry.footsteps import (
    Footstep,
    Side,
    SoleRect,
    Stride,
    Timeline,
    Timing,
    place_footsteps,
    standing_feet,
    stride_between,
)
from rtgait.core.geometry.terrain import TerrainKind
from rtgait.core.limits import (
    MAX_COG_HEIGHT,
    MAX_GRAVITY,
    MAX_HORIZON_STEPS,
    MAX_PHASE_DURATION,
    MAX_STEPS,
    MIN_COG_HEIGHT,
    MIN_DT,
    MIN_GRAVITY,
    MIN_PHASE_DURATION,
)
from rtgait.core.obstacle.box import Obstacle
from rtgait.core.planner.config import ALL_CONNECTION_MODES, MAX_AUTO_MARGIN, VelocityLimits
from rtgait.core.planner.online import ConnectionMode, PlannerConfig
from rtgait.scenario.checks import (
    PHASES,
    ScenarioError,
    check_distinct_steps,
    check_phase_lengths,
    check_ticks,
    within,
)
from rtgait.scenario.guide_path import GuidePath
from rtgait.scenario.obstacles import check_seen_within
from rtgait.scenario.terrain_table import TerrainSpec
from rtgait.scenario.tomlfile import SettingsPairs, TomlFiles
from rtgait.scenario.walking_table import RobotWalking

__all__ = [
    "DEFAULT_STEP_HEIGHT",
    "DEFAULT_STEP_WIDTH",
    "MAX_WALK_STEPS",
    "PHASES",
    "GuidePath",
    "Scenario",
    "ScenarioError",
]

_NAME_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*")
# Stride.turn must stay strictly inside +-pi/2; checking yaws with this rule gives the error a TOML field name.
MAX_WALK_STEPS = MAX_STEPS - 1
"""Most forward steps of a scenario: the closing step makes :data:`~rtgait.core.limits.MAX_STEPS`."""
_STEPS_WHY = f"one closing step is added and a walk has at most {MAX_STEPS} steps"
_HORIZON_WHY = "the size and cost of every plan grow with it"
_COG_HEIGHT_BOUNDS = (MIN_COG_HEIGHT, MAX_COG_HEIGHT)
_GRAVITY_BOUNDS = (MIN_GRAVITY, MAX_GRAVITY)
_PHASE_BOUNDS = (MIN_PHASE_DURATION, MAX_PHASE_DURATION)
_MASS_BOUNDS = (1.0, 500.0)  # kg: from a toy biped to the heaviest humanoid built
DEFAULT_STEP_WIDTH = 0.19
"""``walk.step_width`` of a footstep plan that does not give it (m): every built-in scenario's, an adult humanoid's
stance (a robot's own replaces it in ``--robot`` runs). A scenario gives its own: it is the width of every step."""
DEFAULT_STEP_HEIGHT = 0.05
"""``walk.step_height`` of a footstep plan that does not give it (m): every built-in scenario's swing-foot peak
height."""

SCENARIO_FILES = TomlFiles(kind="scenario", folder="scenarios", error=ScenarioError)
"""The scenario TOML files: the built-in ones by name, any other by path; their readers and checks."""
_FILES = SCENARIO_FILES


@dataclass(frozen=True)
class Scenario:
    """Everything needed to roll out one walk.

    Attributes:
        name: short identifier, also the default output folder name.
        description: one line for listings.
        connection: ``"real-time"``, ``"quasi-real-time"`` or ``"auto"`` (:mod:`rtgait.core.planner.auto`).
        cog_height: constant COG height above the ground (m).
        gravity: (m/s^2).
        sole: sole rectangle around the foot frame (m).
        timing: phase durations (s).
        dt: control period at which the walk is sampled (s).
        horizon_steps: steps covered by each plan after its first double support.
        steps: number of forward steps; one closing step (length 0) follows them.
        step_length: forward length of each step (m).
        step_width: lateral distance between the feet (m).
        step_height: peak swing-foot height (m).
        changes: footstep changes, each handed to the planner at its connection mode's deadline.
        yaw: turn of every forward step (rad), positive to the left.
        first_foot: the foot that swings first.
        source: where the scenario came from (``"builtin"`` or a file path); informative only.
        guide: a hand-guided walk's path (``[guide]``), or ``None``.
        mass: the robot's mass (kg, ``[robot] mass``) for pendulum-level simulations, where pushes act on it;
            ``None``: not given (``rtgait simulate --model lipm`` then takes an HRP-2-like 57 kg).
        auto_margin: with ``connection = "auto"``, the ZMP margin (m) a connection must be predicted to keep.
        footholds: a footstep plan's landings ``F[2..steps + 2]`` in the world frame (m, rad), one per step, the
            last one being the closing step (:mod:`rtgait.scenario.footholds`); ``None`` for a walk given by
            ``step_length`` and ``yaw``. Its strides start from the standing feet (``step_width`` apart at the
            origin), so a different ``step_width`` (a robot's) moves the first stride, never a foothold. Per-step
            timings, if any, are in ``timing.per_step``.
        control: the ``[control]`` table, the controller's settings for this walk, as read
            (:data:`~rtgait.scenario.tomlfile.SettingsPairs`): ``rtgait simulate`` applies them over the robot's
            (:mod:`rtgait.control.control_table`, which checks them).
        obstacles: boxes the walk sees while walking and steps around (``[[obstacle]]``,
            :mod:`rtgait.scenario.obstacles`).
        velocity: the robot's stride limits (``[robot.velocity]``), applied over the planner's defaults; ``None``:
            the defaults.
        terrain: the ``[terrain]`` table (:class:`~rtgait.scenario.terrain_table.TerrainSpec`), or ``None``: flat.
        walking: the ``[walking.<robot>]`` tables, what this walk asks of a named robot in place of its description's
            ``[walking]`` values (:mod:`rtgait.scenario.walking_table`); a robot without one walks with its own.
    """

    name: str
    description: str
    connection: ConnectionMode
    cog_height: float
    gravity: float
    sole: SoleRect
    timing: Timing
    dt: float
    horizon_steps: int
    steps: int
    step_length: float
    step_width: float
    step_height: float
    changes: tuple[ScheduledChange, ...] = ()
    yaw: float = 0.0
    first_foot: Side = "right"
    source: str = field(default="", compare=False)
    guide: GuidePath | None = None
    mass: float | None = None
    auto_margin: float = 0.01
    footholds: tuple[Footstep, ...] | None = None
    control: SettingsPairs = ()
    obstacles: tuple[Obstacle, ...] = ()
    velocity: VelocityLimits | None = None
    terrain: TerrainSpec | None = None
    walking: tuple[RobotWalking, ...] = ()

    def __post_init__(self) -> None:
        # The TOML loader already checks every field with its file path; these checks cover scenarios built in
        # code or modified with dataclasses.replace (the CLI's --dt, a robot's COG height and step width). The
        # limits (rtgait.core.limits) are checked here, before any work, so no accepted scenario can exhaust
        # memory or time or leave the range where the closed form is well conditioned.
        if not _NAME_PATTERN.fullmatch(self.name):
            raise ScenarioError(f"name must be letters, digits, '.', '_' or '-' (a folder name), got {self.name!r}")
        if self.connection not in ALL_CONNECTION_MODES:
            raise ScenarioError(f"connection must be one of {', '.join(ALL_CONNECTION_MODES)}, got {self.connection!r}")
        within("auto_margin", self.auto_margin, (-MAX_AUTO_MARGIN, MAX_AUTO_MARGIN), "m")
        if self.connection == "auto" and not self.timing.uniform:
            raise ScenarioError('connection = "auto" needs one timing for every step: per-step timings are unsupported')
        within("cog_height", self.cog_height, _COG_HEIGHT_BOUNDS, "m")
        within("gravity", self.gravity, _GRAVITY_BOUNDS, "m/s^2")
        if self.mass is not None:
            within("mass", self.mass, _MASS_BOUNDS, "kg")
        self._check_period()
        _FILES.count(self.steps, "steps", high=MAX_WALK_STEPS, why=_STEPS_WHY)
        _FILES.count(self.horizon_steps, "horizon_steps", high=MAX_HORIZON_STEPS, why=_HORIZON_WHY)
        check_phase_lengths(self.timing, self.cog_height, self.gravity)
        check_ticks(self.duration, self.dt)
        for index, change in enumerate(self.changes):
            if not 1 <= change.step <= self.steps:
                raise ScenarioError(
                    f"walk.change[{index}].step must be a step of the walk (1..{self.steps}), got {change.step}"
                )
        check_distinct_steps([change.step for change in self.changes], "walk.change")
        if not (isinstance(self.control, tuple) and all(isinstance(p, tuple) and len(p) == 2 for p in self.control)):
            raise ScenarioError(f"control must be a tuple of (key, value) pairs, got {self.control!r}")
        check_seen_within(self.obstacles, self.duration)
        if self.footholds is not None:
            if len(self.footholds) != self.steps + 1:
                raise ScenarioError(
                    f"footholds must hold steps + 1 = {self.steps + 1} landings, got {len(self.footholds)}"
                )
            if self.changes:
                raise ScenarioError("a footstep plan has no walk.change entries: edit the footholds instead")
            if self.footholds[0].side != self.first_foot:
                raise ScenarioError(f"the first footstep must be the first foot ({self.first_foot})")
        if self.terrain is not None:
            self.nominal_footprints()  # places the walk on the terrain: a step it cannot take is refused now

    def _check_period(self) -> None:
        """``dt`` is a number within [MIN_DT, the shortest phase]."""
        if not (isinstance(self.dt, (int, float)) and math.isfinite(self.dt) and self.dt > 0.0):
            raise ScenarioError(f"dt must be a number > 0 s, got {self.dt}")
        if self.dt < MIN_DT:
            raise ScenarioError(f"dt must be at least {MIN_DT:g} s, got {self.dt}")
        shortest = self.timing.shortest_phase
        if self.dt > shortest:
            # A period longer than a phase would skip whole phases (and their replans) between two samples.
            raise ScenarioError(f"dt must not exceed the shortest phase ({shortest} s), got {self.dt}")

    @property
    def placed_on(self) -> TerrainKind | None:
        """The terrain the walk's footholds are placed on, for what the controller does to them (step adjustment's
        moved landings); ``None`` on the flat floor, or when the plan walks its own footholds and the terrain is the
        truth it does not know (``place_footsteps = false``)."""
        spec = self.terrain
        if spec is None or not spec.place_footsteps or spec.terrain.kind == "flat":
            return None
        return spec.terrain

    def planner_config(self) -> PlannerConfig:
        """The online planner's parameters for this scenario (with its ``[robot.velocity]`` limits, if any)."""
        config = PlannerConfig(
            cog_height=self.cog_height,
            timing=self.timing,
            step_width=self.step_width,
            step_height=self.step_height,
            horizon_steps=self.horizon_steps,
            connection=self.connection,
            gravity=self.gravity,
            first_side=self.first_foot,
            # The auto connection predicts margins against the sole; the other modes do not need it.
            auto_margin=self.auto_margin,
            sole=self.sole if self.connection == "auto" else None,
        )
        if self.velocity is None:
            return config
        try:
            return self.velocity.apply(config, "robot.velocity")
        except ValueError as error:
            raise ScenarioError(str(error)) from None

    def strides(self) -> list[Stride]:
        """Strides of the walk as planned before any change: ``steps`` forward ones, then a closing one (of a
        footstep plan: from each foothold to the next, the standing feet first); on a terrain, from each placed
        foothold to the next (their height changes and surfaces included)."""
        if self.terrain is not None and self.terrain.place_footsteps:
            return [stride_between(a, b) for a, b in itertools.pairwise(self.nominal_footprints()[1:])]
        return self._plan_strides()

    def _plan_strides(self) -> list[Stride]:
        if self.footholds is not None:
            chain = [*standing_feet(self.step_width, self.first_foot), *self.footholds]
            return [stride_between(a, b) for a, b in itertools.pairwise(chain[1:])]
        forward = Stride(self.step_length, self.step_width, self.yaw)
        # The closing step lands beside the last footprint so the walk ends standing with parallel feet.
        return [forward] * self.steps + [Stride(0.0, self.step_width, 0.0)]

    def nominal_footprints(self) -> list[Footstep]:
        """Footprints ``F[0..steps+1]`` the walk would have without any change (m, rad), on the terrain if any."""
        if self.footholds is not None:
            prints = [*standing_feet(self.step_width, self.first_foot), *self.footholds]
        else:
            prints = place_footsteps(standing_feet(self.step_width, self.first_foot), self._plan_strides())
        if self.terrain is not None:
            prints = self.terrain.place(prints, self.sole, PlannerConfig.max_step_length, self.step_height)
        return prints

    @property
    def duration(self) -> float:
        """Time from the start until the COG has come to rest (s)."""
        t = self.timing
        # steps + 1 steps in all (the closing one), each but the last followed by a double support.
        n = self.steps + 1
        if t.per_step:
            return Timeline(t, n, t.per_step).end_time
        return t.start + n * t.single_support + (n - 1) * t.double_support + t.end + t.settle


# ----- finding scenarios ----------------------------------------------------------------------------------------
