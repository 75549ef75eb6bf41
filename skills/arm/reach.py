"""How far the arm can reach, to reject hopeless IK targets at once instead of after every restart."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from scipy.optimize import lsq_linear

from skills.arm.urdf_model import joint_kind


@dataclass(frozen=True)
class Reach:
    """Where the shoulder can be and how far the TCP can get from it.

    The shoulder is the first controlled revolute joint on the chain to the TCP. Prismatic joints
    above it (the lift) move it over a parallelotope ``base + directions · t``, t ∈ [0, 1]ᵏ; the
    TCP is never further from it than the sum of the link offsets (and prismatic strokes) below it.

    Args:
        base: the shoulder's position with every controlled joint at its lower limit; None when
            the chain has no revolute joint (then nothing is out of reach).
        directions: (3, k) how far each lift above the shoulder moves it over its whole stroke.
        radius: the bound on the TCP's distance from the shoulder (m).
    """

    base: np.ndarray | None
    directions: np.ndarray
    radius: float

    @staticmethod
    def of(model: pin.Model, frame_id: int, joint_names: Sequence[str], lower: np.ndarray, upper: np.ndarray,
           full_configuration: Callable[[np.ndarray], np.ndarray]) -> Reach:
        """The reach of the chain from the root to a frame.

        Args:
            model: the (reduced) model.
            frame_id: the TCP frame's id in ``model``.
            joint_names: the controlled joints, in the order of ``q``.
            lower: their lower limits.
            upper: their upper limits.
            full_configuration: the model configuration for a controlled ``q``.

        Returns:
            The reach; unbounded when no controlled revolute joint is on the chain.
        """
        frame = model.frames[frame_id]
        chain = []
        joint = frame.parentJoint
        while joint > 0:
            chain.append(joint)
            joint = model.parents[joint]
        chain.reverse()
        controlled = {model.getJointId(name): i for i, name in enumerate(joint_names)}
        revolute = [j for j in chain if j in controlled and joint_kind(model.joints[j]) == "revolute"]
        if not revolute:
            return Reach(None, np.zeros((3, 0)), math.inf)
        shoulder = revolute[0]
        below = chain[chain.index(shoulder) + 1:]
        radius = float(np.linalg.norm(frame.placement.translation))
        for j in below:
            radius += float(np.linalg.norm(model.jointPlacements[j].translation))
            if joint_kind(model.joints[j]) == "prismatic":
                radius += float(np.max(np.abs([model.lowerPositionLimit[model.idx_qs[j]],
                                               model.upperPositionLimit[model.idx_qs[j]]])))
        lifts = [controlled[j] for j in chain[:chain.index(shoulder)] if j in controlled]
        data = model.createData()

        def shoulder_at(q: np.ndarray) -> np.ndarray:
            pin.forwardKinematics(model, data, full_configuration(q))
            return data.oMi[shoulder].translation.copy()

        q = lower.copy()
        base = shoulder_at(q)
        directions = []
        for i in lifts:
            moved = q.copy()
            moved[i] = upper[i]
            directions.append(shoulder_at(moved) - base)
        return Reach(base, np.array(directions).T.reshape(3, len(lifts)), radius)

    def excess(self, point: np.ndarray) -> tuple[float, float] | None:
        """Whether a point lies beyond reach, and by how much.

        Args:
            point: a position in the model's root frame.

        Returns:
            (distance from the nearest shoulder position, reach) when the point is beyond reach, else None.
        """
        if self.base is None:
            return None
        offset = point - self.base
        k = self.directions.shape[1]
        if k == 0:
            t = np.zeros(0)
        elif k == 1:
            d = self.directions[:, 0]
            squared = float(d @ d)
            t = np.array([np.clip(offset @ d / squared, 0.0, 1.0) if squared > 0 else 0.0])
        else:
            t = lsq_linear(self.directions, offset, bounds=(0.0, 1.0)).x
        distance = float(np.linalg.norm(offset - self.directions @ t))
        return (distance, self.radius) if distance > self.radius + 1e-9 else None
