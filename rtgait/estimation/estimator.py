"""The estimator's place in the control tick: sensor readings (and, for a simulator's truth, the truth) in, the
walking state a controller acts on out (:class:`~rtgait.estimation.state.Measurement`)."""

from __future__ import annotations

from typing import Literal, Protocol, runtime_checkable

from rtgait.estimation.state import Measurement
from rtgait.interface.readings import SensorReadings
from rtgait.interface.truth import GroundTruth

__all__ = ["DEFAULT_STATE", "STATE_SOURCES", "Estimator", "StateSource", "check_state"]

StateSource = Literal["truth", "estimated"]
"""What a controller acts on: ``"estimated"``, an estimate from the robot's own sensors; ``"truth"``, a simulator's
ground truth (for comparison)."""
STATE_SOURCES: tuple[StateSource, ...] = ("truth", "estimated")
DEFAULT_STATE: StateSource = "estimated"
"""What a controller acts on unless told otherwise, in the stack, the MuJoCo loop and the command line: the estimate
from the robot's own sensors, as on a robot."""


def check_state(state: str, name: str = "state") -> None:
    """Raise a ``ValueError`` naming ``name`` unless ``state`` is one of :data:`STATE_SOURCES`."""
    if state not in STATE_SOURCES:
        raise ValueError(f"{name} must be one of {', '.join(STATE_SOURCES)}, got {state!r}")


@runtime_checkable
class Estimator(Protocol):
    """Turns each tick's readings into the walking state.

    Attributes:
        reads_truth: whether it reads the simulator's ground truth (then it is for evaluation and ``--state truth``
            only: a robot has no such channel); an estimator for a robot reads ``readings`` alone.
    """

    reads_truth: bool

    def reset(self) -> None:
        """Forget every state (filters, contact states): the next update starts afresh."""
        ...

    def update(self, readings: SensorReadings | None, truth: GroundTruth | None) -> Measurement:
        """The walking state at this tick from its readings (``None`` where the estimator reads none) and, for an
        estimator that reads the truth, the truth of the same instant."""
        ...
