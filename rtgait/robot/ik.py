"""Whole-body inverse kinematics for walking, one control tick at a time.

In the spirit of Resolved Momentum Control (Kajita et al. 2003): the walking pattern prescribes the COG and
both feet; the whole body (free-floating base, legs, torso) follows with every other joint locked at the
half-sitting posture. Tasks, all in the world frame:

* COG position (x, y, z), m;
* each sole frame's position and orientation: the planned (x, y, z) and yaw, sole level, or tilted by the
  target's pitch and roll when it has them (``(x, y, z, yaw, pitch, roll)``: the sole on a sloped foothold,
  ``Rz(yaw) Ry(pitch) Rx(roll)``) (6 per foot);
* torso orientation: upright, heading along the mean yaw of the feet (3);
* pelvis (floating base) orientation: likewise, with a small weight (3).

Both upright orientations may be tilted together by a lean (``IKTargets.lean``, the hip strategy): the upper body
then turns about the hips while the COM and the soles stay on their targets.

The pelvis task is compatible with the others (the torso joints connect an upright pelvis to an upright torso);
without it the solution that bends the joints least from half-sitting leans the pelvis back by about 8 degrees
and pitches the torso joint forward to compensate, a posture no walking robot uses. That makes 21 equations for
the 6 + n_moving unknowns (20 for Talos), consistent whenever the targets are reachable.

Each iteration is one damped, weighted Gauss-Newton step on the reduced model: the task Jacobians at the
current configuration are stacked into ``J`` and ``(J^T W J + D) dq = J^T W e + mu (q_posture - q)`` is solved
by a Cholesky factorisation (LAPACK ``dposv``). ``D`` is a small damping (it keeps the steps bounded near
singular legs, knees stretched) plus the tiny posture weight ``mu``, which pulls the joints toward half-sitting
in whatever freedom the tasks leave.

Joint limits are never left. With a barrier (``IKWeights.limit > 0``: ``SMOOTH_LIMITS``, for a reference that feeds
forward torques) they are also approached smoothly: within ``limit_margin`` of a limit ``k d^3 / 3`` (``d`` the depth
into that band, rad) joins the cost; its gradient ``k d^2`` and curvature ``2 k d``
grow from zero at the band's edge, so the solution stays continuous in the targets with a continuous rate: a joint
that the tasks drive toward its limit slows down over the band and the other joints take over the task gradually.
A hard stop instead (the joint pinned where it would cross, the rest re-solved) moves the other joints in one tick,
a step in the reference's velocity whose difference is a burst of acceleration in the feed-forward torques. Without
the barrier (the default), and as its backstop, a step that would cross a limit is solved again with those joints
pinned at the limit, and the result is clipped.

The solver is warm-started from the previous tick; since the targets move by millimetres per tick, one iteration
leaves errors of micrometres, and more iterations are made (up to ``max_iterations``) only while an error is above
the tolerance.

The weights of the tasks and the errors a solution leaves in them are in :mod:`rtgait.robot.ik_terms`; the rotation
errors of the orientation tasks in :mod:`rtgait.robot.rotation_errors`.

Kinematics and Jacobians at a configuration are computed once (one ``computeJointJacobians``, then the COG
Jacobian and the frame Jacobians, which reuse it) and kept: the evaluation that measures the errors of the
returned solution is reused by the next tick's first step when it starts from that solution.
"""

from __future__ import annotations

import math
from operator import gt as _gt
from operator import lt as _lt

import numpy as np
import pinocchio as pin
from scipy.linalg.lapack import dposv

from rtgait.core.geometry.footsteps import mean_heading
from rtgait.interface.task_targets import IKTargets
from rtgait.robot.ik_terms import IKErrors, IKWeights
from rtgait.robot.model import RobotModel
from rtgait.robot.rotation_errors import _floats, _foot_error, _leaned_yaw_error

__all__ = ["IKTargets", "WholeBodyIK"]

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
# Rows of the stacked task vector: COG 0:3, left foot 3:9 (position 3:6, orientation 6:9), right foot 9:15,
# torso orientation 15:18, pelvis orientation 18:21.
_N_TASKS = 21
_dot, _fromiter, _concatenate = np.dot, np.fromiter, np.concatenate
_LAST_ROW = [0.0, 0.0, 0.0, 1.0]  # of a homogeneous matrix
# The calls of an evaluation, bound once.
_joint_jacobians, _com_jacobian = pin.computeJointJacobians, pin.jacobianCenterOfMass
_frame_jacobian = pin.getFrameJacobian


