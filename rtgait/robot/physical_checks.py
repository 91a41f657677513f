"""Physical sense of a robot's URDF: the numbers finite, every link's mass and inertia those of a rigid body, the
whole robot's mass and COM height those of a humanoid.

Per link, read from the URDF's XML before Pinocchio parses it (:func:`check_urdf_physics`; Pinocchio's URDF parser
prints several lines of C++ errors for a number it cannot read and then drops the element, building a robot without
that link's mass):

* every number of a joint's ``<origin>``, ``<axis>``, ``<limit>`` and ``<dynamics>`` and of a link's ``<inertial>``
  is a finite decimal number;
* a link's mass m is positive (kg). A link without ``<inertial>`` is massless by the URDF spec, and so is one whose
  ``<inertial>`` writes that out, mass 0 and every inertia entry 0 (Talos's camera frames): both are frames and
  carry nothing. Any other mass <= 0 is an error;
* its inertia matrix I (kg m^2, symmetric, about the link's COM) has principal moments, the eigenvalues
  I1 <= I2 <= I3, that are not negative (I positive semi-definite) and satisfy the triangle inequality
  I1 + I2 >= I3, which holds for every rigid body: along the principal axes, I1 + I2 - I3 = 2 * integral of z^2 dm
  >= 0 (z along the third axis). Both within m * r^2, r = :data:`INERTIA_TOLERANCE_RADIUS`. A point mass (I = 0)
  passes: Talos's optical frames carry 10 g each with no inertia, as many URDFs model small parts.

For the whole robot, once the model is built (:func:`check_whole_body`, called by
:meth:`rtgait.robot.model.RobotModel.load`): the total mass within :data:`TOTAL_MASS_RANGE` and the COM height at
half-sitting within :data:`COM_HEIGHT_RANGE`. Every problem is a :class:`~rtgait.robot.description_checks.RobotError`
of one line naming the link or joint and the value.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ElementTree
from pathlib import Path

import numpy as np

from rtgait.robot.description_checks import RobotError

__all__ = [
    "COM_HEIGHT_RANGE",
    "INERTIA_TOLERANCE_RADIUS",
    "TOTAL_MASS_RANGE",
    "check_urdf_physics",
    "check_whole_body",
]

TOTAL_MASS_RANGE = (1.0, 500.0)
"""Plausible total mass of a humanoid (kg): from a toy-sized robot (Robotis OP3 3.5 kg, a 1 kg kit) to well beyond
the heaviest full-size ones (Valkyrie 129 kg, HRP-5P 101 kg). A URDF written in grams lands above it, one whose
links are mostly massless below it. The same range as ``simulate --model lipm --mass``."""

COM_HEIGHT_RANGE = (0.1, 2.0)
"""Plausible COM height of a humanoid standing at half-sitting (m), above the ground under its soles. A standing
humanoid's COM is at about 55 % of its height: 0.1 m is a 0.2 m toy, 2 m a 3.6 m giant. A URDF in mm, or a posture
or sole frame that puts the body under the feet, lands outside it."""

INERTIA_TOLERANCE_RADIUS = 1e-3
"""Slack of a link's inertia checks (m): the principal moments may miss them by the inertia of the link's mass m at
this distance, m * r^2 (kg m^2). URDF files write inertias with about six significant digits; for a link of gyration
radius k that rounding moves the moments by about 1e-6 * m * k^2, below m * (1 mm)^2 for any k < 1 m, and can make a
thin plate (I1 + I2 = I3 exactly) or a thin rod (I1 = 0) seem to break the rules. A real link's moments are larger
than m * (1 cm)^2, a hundred times the slack."""

# A URDF number as urdfdom reads it: a decimal float, no "nan", "inf", "1_000" (which Python's float() takes).
_DECIMAL = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?")
_INERTIA_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
_JOINT_NUMBERS = {  # element -> its numeric attributes and how many numbers each holds
    "origin": {"xyz": 3, "rpy": 3},
    "axis": {"xyz": 3},
    "limit": {"lower": 1, "upper": 1, "effort": 1, "velocity": 1},
    "dynamics": {"damping": 1, "friction": 1},
}


def check_urdf_physics(root: ElementTree.Element, urdf: Path) -> None:
    """Check the numbers of the URDF's joints and the mass and inertia of its links (see the module docstring).

    Args:
        root: the URDF's ``<robot>`` element.
        urdf: the URDF file, for messages.

    Raises:
        RobotError: one line naming the URDF, the link or joint and the value.
    """
    where = f"model.urdf {urdf.name}"
    for joint in root.findall("joint"):
        name = f'{where}: joint "{joint.get("name", "")}"'
        for tag, attributes in _JOINT_NUMBERS.items():
            element = joint.find(tag)
            if element is not None:
                for attribute, count in attributes.items():
                    _numbers(element, attribute, count, name)
    for link in root.findall("link"):
        inertial = link.find("inertial")
        if inertial is not None:
            _check_inertial(inertial, f'{where}: link "{link.get("name", "")}"')


def check_whole_body(name: str, mass: float, com_height: float) -> None:
    """Check the total mass (kg) and the COM height at half-sitting (m) of robot ``name`` against
    :data:`TOTAL_MASS_RANGE` and :data:`COM_HEIGHT_RANGE`.

    Raises:
        RobotError: either is outside its range (or not finite).
    """
    low, high = TOTAL_MASS_RANGE
    if not low <= mass <= high:
        raise RobotError(
            f"robot {name}: total mass {mass:.6g} kg is outside the plausible range [{low:g}, {high:g}] kg of a "
            "humanoid; check the URDF's masses and their unit (kg)"
        )
    low, high = COM_HEIGHT_RANGE
    if not low <= com_height <= high:
        raise RobotError(
            f"robot {name}: the COM is {com_height:.4g} m above the soles at half-sitting, outside the plausible "
            f"range [{low:g}, {high:g}] m of a humanoid; check the URDF's lengths (m), [posture] and the sole frames"
        )


def _check_inertial(inertial: ElementTree.Element, name: str) -> None:
    origin = inertial.find("origin")
    if origin is not None:
        _numbers(origin, "xyz", 3, name)
        _numbers(origin, "rpy", 3, name)
    mass_element, inertia_element = inertial.find("mass"), inertial.find("inertia")
    if mass_element is None or mass_element.get("value") is None:
        raise RobotError(f'{name}: its <inertial> has no <mass value="..."/>')
    if inertia_element is None or any(inertia_element.get(key) is None for key in _INERTIA_KEYS):
        raise RobotError(f"{name}: its <inertial> needs an <inertia> with all of {', '.join(_INERTIA_KEYS)}")
    mass = _number(mass_element.get("value", ""), f"{name} <mass value>")
    if not math.isfinite(mass):
        raise RobotError(f"{name} has mass {mass} kg: masses must be positive and finite")
    entries = {key: _number(inertia_element.get(key, ""), f"{name} <inertia {key}>") for key in _INERTIA_KEYS}
    for key, value in entries.items():
        if not math.isfinite(value):
            raise RobotError(f"{name} has inertia {key} = {value} kg m^2: inertias must be finite")
    if mass == 0.0 and not any(entries.values()):
        return  # a massless frame written out (see the module docstring)
    if mass <= 0.0:
        raise RobotError(
            f"{name} has mass {mass:g} kg: masses must be positive and finite (a massless link has no <inertial>)"
        )
    matrix = np.array(
        [
            [entries["ixx"], entries["ixy"], entries["ixz"]],
            [entries["ixy"], entries["iyy"], entries["iyz"]],
            [entries["ixz"], entries["iyz"], entries["izz"]],
        ]
    )
    moments = np.linalg.eigvalsh(matrix)  # ascending: I1 <= I2 <= I3
    text = ", ".join(f"{m:.4g}" for m in moments)
    slack = mass * INERTIA_TOLERANCE_RADIUS**2
    if moments[0] < -slack:
        raise RobotError(
            f"{name} has an inertia with principal moments {text} kg m^2: none may be negative "
            "(the inertia matrix positive semi-definite)"
        )
    if moments[0] + moments[1] < moments[2] - slack:
        raise RobotError(
            f"{name} has an inertia with principal moments {text} kg m^2: no rigid body has them, the two smaller "
            "must add up to at least the largest (I1 + I2 >= I3)"
        )


def _numbers(element: ElementTree.Element, attribute: str, count: int, name: str) -> tuple[float, ...]:
    """The ``count`` numbers of ``element``'s ``attribute`` (none when it is absent), each finite."""
    text = element.get(attribute)
    if text is None:
        return ()
    what = f"{name} <{element.tag} {attribute}>"
    values = tuple(_number(item, what) for item in text.split())
    if len(values) != count:
        raise RobotError(f'{what}: expected {count} number{"s" if count > 1 else ""}, got "{text}"')
    for value in values:
        if not math.isfinite(value):
            raise RobotError(f'{what} = "{text}": every number must be finite')
    return values


def _number(text: str, what: str) -> float:
    """``text`` as a float: a decimal number, or nan / inf (left to the caller to refuse with its own words)."""
    stripped = text.strip()
    try:
        value = float(stripped)
    except ValueError:
        value = None
    if value is None or (math.isfinite(value) and not _DECIMAL.fullmatch(stripped)):
        raise RobotError(f'{what}: "{text}" is not a number')
    return value
