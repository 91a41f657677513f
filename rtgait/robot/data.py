"""Where the robot files are: example-robot-data's installed share folder.

The ``example-robot-data`` wheel ships URDFs and meshes under ``cmeel.prefix/share/example-robot-data/robots``
inside site-packages, but not the ``example_robot_data`` Python helper; the folder is found from the installed
distribution's file list, never from the network.
"""

from __future__ import annotations

import importlib.metadata
from functools import cache
from pathlib import Path

DISTRIBUTION = "example-robot-data"
SHARE = Path("cmeel.prefix/share")
ROBOTS = SHARE / "example-robot-data" / "robots"


class RobotDataError(LookupError):
    """The robot files cannot be found."""


@cache
def share_dir() -> Path:
    """The ``share`` folder that ``package://`` URIs of example-robot-data URDFs resolve against."""
    try:
        dist = importlib.metadata.distribution(DISTRIBUTION)
    except importlib.metadata.PackageNotFoundError:
        raise RobotDataError(f"the '{DISTRIBUTION}' package is not installed: pip install 'rtgait[robot]'") from None
    folder = Path(dist.locate_file(SHARE))
    if not (folder / "example-robot-data" / "robots").is_dir():
        raise RobotDataError(f"'{DISTRIBUTION}' is installed but its robot folder is missing under {folder}")
    return folder


def robots_dir() -> Path:
    """``.../share/example-robot-data/robots``: one sub-folder per robot."""
    return share_dir() / "example-robot-data" / "robots"


def data_file(relative: str | Path) -> Path:
    """A file of example-robot-data by its path below ``robots/`` (e.g. ``talos_data/robots/talos_reduced.urdf``)."""
    path = robots_dir() / relative
    if not path.is_file():
        raise RobotDataError(f"example-robot-data has no file robots/{relative}")
    return path
