"""N-step capturability of the linear inverted pendulum with a finite foot, and the largest push it survives.

Source: T. Koolen, T. de Boer, J. Rebula, A. Goswami, J. Pratt, "Capturability-based analysis and control of legged
locomotion, Part 1: Theory and application to three simple gait models", Int. J. Robotics Research 31(9), 2012. The
facts used here, restated:

Model (the paper's "3D-LIPM with finite-sized foot"). A point mass at constant height, ``w = sqrt(g / z_c)`` (1/s).
The ZMP can be placed anywhere within ``r_max`` (m) of the stance foot's reference point (a round foot). A step puts
the next reference point anywhere within ``l_max`` (m) of the current one, at least ``dt_s`` (s) after the previous
step; at touch-down the ZMP may jump onto the new foot at once (no double support). The state that matters is the
instantaneous capture point, i.e. the DCM ``xi = c + c' / w``, through its distance ``d`` from the stance reference
point.

Bounds. The pendulum is N-step capturable (can be brought to rest using at most N steps) if and only if ``d <= d_N``:

    d_0 = r_max
    d_N = (d_{N-1} + l_max - r_max) e^{-w dt_s} + r_max

Why: the best the stance foot can do is hold the ZMP at its edge facing the DCM, which then recedes along that line,
``d(t) = r_max + (d - r_max) e^{w t}``; stepping ``l_max`` toward it after ``dt_s`` leaves
``r_max + (d - r_max) e^{w dt_s} - l_max``, which must be at most ``d_{N-1}``. Solving the linear recurrence with
``a = e^{-w dt_s}``:

    d_N = r_max + l_max (a + a^2 + ... + a^N) = r_max + l_max a (1 - a^N) / (1 - a)
    d_inf = r_max + l_max a / (1 - a)

so ``d_N`` increases with N toward ``d_inf``; a DCM at or beyond ``d_inf`` cannot be captured by any number of steps.

Pushes. A push of impulse ``J`` (N s) on the mass ``m`` (kg) changes the COM velocity by ``J / m`` and hence the DCM
by ``J / (m w)``. :func:`max_capturable_impulse` turns the bounds into the largest push a given instant of single
support survives. Its assumptions, beyond the model's:

* Instantaneous push. A constant force ``F`` over ``T`` with the ZMP fixed moves the DCM by
  ``F (e^{w T} - 1) / (m w^2)``, i.e. like the impulse ``F T`` applied at about ``T / 2`` into the push; for ``T``
  well below ``1 / w`` (0.29 s at ``z_c = 0.8 m``) the difference is small, and it is ignored here.
* The first step is already under way. The swing foot lands no earlier than ``tau_1 = max(remaining, min_remaining)``
  after the push: ``remaining`` is the time the swing still needs (the planned remaining swing time, or less if the
  swing may be hurried), and ``min_remaining`` the least time in which the foot can be re-aimed and put down (a foot
  about to touch down cannot be sent elsewhere instantly). Each later step takes at least ``dt_s``. So the N-step
  bound at the push instant is ``D_N = (d_{N-1} + l_max - r_max) e^{-w tau_1} + r_max`` (``D_0 = r_max``);
  it equals ``d_N`` when ``tau_1 = dt_s``.
* Round foot and round reach. The capturable region is the disc of radius ``D_N`` about the stance reference point,
  in every direction. A rectangular sole is approximated by a single ``r_max``: the reach of the sole from the
  reference point toward the pushed DCM (:func:`reach_along`; that is the push direction when the planned DCM is
  near the reference point) is exact when the DCM moves along a line through the reference point, e.g. a push along
  an axis of the foot with the DCM on that axis; the smallest reach over all directions (the disc inscribed about
  the reference point) is always on the safe side. ``l_max`` likewise stands for the step length available in that
  direction.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

ArrayLike = float | np.ndarray | Sequence[float]


def _check(name: str, value: ArrayLike, low: float, strict: bool, unit: str) -> np.ndarray:
    """``value`` as a float array; ValueError naming ``name`` unless all finite and ``> low`` (or ``>= low``)."""
    arr = np.asarray(value, dtype=float)
    ok = np.isfinite(arr) & ((arr > low) if strict else (arr >= low))
    if not np.all(ok):
        relation = ">" if strict else ">="
        raise ValueError(f"{name} must be finite and {relation} {low:g} {unit}, got {value!r}")
    return arr


def _check_steps(steps: ArrayLike) -> np.ndarray:
    arr = np.asarray(steps, dtype=float)
    if not np.all((arr >= 0.0) & (arr == np.round(arr))):  # NaN fails both; inf passes (round(inf) is inf)
        raise ValueError(f"steps must be whole numbers >= 0 (or inf), got {steps!r}")
    return arr


def _out(x: np.ndarray) -> float | np.ndarray:
    return float(x) if np.ndim(x) == 0 else x


def capture_bound(
    steps: ArrayLike, *, r_max: ArrayLike, l_max: ArrayLike, step_time: ArrayLike, omega: ArrayLike
) -> float | np.ndarray:
    """``d_N`` (m): the largest DCM distance from the stance reference point that ``N = steps`` steps can capture.

    Args:
        steps: ``N``, whole numbers >= 0; ``inf`` gives :func:`capture_bound_limit`.
        r_max: how far the ZMP can move from the reference point (m), >= 0.
        l_max: longest step, between reference points (m), >= 0.
        step_time: shortest time between touch-downs ``dt_s`` (s), > 0.
        omega: pendulum frequency ``w`` (1/s), > 0.

    All arguments broadcast; a scalar result is a float. Computed as ``r_max + l_max a (1 - a^N) / (1 - a)``,
    ``a = e^{-w dt_s}`` (module docstring), with ``expm1`` so that a small ``w dt_s`` loses no accuracy.
    """
    n = _check_steps(steps)
    r = _check("r_max", r_max, 0.0, False, "m")
    length = _check("l_max", l_max, 0.0, False, "m")
    x = _check("step_time", step_time, 0.0, True, "s") * _check("omega", omega, 0.0, True, "1/s")
    ratio = np.expm1(-n * x) / np.expm1(-x)  # (1 - a^N) / (1 - a): 0 for N = 0, 1 / (1 - a) for N = inf
    return _out(r + length * np.exp(-x) * ratio)


def capture_bound_limit(
    *, r_max: ArrayLike, l_max: ArrayLike, step_time: ArrayLike, omega: ArrayLike
) -> float | np.ndarray:
    """``d_inf = r_max + l_max e^{-w dt_s} / (1 - e^{-w dt_s})`` (m): beyond it no number of steps captures."""
    return capture_bound(np.inf, r_max=r_max, l_max=l_max, step_time=step_time, omega=omega)


def steps_to_capture(
    distance: ArrayLike, *, r_max: ArrayLike, l_max: ArrayLike, step_time: ArrayLike, omega: ArrayLike
) -> float | np.ndarray:
    """Fewest steps ``N`` with ``distance <= d_N`` (a float, ``inf`` when ``distance >= d_inf``).

    ``distance`` is the DCM's distance from the stance reference point (m), >= 0; other arguments as for
    :func:`capture_bound`. Solves ``a^N <= 1 - (d - r_max)(1 - a) / (l_max a)`` by logarithms, then corrects the
    integer by one either way where round-off put it across a bound.
    """
    d = _check("distance", distance, 0.0, False, "m")
    r = _check("r_max", r_max, 0.0, False, "m")
    length = _check("l_max", l_max, 0.0, False, "m")
    x = _check("step_time", step_time, 0.0, True, "s") * _check("omega", omega, 0.0, True, "1/s")
    d, r, length, x = np.broadcast_arrays(d, r, length, x)
    bound = {"r_max": r, "l_max": length, "step_time": x, "omega": 1.0}  # only the product w dt_s matters

    def d_n(n: np.ndarray) -> np.ndarray:
        return np.asarray(capture_bound(n, **bound))

    between = (d > r) & (d < d_n(np.full(d.shape, np.inf)))  # r_max < d < d_inf, hence l_max > 0 and 0 < q < 1
    with np.errstate(divide="ignore", invalid="ignore"):
        q = 1.0 + (d - r) * np.expm1(-x) / (length * np.exp(-x))  # a^N must be at most q
        n = np.where(between, np.ceil(np.log(q) / -x), 0.0)
    n = np.where(between & (n > 0.0) & (d <= d_n(np.maximum(n - 1.0, 0.0))), n - 1.0, n)
    n = np.where(between & (d > d_n(n)), n + 1.0, n)
    n = np.where(d <= r, 0.0, np.where(between, n, np.inf))
    return _out(n)


def push_capture_bound(
    steps: ArrayLike,
    *,
    first_landing: ArrayLike,
    r_max: ArrayLike,
    l_max: ArrayLike,
    step_time: ArrayLike,
    omega: ArrayLike,
) -> float | np.ndarray:
    """``D_N`` (m): the N-step bound at an instant of single support whose swing foot lands ``first_landing`` (s,
    >= 0) later at the earliest: ``D_0 = r_max``, ``D_N = (d_{N-1} + l_max - r_max) e^{-w first_landing} + r_max``.

    Later steps take at least ``step_time`` each; other arguments as for :func:`capture_bound`.
    """
    n = _check_steps(steps)
    tau = _check("first_landing", first_landing, 0.0, False, "s")
    r = _check("r_max", r_max, 0.0, False, "m")
    length = _check("l_max", l_max, 0.0, False, "m")
    w = _check("omega", omega, 0.0, True, "1/s")
    previous = np.asarray(capture_bound(np.maximum(n - 1.0, 0.0), r_max=r, l_max=length, step_time=step_time, omega=w))
    bound = (previous + length - r) * np.exp(-w * tau) + r
    return _out(np.where(n == 0, r, bound))


def max_capturable_impulse(
    dcm_offset: Sequence[float] | np.ndarray,
    direction: Sequence[float] | np.ndarray,
    *,
    mass: float,
    omega: float,
    r_max: float,
    l_max: float,
    step_time: float,
    remaining: float,
    min_remaining: float = 0.0,
    steps: float = 1,
) -> float | np.ndarray:
    """Largest instantaneous push (N s) along ``direction`` after which the pendulum is still ``steps``-step capturable.

    Args:
        dcm_offset: planned DCM minus the stance foot's reference point at the push instant, ``(2,)`` (m).
        direction: push direction, ``(2,)`` or ``(k, 2)`` for several at once; normalised here, must not be zero.
        mass: ``m`` (kg).
        omega: ``w`` (1/s).
        r_max, l_max, step_time: foot reach (m), longest step (m), shortest step time (s), as in
            :func:`capture_bound`.
        remaining: time the swing foot still needs before it can land (s), >= 0.
        min_remaining: least time to re-aim and put down the swing foot (s), >= 0; the first landing is at
            ``tau_1 = max(remaining, min_remaining)``.
        steps: ``N``, the number of steps allowed (1: the step in progress only; 0: no step, the stance foot alone).

    Returns:
        ``J = m w s``, with ``s`` the largest ``s >= 0`` such that ``|dcm_offset + s u| <= D_N`` (module docstring);
        ``0.0`` when the planned DCM itself is outside ``D_N`` (no push is survivable). A float for one direction,
        an array ``(k,)`` for several.
    """
    offset = np.asarray(dcm_offset, dtype=float)
    if offset.shape != (2,) or not np.all(np.isfinite(offset)):
        raise ValueError(f"dcm_offset must be a finite (x, y) offset in m, got {dcm_offset!r}")
    u = np.asarray(direction, dtype=float)
    if u.shape[-1:] != (2,) or u.ndim > 2 or not np.all(np.isfinite(u)):
        raise ValueError(f"direction must be finite, shape (2,) or (k, 2), got {direction!r}")
    norm = np.linalg.norm(u, axis=-1, keepdims=True)
    if np.any(norm <= 0.0):
        raise ValueError("direction must not be the zero vector")
    u = u / norm
    m = float(_check("mass", mass, 0.0, True, "kg"))
    w = float(_check("omega", omega, 0.0, True, "1/s"))
    tau = max(
        float(_check("remaining", remaining, 0.0, False, "s")),
        float(_check("min_remaining", min_remaining, 0.0, False, "s")),
    )
    bound = float(push_capture_bound(steps, first_landing=tau, r_max=r_max, l_max=l_max, step_time=step_time, omega=w))
    # |o + s u|^2 = D^2  <=>  s^2 + 2 (o.u) s + |o|^2 - D^2 = 0; the larger root is the exit along u.
    along = u @ offset
    inside = offset @ offset - bound**2  # <= 0 when the planned DCM itself is capturable
    s = np.zeros_like(along) if inside > 0.0 else -along + np.sqrt(np.maximum(along**2 - inside, 0.0))
    return _out(m * w * s)


def reach_along(
    polygon: np.ndarray, origin: Sequence[float] | np.ndarray, direction: Sequence[float] | np.ndarray
) -> float:
    """Largest ``r >= 0`` (m) with ``origin + r u`` in the convex ``polygon`` ``(k, 2)``, ``u`` = unit ``direction``.

    The ``r_max`` of a sole along one direction (module docstring). ``origin`` must be inside the polygon.
    """
    vertices = np.asarray(polygon, dtype=float)
    if vertices.ndim != 2 or vertices.shape[0] < 3 or vertices.shape[1] != 2 or not np.all(np.isfinite(vertices)):
        raise ValueError("polygon must be at least 3 finite counter-clockwise vertices, shape (k, 2), in m")
    o = np.asarray(origin, dtype=float)
    u = np.asarray(direction, dtype=float)
    if o.shape != (2,) or u.shape != (2,) or not (np.all(np.isfinite(o)) and np.all(np.isfinite(u))):
        raise ValueError("origin and direction must be finite (x, y) pairs")
    norm = math.hypot(u[0], u[1])
    if norm == 0.0:
        raise ValueError("direction must not be the zero vector")
    u = u / norm
    edge = np.roll(vertices, -1, axis=0) - vertices
    normal = np.stack([edge[:, 1], -edge[:, 0]], axis=1)  # outward for counter-clockwise vertices
    slack = np.einsum("kd,kd->k", normal, vertices - o)  # >= 0 on every edge when origin is inside
    if np.any(slack < -1e-12 * max(1.0, float(np.max(np.abs(vertices))))):
        raise ValueError("origin must be inside the polygon (and the vertices counter-clockwise)")
    rate = normal @ u
    with np.errstate(divide="ignore"):
        limits = np.where(rate > 0.0, np.maximum(slack, 0.0) / rate, np.inf)
    return float(np.min(limits))
