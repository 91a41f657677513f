"""Write the example height fields next to this file: ``ramp.npy`` and ``bumps.npy`` (heights in m, rows along y).

* ``ramp.npy``: a 5 degree ramp as a grid, level at 0 up to x = 0.5 m, rising ``tan(5 deg)`` per metre over 2 m, then
  level at the top (``h = tan(5 deg) clip(x - 0.5, 0, 2)``), over x in [0, 3.5] m at 5 cm and y in [-0.5, 0.5] m at
  10 cm: the same ground as ``[terrain] type = "slope"`` with ``angle = 5 deg, length = 2, start = 0.5``.
* ``bumps.npy``: two gentle bumps 3 cm high and 1 m long across the walk (``h = 0.015 (1 - cos(2 pi (x - 0.5)))``
  for x in [0.5, 2.5] m), the ground rising to the left by 2 % of the height per centimetre (``h (1 + 2 y)``), so
  the feet meet pitch and roll; same grid.

Run ``python examples/heightfield/make_heightfields.py``; the scenarios ``heightfield-ramp.toml`` and
``heightfield-bumps.toml`` read them (``rtgait plan examples/heightfield/heightfield-bumps.toml``).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
X = np.linspace(0.0, 3.5, 71)  # m: 5 cm apart
Y = np.linspace(-0.5, 0.5, 11)  # m: 10 cm apart
RAMP_ANGLE = math.radians(5.0)


def ramp() -> np.ndarray:
    """Heights (m) of the 5 degree ramp, ``(len(Y), len(X))``."""
    row = math.tan(RAMP_ANGLE) * np.clip(X - 0.5, 0.0, 2.0)
    return np.tile(row, (len(Y), 1))


def bumps() -> np.ndarray:
    """Heights (m) of the two bumps with their cross slope, ``(len(Y), len(X))``."""
    along = np.where((X >= 0.5) & (X <= 2.5), 0.015 * (1.0 - np.cos(2.0 * math.pi * (X - 0.5))), 0.0)
    return along[None, :] * (1.0 + 2.0 * Y[:, None])


if __name__ == "__main__":
    np.save(HERE / "ramp.npy", ramp())
    np.save(HERE / "bumps.npy", bumps())
    print(f"wrote {HERE / 'ramp.npy'} and {HERE / 'bumps.npy'}")
