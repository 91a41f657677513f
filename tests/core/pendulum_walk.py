"""The pendulum walk the closed-loop and step-adjustment tests share: an HRP-2-like point mass (57 kg, COM 0.8 m
high) on 4 steps of 0.1 m and the closing one with fig8's timing (6.3 s: short enough that the open-loop pendulum
does not diverge from round-off alone before it ends), pushed on step 3."""

from __future__ import annotations

import math

from rtgait.core.geometry.footsteps import SoleRect, Timing
from rtgait.core.lipm.closed_form import GRAVITY
from rtgait.core.planner.online import PlannerConfig, straight_walk

SOLE = SoleRect(front=0.13, back=0.10, inner=0.07, outer=0.07)
MASS = 57.0
ZC = 0.8
W = math.sqrt(GRAVITY / ZC)
CONFIG = PlannerConfig(
    cog_height=ZC, timing=Timing(0.7, 0.1, start=0.8, end=0.8, settle=0.8), connection="quasi-real-time"
)
STRIDES = straight_walk(CONFIG, 4, 0.1)
PUSHED_STEP = 3  # its single support is phase 5, on the left stance footprint F[3]; the right foot swings
