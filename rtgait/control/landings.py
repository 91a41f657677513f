"""The feet's landings in the MuJoCo loop: what a landing does to the plan and to its foot's target
(:class:`FootLandings`, owned and called every tick by :class:`~rtgait.control.controller.WalkingController`).

Landings come detected by the measurer (:class:`~rtgait.estimation.state.Landing`: side, measured sole pose). Each is
logged with its kind; in the ``"adaptive"`` level it also acts. Settings (s, m, m/s) are those of
:class:`~rtgait.control.settings.ControllerOptions`.

**Classification** of a landing of foot ``i`` at ``t`` (s), the plan's phase ``q`` starting at ``t_q``, lasting ``T_q``:

* *re-landing*: the foot's last swing already ended on the ground, or the plan has it standing and ``q`` is not the
  phase right after its swing (a bounce, or a standing foot unloaded and loaded again);
* a foot *skimming* over ground it met short of its foothold (below): its landings wait for the swing's end;
* the plan has the foot swinging: *on time* when ``t_q + T_q - t <= on_time_window`` (the swing's height profile ends
  flat, so a stance side that gives 2 mm makes every landing that early), *early* when
  ``t - t_q >= early_touchdown_fraction T_q``, else *ignored* (a scuff);
* the swing is over: *late* when the foot was in the air at the swing's end and ``late_grace`` (the detection lag)
  has passed since, else on time.

**Re-anchoring** (``"adaptive"``): every landing but an ignored one is reported with its measured pose
(:meth:`~rtgait.core.planner.online.OnlinePlanner.touchdown`: re-anchoring and an immediate replan, after which the
tick's sample is taken again); a re-landing only when it moved ``relanding_tolerance`` (heading: twice that, in rad)
from where the foot was last anchored. A refused touch-down is logged (``"touchdown-refused"``); the plan stays.
Off the flat floor the controller hands the landings over in the feet's frame (:mod:`rtgait.control.foot_frame`):
measured from the standing foot's target, so that a re-anchored foot stays where it touched.

**Heights.** Each foot's target is the plan's ``(x, y, z_plan, yaw)`` with a height offset ``z`` (m) on top:

* a new swing sheds the offset its foot stood at: ``z(t) = z_0 (1 - s)``, ``s = (t - t_lift) / T_swing``;
* an *early* landing holds the foot where it landed, ``(x_l, y_l, yaw_l)``, until the plan's double support, its
  target going on down with the plan to a floor, ``max(z_plan + z, z_floor)``, ``z_floor = z_plan(t_l) + z -
  late_descent_limit`` (on higher ground the foot must not push the robot up); at the hold's end ``z <- max(z,
  z_floor - z_foothold)`` (the plan stands at the foothold's height then); meanwhile the polygon and the ZMP split
  take both feet;
* an *early* or *on time* landing of a swinging foot farther than :data:`SHORT_LANDING` from the swing's planned
  foothold, its measured sole level (:data:`SKIM_TILT`) and between :data:`SKIM_MIN_HEIGHT` and :data:`SKIM_HEIGHT`
  above it, met ground higher than the plan before it was over its foothold (an unseen step: the sole on the step's
  edge, its heel over the lower floor). It is not held or re-anchored there: the target stops descending at the
  measured height it touched, ``z_touch``,
  ``z = max(z_plan + z, z_touch + c min(1, d / SHORT_LANDING))`` (``d``: the plan's distance to the foothold,
  ``c``: :data:`SKIM_CLEARANCE`), and goes on with the plan's swing to the foothold, where it stands at that
  height (kept as the offset at the swing's end); the plan keeps its single support, and no step adjustment moves
  the landing while it skims (:attr:`FootLandings.skimming`);
* a *late* foot's target descends from where it stood, ``z = z_0 - D(t - t_late)``, to ``-late_descent_limit`` while
  the other foot carries the robot (auto_stabilizer ``FootStepGenerator.h``: ``touchVel`` 0.3 m/s, ``goalOffset``
  -0.02 m; the plan is not delayed). ``D`` is ``late_descent_speed`` times the time from the first tick (default),
  or, with ``late_descent_acceleration`` > 0 (:mod:`rtgait.control.late_descent`), leaves rest as the swing ends,
  reaches ``late_descent_speed`` along a quintic blend at that peak acceleration and comes to rest at the limit the
  same way: started at full speed in one tick, the step of the target's velocity makes the swing leg ring and its
  force reading a landing with the sole millimetres up. Once landed it stands at the ground's
  measured depth under its foothold,
  ``z_g = min(0, max(-late_descent_limit, d))``, reached linearly over the single support it carries next, ``z =
  z_land + (z_g - z_land) s``, ``s = (t - t_l) / (t_end - t_l)``: kept as deep as the target went, it would extend
  the stance leg, lift the body and make the next landing later still. The depth is measured against the other
  foot, both soles in the estimator's frame: ``r = (z_l - z_o) - (z_f - z_o,plan)``, ``z_l`` and ``z_o`` the
  measured heights of the landing sole and the other one, ``z_f`` and ``z_o,plan`` their footholds' heights, is how
  much lower than the plan the landing sole stands relative to the other, and ``d = z_o,offset + r`` when ``|r| >
  ground_tolerance``, else ``d = z_o,offset``: the other foot stands at its ground's depth, its target's offset.
  Neither the estimator's own height nor the relative one alone is the depth: the first drifts (69 mm down over the
  0.9 m of ``stairs-up``, about 11 mm a tread; down a ramp it is the foothold's own height, and every stance target
  sank by up to ``late_descent_limit`` and the stance leg, pushed into the ramp, lifted the body: Talos fell down
  ``slope-down``), and the second carries the legs' calibration error, a few millimetres a landing, which added up
  landing after landing sank every stance target (17 mm over a minute of Talos walking backward at its own gains
  with a model error). Within the tolerance the ground is taken for the other foot's: a real change of level
  (an unseen step down) is centimetres.

**Blends.** A re-anchoring moves a landed foot's target by the servo lag, and an early landing's hold starts and
ends with a jump; with ``anchor_blend`` > 0 the IK's target goes there from its old pose and rate along the planner's
retargeted-swing quintic (:mod:`rtgait.control.target_blend`). The planner, the support polygon and the ZMP split
have the foot where it was measured at once: only :meth:`FootLandings.ik_targets` blends.

The heights and targets are :class:`~rtgait.control.foot_targets.FootTargets`' (a mixin of :class:`FootLandings`).
Python floats and lists of two (left, right) only: the per-tick work is a few comparisons unless a foot lands.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from rtgait.control.foot_targets import SHORT_LANDING, FootTargets
from rtgait.control.settings import ControlEvent
from rtgait.control.target_blend import FootBlend, Pose

if TYPE_CHECKING:
    from rtgait.control.settings import ControllerOptions
    from rtgait.core.geometry.footsteps import Side
    from rtgait.core.planner.online import OnlinePlanner
    from rtgait.core.planner.sample import SampleValues
    from rtgait.estimation.state import Landing, Measurement

__all__ = ["SKIM_HEIGHT", "SKIM_MIN_HEIGHT", "SKIM_TILT", "FootLandings"]

_SIDES: tuple[Side, Side] = ("left", "right")

SKIM_HEIGHT = 0.05
"""Highest ground (m) above the swing's foothold taken as met short of it: an unseen step (up to 3 cm), with
the swing's tracking error; a touch higher than that is not ground the sole can skim to its foothold."""

