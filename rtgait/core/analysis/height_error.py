"""The error the COG's vertical motion adds to the horizontal dynamics, measured on a planned walk.

The planner's horizontal equation is the pendulum's, ``p = c - c'' / w^2`` per axis (the paper's eq. 3, its eq. 4
neglecting the rest). The ZMP a point mass with this COG motion really has on a support surface at height ``p_z``
is, without any multibody term (no angular momentum about the COG),

    p_true = c - (c_z - p_z) c'' / (c_z'' + g)                                                       (full ZMP)

per horizontal axis (m). :func:`zmp_error` evaluates it on the planned COG of a rollout (positions and
accelerations as sampled) and returns ``|p_true - p|``. ``p_z`` is the height of the true support surface at the
planned ZMP: the terrain's plane (height, pitch and roll) under the contact foot nearest to the ZMP, as a centre of
pressure lies on a sole, never over the gap between two feet (or two stepping stones).

With the 3D-DCM/VRP form (``c_z - c_z'' / w^2 = h + zc``, ``docs/method.md``) this reduces to
``p_true - p = (h - p_z) c'' / (c_z'' + g)``: zero wherever the surface under the ZMP is at the VRP's support
height ``h`` (every single support), non-zero in double supports between footholds at different heights and on
tilted soles. :func:`smooth_height_profile` gives the alternative the docs compare against: the same horizontal
plan with the COG height ``zc + h_s(t)``, ``h_s`` a quintic from one stance height to the next over each double
support, and ``w`` kept constant.
"""

from __future__ import annotations

import math

import numpy as np

from rtgait.core.analysis.rollout import Rollout
from rtgait.core.geometry.swing import blend
from rtgait.core.geometry.terrain import Terrain, surface


def support_heights(rollout: Rollout, terrain: Terrain) -> np.ndarray:
    """``p_z`` per tick (m): the terrain's plane under the contact foot nearest to the planned ZMP, at the ZMP."""
    zmp_x, zmp_y = rollout.column("zmp_x"), rollout.column("zmp_y")
    out = np.empty(len(rollout.times))
    planes: dict[tuple[float, float, float], tuple[float, float, float]] = {}
    for k, q in enumerate(rollout.phase):
        feet = rollout.contacts[int(q)]
        foot = min(feet, key=lambda f: (f.x - zmp_x[k]) ** 2 + (f.y - zmp_y[k]) ** 2)
        key = (foot.x, foot.y, foot.yaw)
        plane = planes.get(key)
        if plane is None:
            plane = planes[key] = surface(terrain, foot.x, foot.y, foot.yaw)
        z, pitch, roll = plane
        c, s = math.cos(foot.yaw), math.sin(foot.yaw)
        dx, dy = zmp_x[k] - foot.x, zmp_y[k] - foot.y
        out[k] = z - math.tan(pitch) * (c * dx + s * dy) + math.tan(roll) * (-s * dx + c * dy)
    return out


def full_zmp(cog: np.ndarray, cog_acc: np.ndarray, surface_z: np.ndarray, gravity: float) -> np.ndarray:
    """``p_true`` ``(k, 2)`` (m): the full ZMP equation on COG positions ``cog`` ``(k, 3)`` (m) and accelerations
    ``cog_acc`` ``(k, 3)`` (m/s^2) over a surface at heights ``surface_z`` ``(k,)`` (m)."""
    scale = (cog[:, 2] - surface_z) / (cog_acc[:, 2] + gravity)
    return cog[:, :2] - scale[:, None] * cog_acc[:, :2]


def zmp_error(rollout: Rollout, terrain: Terrain, gravity: float, cog_z: np.ndarray | None = None) -> np.ndarray:
    """``|p_true - p|`` per tick (m): the full ZMP of the planned COG (or of the COG at heights ``cog_z`` (m), its
    acceleration by central differences) minus the planned ZMP, ``p_z`` from :func:`support_heights`."""
    cols = rollout.column
    cog = np.column_stack((cols("cog_x"), cols("cog_y"), cols("cog_z")))
    acc = np.column_stack((cols("cog_ax"), cols("cog_ay"), cols("cog_az")))
    if cog_z is not None:
        cog[:, 2] = cog_z
        acc[:, 2] = np.gradient(np.gradient(cog_z, rollout.times), rollout.times)
    zmp = np.column_stack((cols("zmp_x"), cols("zmp_y")))
    surface_z = support_heights(rollout, terrain)
    return np.linalg.norm(full_zmp(cog, acc, surface_z, gravity) - zmp, axis=1)


def smooth_height_profile(rollout: Rollout, cog_height: float) -> np.ndarray:
    """The alternative COG height (m) per tick: ``zc`` above the stance foot in single support, a quintic from one
    stance height to the next over each double support (the mean of both feet where no single support is next)."""
    support_z: dict[int, float] = {}
    for q, feet in rollout.contacts.items():
        support_z[q] = feet[0].z if len(feet) == 1 else 0.5 * (feet[0].z + feet[1].z)
    heights = np.empty(len(rollout.times))
    phases = rollout.phase
    for q in np.unique(phases):
        q = int(q)
        ticks = np.flatnonzero(phases == q)
        feet = rollout.contacts[q]
        if len(feet) == 1:
            heights[ticks] = feet[0].z
            continue
        start = support_z.get(q - 1, support_z[q]) if q > 0 else support_z[q]
        end = support_z.get(q + 1, support_z[q])
        if len(rollout.contacts.get(q - 1, ())) != 1:
            start = support_z[q]
        if len(rollout.contacts.get(q + 1, ())) != 1:
            end = support_z[q]
        t0 = rollout.phase_starts[q]
        t1 = rollout.phase_starts.get(q + 1, rollout.times[ticks[-1]])
        span = max(t1 - t0, 1e-9)
        s = np.clip((rollout.times[ticks] - t0) / span, 0.0, 1.0)
        heights[ticks] = start + (end - start) * np.array([blend(v)[0] for v in s])
    return cog_height + heights


__all__ = ["full_zmp", "smooth_height_profile", "support_heights", "zmp_error"]
