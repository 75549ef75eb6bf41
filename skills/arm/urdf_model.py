"""The Pinocchio model of the controlled chain, built from URDF text: every joint but the
controlled ones locked at a fixed value, so one model serves the bare arm and the whole robot.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pinocchio as pin


def reduced_model(full: pin.Model, joints: Sequence[str], fixed: dict[str, float]) -> pin.Model:
    """The model with every joint but ``joints`` locked, so that ``q`` holds the controlled joints only.

    Args:
        full: the model of the whole URDF.
        joints: the controlled joints' names (1-DoF revolute or prismatic).
        fixed: positions for uncontrolled 1-DoF joints; the others stay at their neutral position,
            clipped into their limits.

    Returns:
        The reduced model (``full`` itself when nothing is locked).

    Raises:
        ValueError: a controlled joint is not 1-DoF revolute or prismatic, or a ``fixed`` entry
            names a controlled, unknown or multi-coordinate joint or has a non-finite value.
    """
    for name in joints:
        joint = full.joints[full.getJointId(name)]
        if joint_kind(joint) is None:
            raise ValueError(f"joints: {name!r} is a {joint.shortname()}, not a 1-DoF revolute or prismatic joint "
                             "with limits (continuous joints are not supported)")
    reference = pin.neutral(full)
    for name, value in fixed.items():
        if name not in full.names or name in joints:
            raise ValueError(f"fixed: {name!r} is not an uncontrolled joint of the URDF")
        joint_id = full.getJointId(name)
        if full.joints[joint_id].nq != 1:
            raise ValueError(f"fixed: {name!r} has {full.joints[joint_id].nq} position coordinates, not 1")
        if not math.isfinite(value):
            raise ValueError(f"fixed: {name!r} = {value!r} is not finite")
        reference[full.idx_qs[joint_id]] = value
    bounded = np.isfinite(full.lowerPositionLimit) & np.isfinite(full.upperPositionLimit)
    reference[bounded] = np.clip(reference[bounded], full.lowerPositionLimit[bounded],
                                 full.upperPositionLimit[bounded])
    locked = [j for j in range(1, full.njoints) if full.names[j] not in joints]
    return pin.buildReducedModel(full, locked, reference) if locked else full


def joint_kind(joint: pin.JointModel) -> str | None:
    """What a joint does to the chain, for the reach bound and for which joints can be controlled.

    Args:
        joint: a Pinocchio joint model.

    Returns:
        "revolute" or "prismatic" for a 1-DoF joint of that kind, else None.
    """
    if joint.nq != 1 or joint.nv != 1:
        return None
    name = joint.shortname()
    if name.startswith("JointModelR"):
        return "revolute"
    if name.startswith("JointModelP"):
        return "prismatic"
    return None