SKIM_MIN_HEIGHT = 0.01
"""Least height (m) of the measured sole above the swing's foothold for ground met short of it: the planned floor is
met within a millimetre of its height (the estimator's landing heights on flat ground), as when a push brings a foot
down early, and that foot must stand where it landed."""

SKIM_TILT = 0.05
"""Largest tilt (rad) of a sole, as measured at the touch, that met ground short of its foothold: flat on the top of
a step. A sole touching with an edge (a foot brought down early by a push) has its sole point above the ground."""


class FootLandings(FootTargets):
    """The landing states of both feet and the targets they give (module docstring).

    Values in, values out: :meth:`update` takes a tick's planner sample and measurement and returns the sample
    (taken again when a touch-down replanned), the feet's targets before foot force control and the support the
    controller acts on; :meth:`ik_targets` gives the IK's feet targets with the blends.

    Args:
        planner: the controller's online planner (re-anchored on landings in ``"adaptive"``).
        options: the landing settings (:class:`~rtgait.control.settings.ControllerOptions`).
        dt: control period (s).
        adaptive: whether landings act on the plan and the feet (the ``"adaptive"`` level) or are only logged.
    """

    def __init__(self, planner: OnlinePlanner, options: ControllerOptions, dt: float, *, adaptive: bool) -> None:
        self.planner, self.options, self.dt = planner, options, dt
        self.adaptive = adaptive
        """Whether landings act (``"adaptive"``); set through :meth:`set_adaptive`."""
        self.reset()

    def reset(self) -> None:
        """Forget the feet's landing states (a new start)."""
        self._phase = -1  # the plan's phase at the last tick
        # Early touch-down: (x, y, yaw) where it landed, and the least height of its target (m).
        self._hold: list[tuple[float, float, float, float] | None] = [None, None]
        # Early touch-down short of the foothold: the least height of its target (m) while it follows the plan.
        # (height it touched, its foothold's height, x, y) (m).
        self._skim: list[tuple[float, float, float, float] | None] = [None, None]
        self._late = [False, False]  # the swing ended in the air ...
        self._late_from = [math.inf, math.inf]  # ... and from when (s) it counts as late
        # A late foot's descent under way: (its target's height when it began (m), the tick before its first (s)).
        self._descent: list[tuple[float, float] | None] = [None, None]
        self._landed = [True, True]  # whether the foot's last swing ended on the ground
        self._anchor: list[tuple[float, float, float] | None] = [None, None]  # the last re-anchored pose per foot
        self._swing_phase = [-2, -2]  # phase of each foot's last swing
        self._z = [0.0, 0.0]  # height of each foot's target above the plan (m): landing heights, late descent
        self._blend: list[tuple[float, float, float] | None] = [None, None]  # (height, swing start, duration)
        # A late foot that landed: its target's height returns from where it landed to the measured ground's, over
        # its stance's single support: (height at the landing, ground height, from, until) (m, m, s, s).
        self._ground: list[tuple[float, float, float, float] | None] = [None, None]
        # A re-anchored or held foot's IK target is blended to where the foot is to stand (rtgait.control.target_blend).
        self._blends = (FootBlend("left"), FootBlend("right"))
        # The pose (x, y, yaw) a landing of this tick sends the foot to, when its target is to be blended there.
        self._moved: list[tuple[float, float, float] | None] = [None, None]
        self._last_ik: tuple[Pose, Pose] | None = None  # the IK's feet targets of the last tick

    def set_adaptive(self, adaptive: bool) -> None:
        """Landings act (``True``, the ``"adaptive"`` level) or are only logged; out of it a late foot's descent
        stops (the height it reached is shed over its next swing, as after any landing). Holds, heights and blends
        under way are kept."""
        self.adaptive = adaptive
        if not adaptive:
            self._late = [False, False]
            self._descent = [None, None]

    # ----- the tick ------------------------------------------------------------------------------------------------
    def update(
        self, t: float, m: Measurement, values: SampleValues, support: str, q: int, events: list[ControlEvent]
    ) -> tuple[SampleValues, str, int, Pose, Pose, str]:
        """This tick's landing bookkeeping at ``t`` (s) for the planner's sample ``values`` in phase ``q`` of
        support ``support``: a new phase (holds end, swings start, late feet), the height offsets, and the landings
        of ``m`` (logged to ``events``; re-anchored in ``"adaptive"``).

        Returns:
            ``(values, support, q, left, right, acting)``: the sample, taken again after a touch-down that
            replanned; both feet's targets ``(x, y, z, yaw)`` (m, rad) before foot force control; and the support
            the controller acts on: the plan's, both feet while a foot that landed early is held, the other foot
            while one is late.
        """
        if q != self._phase:
            held = (self._hold[0] is not None, self._hold[1] is not None)
            before = self.targets(values) if held[0] or held[1] else None
            self._enter_phase(q, support, m)  # ends the holds of early landings
            if before is not None:
                after = self.targets(values)
                goals = [(a[0], a[1], a[3]) if h else None for a, h in zip(after, held, strict=True)]
                self._start_blends(t, before, after, goals)
        self._update_heights(t)
        if m.landings:
            before = self.targets(values)
            for landing in m.landings:
                if self._landing(t, landing, m, values, support, q, events) and self.adaptive:
                    values, support, q = self.planner.sample_values(t)  # the touch-down replanned
            moved, self._moved = self._moved, [None, None]
            if moved[0] is not None or moved[1] is not None:
                self._start_blends(t, before, self.targets(values), moved)
        left, right = self._foot_target(0, values.left_foot), self._foot_target(1, values.right_foot)
        # The feet the controller acts on (inline: every tick): the plan's, both after an early touch-down, the
        # other while one is late.
        acting = support
        if support in _SIDES:
            if self._hold[1 if support == "left" else 0] is not None:
                acting = "double"
        else:
            late_left = self._late[0] and t >= self._late_from[0]
            late_right = self._late[1] and t >= self._late_from[1]
            if late_left != late_right:
                acting = "right" if late_left else "left"
        return values, support, q, left, right, acting

    def ik_targets(self, t: float, left: Pose, right: Pose) -> tuple[Pose, Pose]:
        """The IK's feet targets at ``t`` (s) for the controller's final ``left`` and ``right`` (force control
        included): blended where a blend is under way (:mod:`rtgait.control.target_blend`). Call once per tick, last:
        the next blends start from these targets and their rate."""
        blends = self._blends
        if blends[0].active:
            left = blends[0].apply(t, left)
        if blends[1].active:
            right = blends[1].apply(t, right)
        self._last_ik = (left, right)
        return left, right

    @property
    def last_ik_targets(self) -> tuple[Pose, Pose] | None:
        """The IK's feet targets ``(x, y, z, yaw)`` of the last tick (:meth:`ik_targets`); ``None`` before the first."""
        return self._last_ik

    # ----- phases and landings -------------------------------------------------------------------------------------
    def _enter_phase(self, q: int, support: str, m: Measurement) -> None:
        """Bookkeeping when the plan enters phase ``q``: a swing that ended in the air is late; a new swing blends
        its foot's landing height out and forgets the last landing."""
        previous = self._phase
        self._phase = q
        for i in (0, 1):
            hold = self._hold[i]
            if hold is not None:  # an early touch-down holds until the swing's end (the plan at its foothold there)
                self._z[i], self._hold[i] = max(self._z[i], hold[3] - self._foothold_z(i)), None
            skim = self._skim[i]
            if skim is not None:  # ground met short of the foothold: it stands at the height it touched
                self._z[i], self._skim[i] = max(self._z[i], skim[0] - skim[1]), None
            if self._swing_phase[i] != previous or previous < 0:
                continue
            if self._blend[i] is not None:  # the swing is over: so is the blend of its foot's height
                self._blend[i], self._z[i] = None, 0.0
            if not self._landed[i]:
                loaded = (m.left, m.right)[i].loaded
                self._late[i] = self.adaptive and not loaded
                self._descent[i] = None
                self._late_from[i] = self.planner.phase_start(q) + self.options.late_grace
                self._landed[i] = loaded
        if support in _SIDES:  # a single support: the other foot lifts off
            i = 1 if support == "left" else 0
            self._swing_phase[i] = q
            self._landed[i] = self._late[i] = False
            self._descent[i] = None
            self._ground[i] = None
            planner = self.planner
            self._blend[i] = (self._z[i], planner.phase_start(q), planner.timeline.duration(q))

    def _landing(
        self,
        t: float,
        landing: Landing,
        m: Measurement,
        values: SampleValues,
        support: str,
        q: int,
        events: list[ControlEvent],
    ) -> bool:
        """Classify a landing (measured in ``m``) and, in ``"adaptive"``, act on it; returns whether the planner
        replanned."""
        i = 0 if landing.side == "left" else 1
        planner = self.planner
        swinging = support in _SIDES and _SIDES[i] != support  # the plan has this foot swinging
        if self._skim[i] is not None and swinging:
            kind = "skimming"  # on its way over ground it met short of its foothold: lands at the swing's end
        elif self._landed[i] or not (swinging or q == self._swing_phase[i] + 1):
            kind = "re-landing"  # it bounced, or a standing foot was unloaded and loaded again
        elif swinging:
            start, duration = planner.phase_start(q), planner.timeline.duration(q)
            if start + duration - t <= self.options.on_time_window:
                kind = "on time"  # the foot follows the plan down: nothing to switch
            elif t - start >= self.options.early_touchdown_fraction * duration:
                kind = "early"
            else:
                kind = "ignored"
        else:
            kind = "late" if self._late[i] and t >= self._late_from[i] else "on time"
        events.append(ControlEvent(t, "landing", landing.side, kind, landing.x, landing.y))
        if kind in ("ignored", "skimming") or not self.adaptive:
            return False
        if kind in ("early", "on time") and swinging and (z_touch := self._short_of_foothold(landing, values, q, i)):
            # Ground higher than the plan met before the foothold: stop descending there, go on to the foothold.
            self._blend[i] = None
            self._skim[i] = z_touch
            text = f"{z_touch[0] - z_touch[1]:+.3f} m above the foothold"
            events.append(ControlEvent(t, "touchdown-skimmed", landing.side, text, landing.x, landing.y))
            return False
        anchor = self._anchor[i]
        if kind == "re-landing" and anchor is not None:
            tolerance = self.options.relanding_tolerance
            moved = math.hypot(landing.x - anchor[0], landing.y - anchor[1])
            if moved < tolerance and abs(math.remainder(landing.yaw - anchor[2], math.tau)) < 2.0 * tolerance:
                return False  # where it was anchored: nothing to re-anchor
        self._landed[i] = True
        if self._late[i] and t >= self._late_from[i]:
            # Lowered to find the ground: stand where the sole met it. The target went below the plan because the
            # foot was higher than planned when the swing ended (a body that rose or rolled, or a lower ground);
            # the measured sole height is the ground's, and keeping the target's own depth instead would extend
            # the stance leg, lift the body and make the next landing later still. The target returns to it over
            # the single support this foot carries next (moved at the descent's speed, a loaded foot's target makes
            # the ankle damping chatter).
            limit = self.options.late_descent_limit
            ground = min(0.0, max(-limit, self._depth(i, landing, m, values)))
            stance = q + 1 if support == "double" else q
            until = planner.phase_start(stance) + planner.timeline.duration(stance)
            self._ground[i] = (self._z[i], ground, t, max(until, t + self.dt))
        self._late[i], self._descent[i] = False, None
        if kind == "early":
            # Stand on it from now on where it landed; it goes on down with the plan (a stiff robot sags: most early
            # landings are that), but no further than late_descent_limit below where it touched (a higher ground).
            self._blend[i] = None
            planned_z = values.lfoot_z if i == 0 else values.rfoot_z
            floor = planned_z + self._z[i] - self.options.late_descent_limit
            self._hold[i] = (landing.x, landing.y, landing.yaw, floor)
            self._moved[i] = (landing.x, landing.y, landing.yaw)
        # A swinging foot's target goes on from where it is to where it landed over what is left of the swing (the
        # planner's retargeted swing, smooth): blended only when that is shorter than anchor_blend.
        remainder = planner.phase_start(q) + planner.timeline.duration(q) - t if swinging else 0.0
        try:
            index = planner.touchdown(t, landing.side, landing.x, landing.y, landing.yaw)
        except (ValueError, RuntimeError) as error:
            events.append(ControlEvent(t, "touchdown-refused", landing.side, str(error), landing.x, landing.y))
            return False
        self._anchor[i] = (landing.x, landing.y, landing.yaw)
        if remainder < self.options.anchor_blend:
            self._moved[i] = (landing.x, landing.y, landing.yaw)
        events.append(ControlEvent(t, "touchdown", landing.side, f"footprint {index}", landing.x, landing.y))
        return True

    def _short_of_foothold(
        self, landing: Landing, values: SampleValues, q: int, i: int
    ) -> tuple[float, float, float, float] | None:
        """Where foot ``i`` met ground short of its foothold: ``(z_touch, z_foothold, x, y)`` (m), its measured sole
        height and its foothold's height and place, when ``landing`` (in swing phase ``q``) is more than
        :data:`SHORT_LANDING` from the foothold, ``z_touch`` between :data:`SKIM_MIN_HEIGHT` and :data:`SKIM_HEIGHT`
        above it; ``None`` otherwise."""
        walk = self.planner.walk
        index = (q + 3) // 2  # single support q swings footprint F[(q + 3) // 2] (rtgait.core.geometry.footsteps)
        try:
            foothold = walk.footprint(index)
        except IndexError:
            return None
        if foothold.side != _SIDES[i] or math.hypot(foothold.x - landing.x, foothold.y - landing.y) <= SHORT_LANDING:
            return None
        # The measured sole height is the ground's: a floor the plan knows (a foot landing early under a push) is met
        # at its height; ground higher than SKIM_HEIGHT is not a step the sole can skim onto.
        if not SKIM_MIN_HEIGHT < landing.z - foothold.z <= SKIM_HEIGHT:
            return None
        if abs(landing.pitch) > SKIM_TILT or abs(landing.roll) > SKIM_TILT:
            return None  # on an edge or a heel (a sole landing tilted under a push): its sole point is off the ground
        return landing.z, foothold.z, foothold.x, foothold.y

    def _depth(self, i: int, landing: Landing, m: Measurement, values: SampleValues) -> float:
        """How far (m) below its foothold foot ``i`` met the ground at ``landing``: the other foot's ground depth,
        plus the landing's height relative to the other sole beyond the plan's when that exceeds
        ``ground_tolerance`` (module docstring, "Heights"); negative: lower than planned."""
        other = 1 - i
        planned = values.rfoot_z if other else values.lfoot_z
        relative = (landing.z - (m.right if other else m.left).pose[2]) - (self._foothold_z(i) - planned)
        ground = self._z[other]
        return ground + relative if abs(relative) > self.options.ground_tolerance else ground

    def _foothold_z(self, i: int) -> float:
        """Height (m) of the foothold foot ``i``'s last swing went to (the plan's height for it at the swing's end);
        0 when it is no longer kept."""
        try:
            return self.planner.walk.footprint((self._swing_phase[i] + 3) // 2).z
        except IndexError:
            return 0.0

    @property
    def skimming(self) -> bool:
        """Whether a foot that met ground short of its foothold is going on to it (no step adjustment meanwhile)."""
        return self._skim[0] is not None or self._skim[1] is not None
