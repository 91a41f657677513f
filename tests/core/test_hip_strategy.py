"""The hip strategy's lean against a pendulum whose CMP it moves (rtgait.core.laws.hip_strategy).

The plant is the DCM of a linear inverted pendulum, ``xi' = w (xi - cmp)``, advanced exactly over each tick with
the CMP held, ``cmp = p + L' / (m g)``: the ZMP ``p`` the sole allows, plus the angular momentum rate of the lean
``L = I lam'`` computed here from the lean angles the law outputs (finite differences), not from the law's own
bookkeeping. The capture bound is the module docstring's, derived by hand: a bang-bang lean to ``max_lean`` at
``max_acceleration`` recovers a DCM at most ``(I a / (m g)) (1 - e^{-w t_1})^2`` past the sole's edge, with
``t_1 = sqrt(max_lean / a)``.
"""

from __future__ import annotations

import math

import pytest

from rtgait.core.laws.hip_strategy import HipStrategy, HipStrategyLimits

MASS, HEIGHT, G = 90.0, 0.877, 9.81
W = math.sqrt(G / HEIGHT)
INERTIA, ACCELERATION, MAX_LEAN = 7.6, 10.5, 0.25
DT = 0.001
EDGE, HOLD = 0.0, -0.05  # the sole's outer edge and where the DCM law holds the DCM (m), on the lateral axis
GAIN = 1.0 + 2.0 / W  # the DCM law's proportional gain (1 + k_p / w)


def limits(**changes: float) -> HipStrategyLimits:
    values = {"inertia": (INERTIA, INERTIA), "max_acceleration": (ACCELERATION, ACCELERATION), "max_lean": MAX_LEAN}
    values.update(changes)
    return HipStrategyLimits(**values)  # type: ignore[arg-type]


def capture_bound() -> float:
    """How far past the edge (m) a DCM can be and still be brought back (module docstring)."""
    t1 = math.sqrt(MAX_LEAN / ACCELERATION)
    return INERTIA * ACCELERATION / (MASS * G) * (1.0 - math.exp(-W * t1)) ** 2


def walk(offset: float, lean: bool, seconds: float = 4.0) -> tuple[list[float], list[float]]:
    """The DCM (m) and the lean (rad) at each tick, the DCM starting ``offset`` past the edge, the ZMP the DCM
    law's clipped to the sole ``[-0.1, EDGE]`` and the clipped part asked of the lean (the controller's wiring)."""
    hip = HipStrategy(limits(), MASS, DT)
    xi, dcm, angles = EDGE + offset, [], [0.0, 0.0]
    for _ in range(round(seconds / DT)):
        law = HOLD + GAIN * (xi - HOLD)
        p = min(max(law, -0.1), EDGE)
        if lean:
            hip.update((0.0, law - p), 0.0)  # heading +x: the lateral axis is world y
            angles.append(hip.lean[1])
        else:
            angles.append(0.0)
        # The lean's angular acceleration over this tick, from the angles alone: lam'' = (l2 - 2 l1 + l0) / dt^2.
        acc = (angles[-1] - 2.0 * angles[-2] + angles[-3]) / DT**2
        cmp = p + INERTIA * acc / (MASS * G)
        xi = cmp + (xi - cmp) * math.exp(W * DT)
        dcm.append(xi)
        if abs(xi) > 1.0:
            break
    return dcm, angles[2:]


def test_a_dcm_past_the_edge_falls_without_the_lean() -> None:
    dcm, _ = walk(0.002, lean=False)
    assert dcm[-1] > 1.0


@pytest.mark.parametrize("share", [0.05, 0.5, 0.8])
def test_the_lean_brings_back_a_dcm_within_its_bound(share: float) -> None:
    dcm, angles = walk(share * capture_bound(), lean=True, seconds=8.0)
    assert max(dcm) < 0.05
    assert abs(dcm[-1] - HOLD) < 2e-3  # back where the law holds it
    assert max(abs(a) for a in angles) <= MAX_LEAN + 1e-12
    assert abs(angles[-1]) < 0.02  # and the upper body comes back upright


