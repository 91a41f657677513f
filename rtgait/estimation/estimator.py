"""The estimator's place in the control tick: sensor readings (and, for a simulator's truth, the truth) in, the
walking state a controller acts on out (:class:`~rtgait.estimation.state.Measurement`)."""

from __future__ import annotations

from typing import Protocol, runtime_checkable

from rtgait.estimation.state import Measurement
from rtgait.interface.readings import SensorReadings
from rtgait.interface.truth import GroundTruth

__all__ = ["Estimator"]


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
