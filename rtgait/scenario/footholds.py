"""Footstep plans: a walk given as absolute footholds in the world frame, each step with its own timing if wanted.

A footstep plan is a TOML file like a scenario (``name``, ``connection``, ``[robot]``, ``[timing]``; every key in
``docs/cli_and_scenarios.md``, "Footstep plans") whose walk is a list of landings instead of a step length::

    [walk]                              # optional, as each of its keys
    step_width = 0.19                   # m: the standing feet, side by side at the origin heading +x (default 0.19)
    step_height = 0.05                  # m, swing-foot peak height (default 0.05)

    [[footstep]]                        # one per step, in walking order, at least two
    side = "right"                      # "left" | "right", alternating; the first one is the foot that swings first
    x = 0.10                            # m, world frame
    y = -0.095
    yaw = 0.0                           # rad, optional (default 0)
    z = 0.0                             # m, optional (default 0): the foothold's height
    pitch = 0.0                         # rad, optional (default 0): the support surface's pitch (+: toes down)
    roll = 0.0                          # rad, optional (default 0): its roll (+: the foot's left edge up)
    single_support = 0.8                # s, optional: this step's single support (default [timing]'s)
    double_support = 0.2                # s, optional: the double support after it (not on the last step)

The file lists the *steps* only: the standing feet ``F[0], F[1]`` are side by side at the origin, heading +x,
``walk.step_width`` apart (a planner started from measured feet, ``start(feet=...)``, moves the walk rigidly with
them, its strides being relative). The last step is the closing one: the walk ends with the ZMP between the last
two footholds and the COG at rest over that point, whatever they are. The double support after the last step is the
final one, ``timing.end``, so the last step may not give ``double_support``.

Refused, with the step named in one line (:class:`~rtgait.scenario.scenario.ScenarioError`): two steps of the same
side in a row, a landing out of reach of its stance foot (farther than :data:`~rtgait.core.limits.MAX_STRIDE`, or a
turn of a quarter turn or more), feet crossing, NaN or infinite values, and a timing outside the phase limits.
:func:`footstep_plan_text` writes a walk's footholds back in this format (``rtgait plan --export-footsteps``),
with ``z``, ``pitch`` and ``roll`` where they are not 0. A ``[terrain]`` table (:mod:`rtgait.scenario.terrain_table`)
with ``place_footsteps = true`` (its default) replaces each foothold's ``z``, ``pitch`` and ``roll`` with the
terrain's.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from rtgait.core.geometry.footsteps import Footstep, Timing, standing_feet, stride_between
from rtgait.core.limits import MAX_STEPS, MAX_STRIDE, MAX_SURFACE_TILT
from rtgait.scenario.scenario import Scenario, ScenarioError
from rtgait.scenario.scenario_file import build_scenario, number, parse_common, walk_stance
from rtgait.scenario.terrain_table import parse_terrain
from rtgait.scenario.tomlfile import TomlFiles

__all__ = ["footstep_plan_text", "parse_footstep_plan"]

_FILES = TomlFiles(kind="footstep plan", folder="scenarios", error=ScenarioError)
_STEP_KEYS = ("yaw", "z", "pitch", "roll", "single_support", "double_support")
_PHASE_BOUNDS = (1e-3, 60.0)


def _step_name(index: int) -> str:
    return f"footstep[{index}] (step {index + 1})"


def _parse_step(entry: Any, index: int, last: bool) -> tuple[Footstep, float | None, float | None]:
    """One ``[[footstep]]`` entry: the landing and its own single and double support (s, ``None``: not given)."""
    where = f"footstep[{index}]"
    entry = _FILES.table(entry, where)
    _FILES.check_keys(entry, where, ("side", "x", "y"), _STEP_KEYS)
    side = entry["side"]
    if side not in ("left", "right"):
        raise ScenarioError(f"{where}.side must be 'left' or 'right', got {side!r}")
    x = number(entry, "x", where, unit="m")
    y = number(entry, "y", where, unit="m")
    yaw = number(entry, "yaw", where, unit="rad") if "yaw" in entry else 0.0
    if not abs(yaw) <= math.pi:
        raise ScenarioError(f"{where}.yaw must be within [-pi, pi] rad, got {yaw}")
    z = number(entry, "z", where, unit="m", bounds=(-MAX_STRIDE, MAX_STRIDE)) if "z" in entry else 0.0
    tilt = {
        key: number(entry, key, where, unit="rad", bounds=(-MAX_SURFACE_TILT, MAX_SURFACE_TILT))
        for key in ("pitch", "roll")
        if key in entry
    }
    timing: list[float | None] = []
    for key in ("single_support", "double_support"):
        value = None
        if key in entry:
            if key == "double_support" and last:
                raise ScenarioError(
                    f"{where}.double_support: the last step is followed by the final double support, timing.end"
                )
            value = number(entry, key, where, rule="> 0", unit="s", bounds=_PHASE_BOUNDS)
        timing.append(value)
    return Footstep(x, y, yaw, side, z, **tilt), timing[0], timing[1]


def check_reach(stance: Footstep, landing: Footstep, index: int) -> None:
    """``landing`` (``footstep[index]``) is a step the robot can take from ``stance``, else :class:`ScenarioError`."""
    name = _step_name(index)
    if landing.side == stance.side:
        raise ScenarioError(f"{name} is a {landing.side} foot again: steps alternate left and right")
    distance = math.hypot(landing.x - stance.x, landing.y - stance.y)
    if distance > MAX_STRIDE:
        raise ScenarioError(
            f"{name} lands {distance:.3g} m from the stance foot: out of reach (a stride is at most {MAX_STRIDE:g} m)"
        )
    try:
        stride_between(stance, landing)
    except ValueError as error:
        text = str(error)
        if "width" in text:
            text = "the feet cross (the landing is on the wrong side of the stance foot)"
        elif "turn" in text:
            text = "it turns a quarter turn or more from the stance foot"
        raise ScenarioError(f"{name} is out of reach: {text}") from None


def parse_footstep_plan(data: dict[str, Any], source: str = "") -> Scenario:
    """Build the :class:`~rtgait.scenario.scenario.Scenario` of a footstep plan from its parsed TOML ``data`` (module
    docstring)."""
    _FILES.check_keys(
        data,
        "",
        ("name", "connection", "robot", "timing", "footstep"),
        ("description", "auto_margin", "control", "walk", "obstacle", "terrain", "walking"),
    )
    common = parse_common(data)
    walk = _FILES.table(data.get("walk", {}), "walk")
    _FILES.check_keys(walk, "walk", (), ("step_width", "step_height"))
    step_width, step_height = walk_stance(walk)  # the built-in scenarios' values when not given
    raw = data["footstep"]
    if not isinstance(raw, list):
        raise ScenarioError("footstep must be an array of tables, written [[footstep]]")
    if not 2 <= len(raw) <= MAX_STEPS:
        raise ScenarioError(f"a footstep plan needs 2..{MAX_STEPS} [[footstep]] entries, got {len(raw)}")
    steps = [_parse_step(entry, index, index == len(raw) - 1) for index, entry in enumerate(raw)]
    first_foot = steps[0][0].side
    chain = list(standing_feet(step_width, first_foot))
    for index, (landing, _, _) in enumerate(steps):
        check_reach(chain[-1], landing, index)
        chain.append(landing)
    timing: Timing = common.pop("timing")
    if any(single is not None or double is not None for _, single, double in steps):
        per_step = tuple(
            (timing.single_support if single is None else single, timing.double_support if double is None else double)
            for _, single, double in steps
        )
        timing = Timing(timing.single_support, timing.double_support, timing.start, timing.end, timing.settle,
                        per_step=per_step)  # fmt: skip
    return build_scenario(
        **common,
        timing=timing,
        steps=len(steps) - 1,  # the last step is the closing one
        step_length=0.0,
        step_width=step_width,
        step_height=step_height,
        first_foot=first_foot,
        source=source,
        footholds=tuple(landing for landing, _, _ in steps),
        terrain=parse_terrain(data["terrain"], step_width) if "terrain" in data else None,
    )


def _toml_string(value: str) -> str:
    return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'


def footstep_plan_text(scenario: Scenario, footprints: Sequence[Footstep], name: str | None = None) -> str:
    """A footstep plan (module docstring) of ``scenario``'s robot and timing walking ``footprints`` ``F[0..N+1]``
    (the standing feet first, as :attr:`~rtgait.core.analysis.rollout.Rollout.footprints` holds them); each step keeps
    its own timing when the scenario has per-step timings. Numbers are written with all their digits (``repr``), so
    loading the text gives the same footholds."""
    t = scenario.timing
    lines = [f"name = {_toml_string(name or scenario.name)}"]
    if scenario.description:
        lines.append(f"description = {_toml_string(scenario.description)}")
    lines.append(f"connection = {_toml_string(scenario.connection)}")
    if scenario.connection == "auto":
        lines.append(f"auto_margin = {scenario.auto_margin!r}")
    lines += ["", "[robot]", f"cog_height = {scenario.cog_height!r}", f"gravity = {scenario.gravity!r}"]
    if scenario.mass is not None:
        lines.append(f"mass = {scenario.mass!r}")
    sole = scenario.sole
    lines += ["", "[robot.sole]", *(f"{key} = {getattr(sole, key)!r}" for key in ("front", "back", "inner", "outer"))]
    lines += ["", "[timing]", *(f"{key} = {getattr(t, key)!r}" for key in ("single_support", "double_support"))]
    lines += [f"dt = {scenario.dt!r}", f"horizon_steps = {scenario.horizon_steps}"]
    lines += [f"{key} = {getattr(t, key)!r}" for key in ("start", "end", "settle")]
    lines += ["", "[walk]", f"step_width = {scenario.step_width!r}", f"step_height = {scenario.step_height!r}"]
    for entry in scenario.walking:  # what the walk asks of a named robot, kept with its footholds
        lines += ["", f"[walking.{entry.robot}]"]
        lines += [f"{key} = {getattr(entry, key)!r}" for key in ("cog_height", "toe_release") if getattr(entry, key)]
    landings = list(footprints)[2:]
    for k, foot in enumerate(landings, start=1):
        lines += ["", "[[footstep]]", f"side = {_toml_string(foot.side)}", f"x = {foot.x!r}", f"y = {foot.y!r}"]
        lines.append(f"yaw = {foot.yaw!r}")
        lines += [f"{key} = {getattr(foot, key)!r}" for key in ("z", "pitch", "roll") if getattr(foot, key)]
        if t.per_step and k <= len(t.per_step):
            single, double = t.per_step[k - 1]
            lines.append(f"single_support = {single!r}")
            if k < len(landings):
                lines.append(f"double_support = {double!r}")
    return "\n".join(lines) + "\n"
