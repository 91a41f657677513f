"""Write the example height fields next to this file: ``ramp.npy``, ``swell.npy`` and ``bumps.npy`` (heights in m,
rows along y).

* ``ramp.npy``: a 5 degree ramp as a grid, level at 0 up to x = 0.5 m, rising ``tan(5 deg)`` per metre over 2 m, then
  level at the top (``h = tan(5 deg) clip(x - 0.5, 0, 2)``), over x in [0, 3.5] m at 2 cm and y in [-0.5, 0.5] m at
  10 cm: the same ground as ``[terrain] type = "slope"`` with ``angle = 5 deg, length = 2, start = 0.5``.
* ``swell.npy``: one gentle swell 3 cm high and 2 m long across the walk (``h = 0.015 (1 - cos(pi (x - 0.5)))`` for
  x in [0.5, 2.5] m), the ground rising to the left by 2 % of the height per centimetre (``h (1 + 2 y)``), so the
  feet meet pitch and roll; same grid.
* ``bumps.npy``: the same height over half the length, two bumps 1 m long (``0.015 (1 - cos(2 pi (x - 0.5)))``), the
  same cross slope: four times the curvature (0.59 1/m), a flat 21 cm sole rocking by 3 mm on a crest.

The samples are 2 cm apart along the walk and 10 cm across it: MuJoCo collides a height field cell by cell (two
triangular prisms each) and keeps at most 50 contacts per pair of geoms, so a 21 x 13 cm sole meets about 45 prisms
here, its contacts reaching its edges; on a 5 cm grid they stop 2 cm short of its toe, on a 2 x 2 cm grid the limit
cuts them off and the sole slides (``docs/cli_and_scenarios.md``).

Run ``python examples/heightfield/make_heightfields.py``; the scenarios ``heightfield-ramp.toml``,
``heightfield-swell.toml`` and ``heightfield-bumps.toml`` read them (``rtgait plan
examples/heightfield/heightfield-swell.toml``).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
X = np.linspace(0.0, 3.5, 176)  # m: 2 cm apart
Y = np.linspace(-0.5, 0.5, 11)  # m: 10 cm apart
RAMP_ANGLE = math.radians(5.0)


def ramp() -> np.ndarray:
    """Heights (m) of the 5 degree ramp, ``(len(Y), len(X))``."""
    row = math.tan(RAMP_ANGLE) * np.clip(X - 0.5, 0.0, 2.0)
    return np.tile(row, (len(Y), 1))


def waves(count: int) -> np.ndarray:
    """Heights (m) of ``count`` waves 3 cm high over x in [0.5, 2.5] m with their cross slope, ``(len(Y), len(X))``."""
    along = np.where((X >= 0.5) & (X <= 2.5), 0.015 * (1.0 - np.cos(count * math.pi * (X - 0.5))), 0.0)
    return along[None, :] * (1.0 + 2.0 * Y[:, None])


if __name__ == "__main__":
    for name, grid in (("ramp", ramp()), ("swell", waves(1)), ("bumps", waves(2))):
        np.save(HERE / f"{name}.npy", grid)
        print(f"wrote {HERE / name}.npy")
