"""The robot as a controller stack sees it: read the sensors, write the joint commands.

A real robot's driver, a simulator or a log player implements :class:`RobotInterface`; a simulator may also offer
its ground truth (:class:`GroundTruthSource`), which only evaluation and an estimator that says so read.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol, runtime_checkable

from rtgait.interface.command import JointCommand
from rtgait.interface.readings import SensorReadings
from rtgait.interface.truth import GroundTruth

__all__ = ["GroundTruthSource", "RobotInterface"]


@runtime_checkable
class RobotInterface(Protocol):
    """Sensors in, joint commands out, once per control period.

    Attributes:
        joint_names: the joints, in the order of every per-joint array of readings and commands.
    """

    joint_names: Sequence[str]

    def read(self) -> SensorReadings:
        """The sensors' readings now."""
        ...

    def write(self, command: JointCommand) -> None:
        """Send the joints' references for the coming control period."""
        ...


@runtime_checkable
class GroundTruthSource(Protocol):
    """What a simulator knows and a robot does not (:mod:`rtgait.interface.truth`)."""

    def ground_truth(self) -> GroundTruth:
        """The truth of the state the last readings describe."""
        ...