def test_no_lean_brings_back_a_dcm_beyond_its_bound() -> None:
    dcm, _ = walk(1.1 * capture_bound(), lean=True)
    assert dcm[-1] > 1.0


def test_the_acceleration_and_the_range_are_kept() -> None:
    hip = HipStrategy(limits(), MASS, DT)
    angles = [0.0, 0.0]
    for k in range(1500):
        hip.update((0.3, -0.3) if k < 700 else (0.0, 0.0), 0.4)
        angles.append(hip.lean[0])
    accelerations = [(c - 2 * b + a) / DT**2 for a, b, c in zip(angles, angles[1:], angles[2:], strict=False)]
    assert max(abs(a) for a in angles) == pytest.approx(MAX_LEAN)
    # Braking in time: no hard stop at the limit (a late brake stopped 0.16 rad/s in one tick, 163 rad/s^2);
    # the last tick before rest may round up by a fraction of the largest acceleration.
    assert max(abs(a) for a in accelerations) <= 1.5 * ACCELERATION


def test_the_lean_is_toward_the_shortfall_in_the_world_frame() -> None:
    """A shortfall toward world +y at heading 90 degrees is a lean forward; it tilts the top toward +y, which is a
    rotation about -x."""
    hip = HipStrategy(limits(), MASS, DT)
    for _ in range(50):
        out = hip.update((0.0, 0.2), math.pi / 2)
    forward, left = hip.lean
    assert forward > 0.0 and left == pytest.approx(0.0, abs=1e-12)
    rx, ry, rz = out.lean
    assert rx < 0.0 and ry == pytest.approx(0.0, abs=1e-12) and rz == 0.0
    assert out.leaning and out.cmp_offset[1] > 0.0


def test_an_axis_with_nothing_asked_returns() -> None:
    hip = HipStrategy(limits(), MASS, DT)
    for _ in range(100):
        hip.update((0.2, 0.2), 0.0)
    for _ in range(4000):
        hip.update((0.2, 0.0), 0.0)  # only forward asked now: the sideways lean must come back, not drift on
    forward, left = hip.lean
    assert forward == pytest.approx(MAX_LEAN)
    assert abs(left) < 0.01


def test_rest_without_shortfall_and_reset() -> None:
    hip = HipStrategy(limits(), MASS, DT)
    out = hip.update((0.005, -0.005), 0.0)  # inside the deadband
    assert out.lean == (0.0, 0.0, 0.0) and not out.leaning and hip.at_rest
    hip.update((0.3, 0.0), 0.0)
    assert not hip.at_rest
    hip.reset()
    assert hip.at_rest


@pytest.mark.parametrize(
    "changes",
    [{"inertia": (0.0, 1.0)}, {"max_acceleration": (1.0, math.nan)}, {"max_lean": 0.0}, {"max_lean": 2.0},
     {"deadband": -0.01}, {"return_rate": 0.0}, {"inertia": (1.0,)}],
)  # fmt: skip
def test_bad_limits(changes: dict[str, object]) -> None:
    with pytest.raises(ValueError, match="HipStrategyLimits"):
        limits(**changes)  # type: ignore[arg-type]


def test_bad_mass_and_dt() -> None:
    with pytest.raises(ValueError, match="mass"):
        HipStrategy(limits(), 0.0, DT)
    with pytest.raises(ValueError, match="dt"):
        HipStrategy(limits(), MASS, -1.0)


def test_the_limits_give_the_hand_derived_bound() -> None:
    forward, lateral = limits(inertia=(5.0, INERTIA), max_acceleration=(16.0, ACCELERATION)).recoverable_offset(
        MASS, W, G
    )
    assert lateral == pytest.approx(capture_bound(), rel=1e-12)
    t1 = math.sqrt(MAX_LEAN / 16.0)
    assert forward == pytest.approx(5.0 * 16.0 / (MASS * G) * (1.0 - math.exp(-W * t1)) ** 2, rel=1e-12)
    with pytest.raises(ValueError, match="omega"):
        limits().recoverable_offset(MASS, 0.0)
