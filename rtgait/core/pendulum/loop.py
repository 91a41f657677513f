"""The closed loop at the pendulum level: planner, controller and a point-mass plant, tick by tick.

For trying measured-state replanning, DCM feedback and step adjustment without a robot model. The plant
(:class:`~rtgait.core.pendulum.plant.LipmPlant`) is the linear inverted pendulum the planner assumes, so whatever goes
wrong is the controller's doing (or the pendulum's instability), never a modelling mismatch.

Controller levels (the names the MuJoCo loop uses too; the table in ``docs/closed_loop.md``): ``"open-loop"`` commands
the planned ZMP and replans from its own plan (the paper's assumption of perfect tracking); ``"stabilized"`` commands
the DCM feedback law's ZMP (:class:`~rtgait.core.laws.feedback.DcmFeedback`); ``"adaptive"`` adds the planner of
:func:`~rtgait.core.planner.levels.level_config` (every plan from the observed COM state, a replan at once beyond
``replan_dcm_error``, step adjustment), which the loop calls :meth:`~rtgait.core.planner.online.OnlinePlanner.observe`
every tick and :meth:`~rtgait.core.planner.online.OnlinePlanner.touchdown` at every landing.

One tick, from ``t`` to ``t + dt`` (``dt`` the control period, 1 ms by default): measure the plant at ``t`` (and
``observe`` it); the planner's sample at ``t`` and its support polygon (the convex hull of the soles on the ground,
rebuilt only when their poses change); the fall test; the sample at ``t + dt`` (a landing inside the tick is reported
by ``touchdown`` first); the commanded ZMP ``p_cmd``; the plant, whose real ZMP is ``p_cmd`` clipped to the polygon,
held over the tick with the pushes and integrated exactly (:meth:`LipmPlant.step`).

Reference ZMP of a tick. Holding the plan's ``p(t)`` over the tick would act like a delay of ``dt / 2`` and push the
DCM off the plan by about ``w dt Delta p / 2`` per ZMP transfer ``Delta p``. The loop holds instead the constant ZMP
that moves the plan's DCM over the tick exactly as ``p(s)`` does: from ``xi' = w (xi - p)``,

    p_bar = (xi_plan(t + dt) - a xi_plan(t)) / (1 - a),        a = e^{w dt}        (m)

a weighted mean of ``p(s)`` over the tick (weights ``w e^{w (t + dt - s)} / (a - 1)``). Only the convergent component
``c - c'/w`` then differs from the plan, by ``O(w dt^2 p')``. When the sample at ``t + dt`` comes from a replan from
the measured state, ``p_bar`` would carry the jump between two plans over ``1 - a``; that tick holds ``p(t)``.

Commanded ZMP: ``p_bar`` in ``"open-loop"``; otherwise ``p_cmd = p_bar + (1 + k_p / w) e + (k_i / w) I`` with
``e = xi - xi_plan(t)`` (m), projected onto the support polygon with anti-windup (:mod:`rtgait.core.laws.feedback`).

The mass has *fallen* when its COM is farther than ``plant.fall_distance`` (default ``z_c tan 25 deg``) from the
support polygon (:meth:`LipmPlant.fallen`; :mod:`rtgait.core.pendulum.plant` explains the choice); the run stops
there. It is *at rest* (``ended_at_rest``) when at the last tick the COM speed is below 1 cm/s and the DCM inside
the final support polygon (:meth:`LipmPlant.at_rest`). The run ends ``end_margin`` (s) after the walk's planned end
(re-read every tick: an emergency stop shortens the walk), or at a fall.

Per tick: one planner sample (two with ``"adaptive"``, plus ``observe``), the feedback law, the plant step and the fall
test on Python floats; numpy only for the plant's state and, when the feet on the ground change, the polygon.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable, Sequence

import numpy as np

from rtgait.core.analysis.rollout import ScheduledChange
from rtgait.core.geometry.footsteps import Footstep, SoleRect, Stride
from rtgait.core.geometry.support import SUPPORT_CODES, support_polygon
from rtgait.core.laws.feedback import DcmFeedback, DcmFeedbackGains
from rtgait.core.laws.stepping import StepAdjustment
from rtgait.core.limits import MAX_ROLLOUT_TICKS, MIN_DT
from rtgait.core.pendulum.plant import LipmPlant
from rtgait.core.pendulum.result import ClosedLoopResult
from rtgait.core.planner.config import PlannerConfig
from rtgait.core.planner.levels import DEFAULT_REPLAN_DCM_ERROR, ControllerLevel, check_level, level_config
from rtgait.core.planner.online import OnlinePlanner, PlanRecord
from rtgait.core.planner.sample import SampleValues
from rtgait.core.push import Push

DEFAULT_DT = 0.001
"""Control period (s): 1 kHz, the rate of the MuJoCo loop and of most humanoid controllers."""

DEFAULT_MASS = 57.0
"""Mass of the point mass (kg) when none is given: an HRP-2-like humanoid (58 kg with batteries)."""

DEFAULT_END_MARGIN = 0.5
"""Time (s) the loop runs past the walk's planned end, so that a mass still moving then is seen falling or not."""


