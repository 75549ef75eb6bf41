"""One damped least-squares IK descent: the inner loop of
`skills.arm.ik_solver.solve_ik`.

The error is world-aligned: the position error p* − p in metres and the rotation error
log3(R* Rᵀ) in radians, so tolerances are plain distances and angles, and a position-only or
free-tool-axis request simply drops or projects rows. The damping follows Sugihara (2011):
λ = ½‖e‖² + λ₀, large far from the target (small, safe steps) and vanishing near it
(Gauss–Newton's fast convergence). Joint limits are enforced every iteration by clamping, with
joints pinned at a limit taken out of the step that would push them past it, so the other joints
keep moving.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Literal

import numpy as np
import pinocchio as pin

IKMode = Literal["pose", "position", "axis"]
"""What IK must match: the full pose; the position only; or the position and the tool axis, leaving
the rotation about that axis free (a symmetric grasp, a top-down pick)."""

IK_MODES = ("pose", "position", "axis")


class IKDescent:
    """One IK target with its weights and tolerances; `run` does one descent towards it.

    Args:
        jacobian_at: for controlled joint positions ``q``, the 6×dof world-aligned Jacobian of the
            TCP and its pose (one kinematics pass).
        lower: the joints' lower limits.
        upper: the joints' upper limits.
        target: the TCP's 4×4 target pose in the root frame.
        mode: what must match (`IKMode`).
        axis: the unit tool axis in the TCP frame ("axis" mode).
        position_weight: the weight of position rows.
        orientation_weight: the weight of rotation rows.
        position_tolerance: converged within this distance (m).
        orientation_tolerance: ... and this angle (rad).
        damping: λ₀.
        max_step: the most any joint moves per iteration.
    """

    def __init__(self, jacobian_at: Callable[[np.ndarray], tuple[np.ndarray, pin.SE3]], lower: np.ndarray,
                 upper: np.ndarray, target: np.ndarray, mode: IKMode, axis: np.ndarray, position_weight: float,
                 orientation_weight: float, position_tolerance: float, orientation_tolerance: float,
                 damping: float, max_step: float) -> None:
        self.jacobian_at, self.lower, self.upper = jacobian_at, lower, upper
        self.mode, self.axis = mode, axis
        self.p_target, self.r_target = target[:3, 3].copy(), target[:3, :3].copy()
        self.axis_target = self.r_target @ axis
        self.wp, self.wr = position_weight, orientation_weight
        self.tol_p, self.tol_r = position_tolerance, orientation_tolerance
        self.damping, self.max_step = damping, max_step

    def cost(self, position_error: float, orientation_error: float) -> float:
        """Which of two failed attempts is better.

        Args:
            position_error: metres from the target.
            orientation_error: radians from it (ignored in "position" mode).

        Returns:
            The errors in units of their tolerances, summed.
        """
        rotation = 0.0 if self.mode == "position" else orientation_error / self.tol_r
        return position_error / self.tol_p + rotation

    def run(self, q: np.ndarray, max_iterations: int) -> tuple[bool, np.ndarray, int]:
        """Descend from ``q`` until converged, stalled (no 1 % progress in 10 steps) or out of steps.

        Args:
            q: the start, within the limits.
            max_iterations: the most steps taken.

        Returns:
            (converged, the last joint positions, iterations used).
        """
        lower, upper = self.lower, self.upper
        best_energy, best_at = math.inf, 0
        for iteration in range(max_iterations):
            jacobian, pose = self.jacobian_at(q)
            error, rows, converged = self._residual(jacobian, pose)
            if converged:
                return True, q, iteration + 1
            energy = 0.5 * float(error @ error)
            if energy < 0.99 * best_energy:
                best_energy, best_at = energy, iteration
            elif iteration - best_at >= 10:
                return False, q, iteration + 1
            step = self._step(rows, error, energy)
            pinned = ((q <= lower) & (step < 0)) | ((q >= upper) & (step > 0))
            if np.any(pinned):  # joints at a limit pushing outward: solve without them
                step = self._step(rows * ~pinned, error, energy)
            largest = float(np.max(np.abs(step)))
            if largest > self.max_step:
                step *= self.max_step / largest
            q = np.clip(q + step, lower, upper)
        jacobian, pose = self.jacobian_at(q)
        return self._residual(jacobian, pose)[2], q, max_iterations

    def _residual(self, jacobian: np.ndarray, pose: pin.SE3) -> tuple[np.ndarray, np.ndarray, bool]:
        """The weighted error e and the matching rows J of the linearisation e(q + dq) ≈ e − J dq."""
        position_error = self.p_target - pose.translation
        close = float(np.linalg.norm(position_error)) <= self.tol_p
        if self.mode == "position":
            return self.wp * position_error, self.wp * jacobian[:3], close
        rotation = pose.rotation
        if self.mode == "pose":
            r_error = self.r_target @ rotation.T
            rotation_error = pin.log3(r_error)
            angle = float(np.linalg.norm(rotation_error))
            rotation_rows = pin.Jlog3(r_error) @ jacobian[3:]
        else:
            axis = rotation @ self.axis
            rotation_error = _rotation_vector(axis, self.axis_target)
            angle = float(np.linalg.norm(rotation_error))
            rotation_rows = (np.eye(3) - np.outer(axis, axis)) @ jacobian[3:]  # spinning about the axis is free
        error = np.concatenate([self.wp * position_error, self.wr * rotation_error])
        rows = np.vstack([self.wp * jacobian[:3], self.wr * rotation_rows])
        return error, rows, close and angle <= self.tol_r

    def _step(self, rows: np.ndarray, error: np.ndarray, energy: float) -> np.ndarray:
        """Levenberg–Marquardt step with Sugihara's damping λ = E + λ₀."""
        normal = rows.T @ rows
        normal[np.diag_indices_from(normal)] += energy + self.damping
        return np.linalg.solve(normal, rows.T @ error)


def _rotation_vector(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation (axis × angle) turning unit vector a onto unit vector b."""
    cross = np.cross(a, b)
    sine = float(np.linalg.norm(cross))
    angle = math.atan2(sine, float(a @ b))
    if sine > 1e-12:
        return cross * (angle / sine)
    if angle < 1.0:
        return np.zeros(3)
    other = np.eye(3)[int(np.argmin(np.abs(a)))]  # opposite: turn about any axis perpendicular to a
    perpendicular = np.cross(a, other)
    return perpendicular / np.linalg.norm(perpendicular) * math.pi