class WholeBodyIK:
    """Tick-by-tick whole-body IK on a robot's reduced model (see the module docstring).

    Args:
        robot: the loaded robot.
        weights: least-squares weights.
        max_iterations: Gauss-Newton iterations per tick at most.
        tolerance: iterate while any position error exceeds this (m); orientation errors are compared with
            ``10 * tolerance`` rad (1 mrad per 0.1 mm: a 0.1 m lever). 0 makes every iteration, which gives a
            trajectory whose residual errors vary smoothly (for finite differences).
        max_step: largest norm of one iteration's step (rad and m together); bounds the first steps from far
            away, irrelevant while tracking.
    """

    def __init__(
        self,
        robot: RobotModel,
        weights: IKWeights | None = None,
        max_iterations: int = 3,
        tolerance: float = 1e-6,
        max_step: float = 0.2,
    ) -> None:
        if max_iterations < 1:
            raise ValueError(f"max_iterations must be >= 1, got {max_iterations}")
        if not (math.isfinite(tolerance) and tolerance >= 0.0):
            raise ValueError(f"tolerance must be >= 0 m, got {tolerance}")
        if not (math.isfinite(max_step) and max_step > 0.0):
            raise ValueError(f"max_step must be > 0 rad, got {max_step}")
        self.robot = robot
        self.model = robot.model
        self.data = robot.model.createData()
        self.weights = weights or IKWeights()
        self.max_iterations = max_iterations
        self.tolerance = tolerance
        self.max_step = max_step

        model = self.model
        nv = model.nv
        if model.nq != nv + 1 or model.joints[1].nv != 6:
            # Every joint after the free flyer must have one coordinate (checked by the description loader);
            # the joint part of q and of v then line up one to one: q[7:] <-> v[6:].
            raise ValueError("the reduced model must be a free flyer followed by one-coordinate joints")
        self._lower = model.lowerPositionLimit[7:].copy()
        self._upper = model.upperPositionLimit[7:].copy()
        w = self.weights
        task_weights = (
            [w.cog] * 3 + ([w.foot_position] * 3 + [w.foot_orientation] * 3) * 2 + [w.torso] * 3 + [w.pelvis] * 3
        )
        self._w = np.array(task_weights)
        # Per-tick buffers. W J is formed as one same-shape product (a broadcast product on the transposed J costs
        # three times more) and read transposed: J^T W is the same numbers in the same memory layout as J.T * w.
        self._w_rows = np.repeat(self._w[:, None], nv, axis=1)
        self._wj = np.empty((_N_TASKS, nv))
        self._jtw = self._wj.T
        diagonal = np.full(nv, w.damping)
        diagonal[6:] += w.posture
        self._damping = np.diag(diagonal)
        # The posture pull mu (q_posture - q) on the joint rows: mu q_posture, and mu.
        self._pull_tail = w.posture * robot.q_half_sitting[7:]
        self._posture = w.posture
        self._max_step2 = max_step * max_step
        self._lower_list, self._upper_list = self._lower.tolist(), self._upper.tolist()
        if not (math.isfinite(w.limit) and w.limit >= 0.0):
            raise ValueError(f"the limit barrier's curvature must be >= 0 per rad^2, got {w.limit}")
        if not (math.isfinite(w.limit_margin) and w.limit_margin > 0.0):
            raise ValueError(f"the limit barrier's margin must be > 0 rad, got {w.limit_margin}")
        # The barrier's band: limit_margin inside each limit, at most half a joint's range (the bands never overlap).
        margin = np.minimum(w.limit_margin, 0.5 * (self._upper - self._lower))
        self._band_lower, self._band_upper = self._lower + margin, self._upper - margin
        self._band_lower_list, self._band_upper_list = self._band_lower.tolist(), self._band_upper.tolist()
        self._barrier_k = w.limit / (2.0 * margin)  # k: curvature 2 k d reaches `limit` at the limit (d = margin)
        self._barrier = w.limit > 0.0
        J = self._J = np.zeros((_N_TASKS, nv))
        # Views of J's task blocks, written in place at each evaluation.
        self._j_blocks = (J[0:3], J[3:9], J[9:15], J[15:18], J[18:21, 3:6])
        self._frames = (robot.left_sole_id, robot.right_sole_id, robot.torso_id)
        self._e: list[float] = [0.0] * _N_TASKS

        data = self.data
        pin.framesForwardKinematics(model, data, robot.q_half_sitting)
        # "Upright" is the torso's and the pelvis's orientation at half-sitting (feet heading +x), turned by the
        # walking yaw.
        self._torso_rest_t = data.oMf[robot.torso_id].rotation.T.copy()
        self._pelvis_rest_t = data.oMi[1].rotation.T.copy()
        self._cached_q: np.ndarray | None = None
        # Views of what the kinematics rewrite in place in the data (its vectors keep their size): the COM, the
        # pelvis's and the torso's rotations, and each sole's translation and rotation (column-major, flattened
        # without a copy), read without a call into Pinocchio at each evaluation.
        soles = [data.oMf[robot.left_sole_id], data.oMf[robot.right_sole_id]]
        feet = [part for sole in soles for part in (sole.translation, sole.rotation.T.reshape(9))]
        self._views = (data.com[0], data.oMi[1].rotation, data.oMf[robot.torso_id].rotation, feet)
        self._feet_values = np.empty(24)
        self._com: list[float] = []
        self._left: list[list[float]] = []
        self._right: list[list[float]] = []
        self._torso: list[list[float]] = []
        self._pelvis: list[list[float]] = []

    # ----- kinematics at one configuration ----------------------------------------------------------------------

    def _evaluate(self, q: np.ndarray) -> None:
        """Kinematics, task Jacobians and frame placements at ``q``, kept until the next evaluation."""
        model, data = self.model, self.data
        j_com, j_left, j_right, j_torso, j_pelvis = self._j_blocks
        left_id, right_id, torso_id = self._frames
        _joint_jacobians(model, data, q)
        # After computeJointJacobians, the COG Jacobian and the frame Jacobians reuse the joint Jacobians; each
        # frame Jacobian call also updates that frame's placement in data.oMf.
        j_com[...] = _com_jacobian(model, data, False)
        j_left[...] = _frame_jacobian(model, data, left_id, _LWA)
        j_right[...] = _frame_jacobian(model, data, right_id, _LWA)
        j_torso[...] = _frame_jacobian(model, data, torso_id, _LWA)[3:6]
        # The free flyer's angular velocity is in the pelvis frame: world-aligned, its Jacobian is [0, R, 0].
        com, pelvis, torso, feet = self._views
        j_pelvis[...] = pelvis
        # Plain Python floats from here on: the error arithmetic is a few dozen scalar operations, which costs
        # less in Python than the per-call overhead of numpy on 3x3 arrays.
        self._com = com.tolist()
        # The soles' placements as the rows of their homogeneous matrices, from one concatenation of the views.
        p = _concatenate(feet, out=self._feet_values).tolist()
        self._left = [[p[3], p[6], p[9], p[0]], [p[4], p[7], p[10], p[1]], [p[5], p[8], p[11], p[2]], _LAST_ROW]
        self._right = [
            [p[15], p[18], p[21], p[12]], [p[16], p[19], p[22], p[13]], [p[17], p[20], p[23], p[14]], _LAST_ROW
        ]  # fmt: skip
        # The torso relative to its upright rest orientation: the torso task becomes "this rotation is a yaw".
        # np.dot: the same BLAS product as @ for these small operands, with less of numpy's dispatch around it.
        self._torso = _dot(torso, self._torso_rest_t).tolist()
        self._pelvis = _dot(pelvis, self._pelvis_rest_t).tolist()
        self._cached_q = q

    def _errors(self, targets: IKTargets) -> list[float]:
        """Fill the stacked task error (target minus current) and return the norms of its 7 groups."""
        cog, left, right, lean = targets
        cog, left, right = _floats(cog), _floats(left), _floats(right)
        com, hl, hr = self._com, self._left, self._right
        cos, sin = math.cos, math.sin
        left_yaw, right_yaw = left[3], right[3]
        yaw = mean_heading(left_yaw, right_yaw)  # the torso's and pelvis's heading
        c, s = cos(yaw), sin(yaw)
        e = [
            cog[0] - com[0], cog[1] - com[1], cog[2] - com[2],
            left[0] - hl[0][3], left[1] - hl[1][3], left[2] - hl[2][3],
            *_foot_error(hl, left, left_yaw),
            right[0] - hr[0][3], right[1] - hr[1][3], right[2] - hr[2][3],
            *_foot_error(hr, right, right_yaw),
            *_leaned_yaw_error(self._torso, c, s, lean),
            *_leaned_yaw_error(self._pelvis, c, s, lean),
        ]  # fmt: skip
        self._e = e
        hypot = math.hypot
        return [hypot(e[0], e[1], e[2]), hypot(e[3], e[4], e[5]), hypot(e[6], e[7], e[8]),
                hypot(e[9], e[10], e[11]), hypot(e[12], e[13], e[14]), hypot(e[15], e[16], e[17]),
                hypot(e[18], e[19], e[20])]  # fmt: skip

    # ----- one Gauss-Newton step -------------------------------------------------------------------------------

    def _step(self, q: np.ndarray) -> np.ndarray:
        """One damped Gauss-Newton step from ``q`` (whose kinematics are evaluated) within the joint limits."""
        J, JtW = self._J, self._jtw
        np.multiply(J, self._w_rows, out=self._wj)  # J^T W, through its view self._jtw
        H = JtW @ J
        H += self._damping
        # The posture pull weight * (q_posture - q) on the joint rows (the free flyer's have none).
        g = _dot(JtW, _fromiter(self._e, np.float64, _N_TASKS))
        q_joints = q[7:]
        g[6:] += self._pull_tail - self._posture * q_joints
        if self._barrier and _outside(q_joints.tolist(), self._band_lower_list, self._band_upper_list):
            self._add_barrier(q_joints, H, g)
        _, dq, info = dposv(H, g)
        if info != 0:  # pragma: no cover - H is symmetric positive definite by construction (damping > 0)
            raise np.linalg.LinAlgError(f"the IK normal equations are not positive definite (LAPACK info {info})")
        size2 = float(_dot(dq, dq))
        if size2 <= self._max_step2:
            # Joint coordinates add exactly (q[7:] + dq[6:], one-coordinate joints): the integrated configuration's
            # joints are the step's, and a step inside the limits (the usual case) is taken as it is.
            q_new = pin.integrate(self.model, q, dq)
            if not _outside(q_new.tolist()[7:], self._lower_list, self._upper_list):
                return q_new
        joints = q_joints + dq[6:]
        pinned = np.maximum(self._lower - joints, joints - self._upper).max() > 0.0
        if pinned:
            dq = self._pinned_step(q, joints, H, g)
            size2 = float(_dot(dq, dq))
        if size2 > self._max_step2:
            dq *= math.sqrt(self._max_step2 / size2)
        q_new = pin.integrate(self.model, q, dq)
        if pinned:
            # A step that passed the check above stays inside the limits; a pinned solve holds its joints at the
            # limit to about 1e-6 of the step, and clipping removes that residue.
            np.clip(q_new[7:], self._lower, self._upper, out=q_new[7:])
        return q_new

    def _add_barrier(self, q_joints: np.ndarray, H: np.ndarray, g: np.ndarray) -> None:
        """Add the Newton terms of the joint-limit barrier ``k d^3 / 3`` to ``H`` and ``g`` (module docstring).

        ``d`` is the depth into the band below the upper limit (cost gradient ``+k d^2``) or above the lower one
        (``-k d^2``); ``g`` is the negative gradient, ``H`` gets the curvature ``2 k d``.
        """
        above = q_joints - self._band_upper
        below = self._band_lower - q_joints
        depth = np.maximum(np.maximum(above, below), 0.0)
        inside = np.flatnonzero(depth)
        d, k = depth[inside], self._barrier_k[inside]
        rows = inside + 6
        H[rows, rows] += 2.0 * k * d
        g[rows] -= np.where(above[inside] > 0.0, 1.0, -1.0) * k * d * d

    def _pinned_step(self, q: np.ndarray, joints: np.ndarray, H: np.ndarray, g: np.ndarray) -> np.ndarray:
        """The step re-solved with every joint that would cross a limit pinned at that limit.

        Clipping alone would leave the other joints' share of the step computed for a motion the pinned joints
        no longer make; a stiff diagonal term holds each pinned joint's step at its distance to the limit.
        """
        below, above = joints < self._lower, joints > self._upper
        pinned = np.flatnonzero(below | above)
        limit = np.where(below, self._lower, self._upper)[pinned]
        stiff = 1e6 * (1.0 + np.abs(H).max())
        rows = pinned + 6
        H[rows, rows] += stiff
        g[rows] += stiff * (limit - q[pinned + 7])
        _, dq, _ = dposv(H, g)
        return dq

    # ----- public ----------------------------------------------------------------------------------------------

    def solve(
        self,
        targets: IKTargets,
        q_previous: np.ndarray,
        max_iterations: int | None = None,
        tolerance: float | None = None,
        errors: bool = True,
    ) -> tuple[np.ndarray, IKErrors | None]:
        """Configuration of the reduced model reaching ``targets``, starting from ``q_previous``.

        Args:
            targets: COG and feet targets (world frame, m and rad).
            q_previous: the previous tick's solution (or the half-sitting configuration to start), shape (nq,).
                Not modified.
            max_iterations: overrides the solver's setting for this call (e.g. many on the first tick).
            tolerance: overrides the solver's tolerance for this call (m); 0 makes every iteration.
            errors: whether to return the task errors; ``False`` skips measuring them after the last iteration,
                which nothing else needs (the next call measures its own first), and returns ``None`` for them.

        Returns:
            The new configuration (a new array) and its task errors measured by forward kinematics (or ``None``).
        """
        iterations = self.max_iterations if max_iterations is None else max_iterations
        tol = self.tolerance if tolerance is None else tolerance
        # Orientations: 1 mrad at a 0.1 m lever is 0.1 mm, hence 10x the position tolerance in rad.
        tol_angle = 10.0 * tol
        q = self._cached_q
        # Comparing the bytes is the cheapest exact test that the cached kinematics belong to q_previous.
        if q is None or not isinstance(q_previous, np.ndarray) or q.tobytes() != q_previous.tobytes():
            q = np.array(q_previous, dtype=float)
            if q.shape != (self.model.nq,):
                raise ValueError(f"q_previous must have shape ({self.model.nq},), got {q.shape}")
            self._evaluate(q)
        norms = self._errors(targets)
        done = 0
        while done < iterations and (
            max(norms[0], norms[1], norms[3]) > tol or max(norms[2], norms[4], norms[5]) > tol_angle
        ):
            q = self._step(q)
            self._evaluate(q)
            done += 1
            if done == iterations and not errors:
                break  # the last iteration's errors decide nothing and the caller does not want them
            norms = self._errors(targets)
        # The caller owns the returned array; the cache keeps its own copy so that in-place edits are detected.
        self._cached_q = q.copy()
        return q, (IKErrors(*norms, done) if errors else None)

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """The stacked task Jacobian at ``q`` (a copy), ``(21, nv)``: rows COG 0:3, left sole 3:9 (position, then
        orientation), right sole 9:15, torso orientation 15:18, pelvis orientation 18:21, all world-aligned."""
        self._evaluate(np.array(q, dtype=float))
        return self._J.copy()

    def errors(self, targets: IKTargets, q: np.ndarray) -> IKErrors:
        """Task errors of configuration ``q`` for ``targets``, without solving (m, rad)."""
        self._evaluate(np.array(q, dtype=float))
        return IKErrors(*self._errors(targets), 0)


def _outside(joints: list[float], lower: list[float], upper: list[float]) -> bool:
    """Whether any joint coordinate is below its lower or above its upper limit (scalar comparisons mapped in C:
    cheaper than numpy's calls on a few dozen numbers, and than a Python loop)."""
    return any(map(_lt, joints, lower)) or any(map(_gt, joints, upper))
