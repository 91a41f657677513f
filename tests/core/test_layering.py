"""The core is pure numpy/scipy: importing it pulls in no robot, simulator or plotting package."""

from __future__ import annotations

import subprocess
import sys

FORBIDDEN = ("pinocchio", "mujoco", "matplotlib", "meshcat", "example_robot_data", "rtgait.robot", "rtgait.sim",
             "rtgait.viz", "rtgait.cli.main", "rtgait.scenario.scenario")  # fmt: skip


def test_core_imports_alone():
    code = (
        "import sys, rtgait.core, rtgait.core.analysis.rollout, rtgait.core.lipm.pattern\n"
        f"bad = sorted(m for m in sys.modules if m.split('.')[0] in {FORBIDDEN!r} or m.startswith({FORBIDDEN!r}))\n"
        "print(','.join(bad))\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == ""