# Column order of the per-tick table collected in the loop (one tuple of floats per tick).
_COLUMNS = (
    "t", "cog_planned_x", "cog_planned_y", "dcm_planned_x", "dcm_planned_y", "zmp_planned_x", "zmp_planned_y",
    "zmp_reference_x", "zmp_reference_y", "zmp_command_x", "zmp_command_y", "zmp_real_x", "zmp_real_y",
    "cog_x", "cog_y", "cog_vx", "cog_vy", "support", "phase", "saturated",
)  # fmt: skip


class _SupportCache:
    """The support polygon of the sampled feet on the ground, rebuilt only when their poses change.

    In single support only the stance foot counts, so the swing foot's motion does not rebuild it; step adjustment
    and touch-downs move footprints, which is why the key is the poses themselves and not the phase index.
    """

    __slots__ = ("key", "polygon", "sole")

    def __init__(self, sole: SoleRect) -> None:
        self.sole = sole
        self.key: tuple[object, ...] | None = None
        self.polygon = np.zeros((0, 2))

    def get(self, values: SampleValues, support: str) -> np.ndarray:
        left = (values.lfoot_x, values.lfoot_y, values.lfoot_yaw)  # the ground pose (x, y, yaw) of each foot
        right = (values.rfoot_x, values.rfoot_y, values.rfoot_yaw)
        if support == "double":
            key: tuple[object, ...] = (support, left, right)
        elif support == "left":
            key = (support, left)
        else:
            key = (support, right)
        if key != self.key:
            feet = []
            if support != "right":
                feet.append(Footstep(*left, "left"))
            if support != "left":
                feet.append(Footstep(*right, "right"))
            self.polygon = support_polygon(feet, self.sole)
            self.key = key
        return self.polygon


