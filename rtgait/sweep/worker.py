"""One physics case in a process of its own: ``python -m rtgait.sweep.worker`` reads a job (JSON) on stdin, walks
it in MuJoCo with :func:`rtgait.io.sim_run.simulate` and prints the outcome as one JSON line on stdout.

A job is ``{"document": <base scenario's TOML document>, "values": <axis values>, "robot": NAME, "controller":
NAME or null, "state": "estimated", "truth" or null}``: the scenario travels whole, so a worker on another machine
needs rtgait, not the sweep's files.
A case that cannot be walked (the robot cannot reach it, a bad value) prints ``{"error": ...}`` and exits with
:data:`CASE_ERROR`; anything else that ends the process (a crash in the simulator, a kill) is the executor's to see.
"""

from __future__ import annotations

import json
import sys
from typing import Any

CASE_ERROR = 3
"""Exit code of a case that failed for a reason of its own (retrying it would fail the same way)."""


def simulate_options(controller: str | None, state: str | None = None) -> dict[str, Any]:
    """Keyword arguments of :func:`rtgait.io.sim_run.simulate` for ``controller`` and ``state`` (``None``: their
    defaults)."""
    options: dict[str, Any] = {} if controller is None else {"controller": controller}
    if state is not None:
        from rtgait.sim.loop_options import LoopOptions

        options["options"] = LoopOptions(state=state)  # type: ignore[arg-type]  # checked by LoopOptions
    return options


def run_job(job: dict[str, Any]) -> dict[str, Any]:
    """Walk one case in physics; its outcome (``fell``, ``tipped``, ``fall_time`` s, ``steps_completed``,
    ``steps_planned``)."""
    from rtgait.io.sim_run import mujoco_messages, simulate
    from rtgait.sweep.spec import case_scenario, scenario_from_document

    scenario = case_scenario(scenario_from_document(job["document"]), job["values"])
    with mujoco_messages():
        result = simulate(scenario, job["robot"], **simulate_options(job.get("controller"), job.get("state")))
    return {
        "fell": bool(result.fell),
        "tipped": bool(result.tipped),
        "fall_time": None if result.fall_time is None else float(result.fall_time),
        "steps_completed": int(result.steps_completed),
        "steps_planned": int(result.steps_planned),
    }


def main() -> int:
    job = json.loads(sys.stdin.read())
    try:
        outcome = run_job(job)
    except (ValueError, RuntimeError) as error:  # the case's own problem: one line, no retry
        print(json.dumps({"error": " ".join(f"{type(error).__name__}: {error}".split())}))
        return CASE_ERROR
    print(json.dumps(outcome))
    return 0


if __name__ == "__main__":  # pragma: no cover - run as a subprocess
    sys.exit(main())