def run_pendulum_loop(
    config: PlannerConfig,
    strides: Sequence[Stride] | None,
    sole: SoleRect,
    *,
    controller: ControllerLevel = "adaptive",
    mass: float = DEFAULT_MASS,
    dt: float = DEFAULT_DT,
    pushes: Iterable[Push] = (),
    changes: Sequence[ScheduledChange] = (),
    gains: DcmFeedbackGains | None = None,
    replan_dcm_error: float = DEFAULT_REPLAN_DCM_ERROR,
    step_adjustment: StepAdjustment | None = None,
    fall_distance: float | None = None,
    duration: float | None = None,
    end_margin: float = DEFAULT_END_MARGIN,
    progress: Callable[[float], None] | None = None,
) -> ClosedLoopResult:
    """Walk ``strides`` with the planner, the controller ``controller`` and a point-mass plant, from t = 0.

    Args:
        config: the planner's base configuration; the level's is made from it by
            :func:`~rtgait.core.planner.levels.level_config`.
        strides: the walk (:class:`~rtgait.core.geometry.footsteps.Stride` per step, the closing one included), or
        ``None`` for a walk by velocity command (then ``duration`` is needed).
        sole: the sole rectangle (m), for the support polygons and the step adjustment.
        controller: ``"open-loop"``, ``"stabilized"`` or ``"adaptive"`` (module docstring).
        mass: of the point mass (kg); only the pushes' effect depends on it.
        dt: control period (s), at least 1e-5 and at most the shortest phase.
        pushes: :class:`~rtgait.core.pendulum.plant.Push` forces on the mass, on the walk's clock.
        changes: footstep changes, each handed to the planner at its connection mode's deadline (as
            :func:`~rtgait.core.analysis.rollout.rollout` does).
        gains: of the DCM feedback (``"stabilized"``, ``"adaptive"``); default :class:`DcmFeedbackGains`.
        replan_dcm_error, step_adjustment: the ``"adaptive"`` planner's settings
            (:func:`~rtgait.core.planner.levels.level_config`).
        fall_distance: COM distance from the support polygon at which the mass counts as fallen (m); default the
            plant's, ``z_c tan 25 deg``.
        duration: run this long (s) instead of until ``end_margin`` after the walk's end.
        end_margin: time run past the walk's planned end (s), >= 0.
        progress: called now and then with the fraction done.

    Returns:
        :class:`ClosedLoopResult`.
    """
    check_level(controller)
    if not (math.isfinite(dt) and dt >= MIN_DT):
        raise ValueError(f"dt must be a finite period >= {MIN_DT:g} s, got {dt}")
    shortest = min(config.timing.single_support, config.timing.double_support, config.timing.start, config.timing.end)
    if dt > shortest:
        raise ValueError(f"dt must not exceed the shortest phase ({shortest} s), got {dt}")
    if not (math.isfinite(end_margin) and end_margin >= 0.0):
        raise ValueError(f"end_margin must be a finite time >= 0 s, got {end_margin}")
    if duration is not None and not (math.isfinite(duration) and duration >= 0.0):
        raise ValueError(f"duration must be a finite time >= 0 s, got {duration}")
    planner = OnlinePlanner(
        level_config(config, controller, sole, replan_dcm_error=replan_dcm_error, step_adjustment=step_adjustment),
        strides,
    )
    adaptive = controller == "adaptive"
    planner.start(0.0)
    if duration is None and not math.isfinite(planner.end_time):
        raise ValueError("a walk by velocity command has no planned end: give a duration")
    pushes = tuple(pushes)
    pending = sorted(changes, key=lambda c: planner.change_deadline(c.step))

    def hand_over(t: float) -> None:
        # Before any sample at t: the changes whose deadline has come (the planner has sampled only before it).
        while pending and t >= planner.change_deadline(pending[0].step):
            change = pending.pop(0)
            planner.change_step(
                change.step, length=change.length, width=change.width, turn=change.turn, through=change.through
            )

    hand_over(0.0)
    current = planner.sample_values(0.0)
    standing, standing_support, _ = current
    w = planner.w
    # The plant starts on the plan: the planner's standing COM, at rest.
    plant = LipmPlant(
        planner.config.cog_height, mass, planner.config.gravity, (standing.cog_x, standing.cog_y),
        (standing.cog_vx, standing.cog_vy), time=0.0, fall_distance=fall_distance, pushes=pushes,
    )  # fmt: skip
    feedback = None if controller == "open-loop" else DcmFeedback(w, gains, dt)
    decay = math.exp(w * dt)
    hold = 1.0 / (1.0 - decay)
    supports = _SupportCache(sole)
    codes = SUPPORT_CODES

    rows: list[tuple[float, ...]] = []
    fell, fall_time = False, None
    steps_completed = 0
    landing_phase, landing_time = -1, math.inf  # the single support under way and the instant its swing lands
    polygon = supports.get(standing, standing_support)
    expected = (duration if duration is not None else planner.end_time + end_margin) / dt
    report_every = max(int(expected) // 50, 1)
    plans: list[PlanRecord] = []
    k = 0
    began = time.perf_counter()
    while True:
        t = k * dt
        limit = duration if duration is not None else planner.end_time + end_margin
        if t > limit + 1e-9 * dt:
            break
        if k >= MAX_ROLLOUT_TICKS:
            raise ValueError(f"a closed-loop run may take at most {MAX_ROLLOUT_TICKS} ticks (duration / dt)")
        cx, cy = plant.cog.tolist()
        vx, vy = plant.cog_vel.tolist()
        if adaptive:
            planner.observe(t, (cx, cy), (vx, vy))  # may replan at once (a large DCM error)
            current = planner.sample_values(t)
        values, support, q = current
        polygon = supports.get(values, support)
        dcm_x, dcm_y = cx + vx / w, cy + vy / w
        row_head = (t, values.cog_x, values.cog_y, values.dcm_x, values.dcm_y, values.zmp_x, values.zmp_y)
        if plant.fallen(polygon):
            fell, fall_time = True, t
            nan = math.nan
            rows.append((*row_head, nan, nan, nan, nan, nan, nan, cx, cy, vx, vy, codes[support], q, 0.0))
            break

        # ----- the next sample, the landing inside this tick, the reference ZMP ---------------------------------
        if q != landing_phase:
            landing_phase = q
            landing_time = planner.phase_start(q + 1) if support != "double" else math.inf
        replans = planner.replan_count
        t_next = (k + 1) * dt  # the next tick's own time, not t + dt: the two may differ in the last bit
        if t_next >= landing_time:
            landing_time = math.inf
            steps_completed += 1
            if adaptive:
                # The swing foot lands where the plan's swing trajectory ends, its footprint (a point mass has no
                # foot to land elsewhere); reported before the double support's replan, which then rests on it.
                i = (q + 1) // 2
                foot = planner.walk.footprint(i + 1)
                planner.touchdown(t, foot.side, foot.x, foot.y, foot.yaw)
        hand_over(t_next)
        following = planner.sample_values(t_next)
        upcoming, _, _ = following
        if adaptive and planner.replan_count != replans:
            # A plan from the measured state began inside the tick: the two DCMs belong to different plans.
            ref_x, ref_y = values.zmp_x, values.zmp_y
        else:
            ref_x = (upcoming.dcm_x - decay * values.dcm_x) * hold
            ref_y = (upcoming.dcm_y - decay * values.dcm_y) * hold

        # ----- controller and plant ----------------------------------------------------------------------------
        if feedback is None:
            cmd_x, cmd_y = ref_x, ref_y
            real_x, real_y = plant.step(dt, (cmd_x, cmd_y), polygon).tolist()
            saturated = real_x != cmd_x or real_y != cmd_y
        else:
            out = feedback.update((ref_x, ref_y), (values.dcm_x, values.dcm_y), (dcm_x, dcm_y), polygon, dt)
            cmd_x, cmd_y = out.zmp
            real_x, real_y = plant.step(dt, (cmd_x, cmd_y), polygon).tolist()
            saturated = out.saturated
        rows.append(
            (*row_head, ref_x, ref_y, cmd_x, cmd_y, real_x, real_y, cx, cy, vx, vy, codes[support], q, float(saturated))
        )  # fmt: skip
        if planner.replan_count > len(plans):
            plans.extend(planner.plans[-i] for i in range(planner.replan_count - len(plans), 0, -1))
        current = following
        k += 1
        if progress is not None and k % report_every == 0:
            progress(min(k / expected, 1.0))
    wall = time.perf_counter() - began
    if progress is not None:
        progress(1.0)

    table = np.array(rows, dtype=float).reshape(-1, len(_COLUMNS))
    ended_at_rest = not fell and plant.at_rest(polygon)
    cog = table[:, 13:15]
    cog_vel = table[:, 15:17]
    n_steps = planner.n_steps
    return ClosedLoopResult(
        times=table[:, 0].copy(),
        cog_planned=table[:, 1:3].copy(),
        dcm_planned=table[:, 3:5].copy(),
        zmp_planned=table[:, 5:7].copy(),
        zmp_reference=table[:, 7:9].copy(),
        zmp_command=table[:, 9:11].copy(),
        zmp_real=table[:, 11:13].copy(),
        cog=cog.copy(),
        cog_vel=cog_vel.copy(),
        dcm=cog + cog_vel / w,
        support=table[:, 17].astype(np.int8),
        phase=table[:, 18].astype(int),
        saturated=table[:, 19] > 0.5,
        controller=controller,
        mass=float(mass),
        dt=float(dt),
        omega=w,
        fell=fell,
        fall_time=fall_time,
        steps_completed=steps_completed,
        steps_planned=n_steps if n_steps is not None else steps_completed,
        # The planner keeps the decisions once it steps (a planner without the attribute adjusts nothing).
        step_adjustments=tuple(getattr(planner, "step_adjustments", ())),
        ended_at_rest=ended_at_rest,
        pushes=pushes,
        plans=tuple(plans),
        footprints=tuple(planner.footprints()),
        walk_end=planner.end_time,
        final_cog=plant.cog,
        final_cog_vel=plant.cog_vel,
        wall_time=wall,
    )


__all__ = ["DEFAULT_DT", "DEFAULT_END_MARGIN", "DEFAULT_MASS", "ClosedLoopResult", "run_pendulum_loop"]
