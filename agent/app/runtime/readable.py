"""Readable one-line texts of blackboard values, for snapshots: what a person wants to see, short.

An observation shows its image size, base pose and label count; a map its extent, cell size and
revision; a pose its x, y and heading; a list its length and last item; an array its shape and
type (or its values, when it holds a few); any other value its ``repr``, cut to one line.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from agent.mapping.occupancy import ExplorationMap
from agent.observation import Observation
from agent.pose import Pose2D

LIMIT = 72


def readable(value: Any) -> str:
    """A one-line description of a blackboard value that stays readable for large objects.

    Args:
        value: the value.

    Returns:
        The description, at most ``LIMIT`` characters.
    """
    return _cut(_text(value))


def _text(value: Any) -> str:
    if isinstance(value, Observation):
        height, width = value.depth.shape[:2]
        return f"{width}×{height} image at {_pose(value.base_pose)}, {len(value.labels)} labels"
    if isinstance(value, ExplorationMap):
        spec = value.spec
        rows, cols = spec.shape
        return (f"map {cols * spec.resolution:.1f}×{rows * spec.resolution:.1f} m from "
                f"({spec.origin_xy[0]:.1f}, {spec.origin_xy[1]:.1f}), cell {spec.resolution:g} m, "
                f"revision {value.revision}")
    if isinstance(value, Pose2D):
        return _pose(value)
    if isinstance(value, np.ndarray):
        if value.size <= 4:
            return f"array {np.round(value, 3).tolist()}"
        return f"array{list(value.shape)} {value.dtype}"
    if isinstance(value, (list, tuple)):
        text = repr(value)
        if len(value) <= 4 and len(text) <= LIMIT:
            return text
        return f"{type(value).__name__} of {len(value)}, last {_text(value[-1])}" if value else text
    if hasattr(value, "__len__") and not isinstance(value, (str, dict, set, frozenset)):
        return f"<{type(value).__name__} of {len(value)}>"
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = ", ".join(f"{field.name}={_cut(_text(getattr(value, field.name)), 24)}"
                           for field in dataclasses.fields(value))
        return f"{type(value).__name__}({fields})"
    return repr(value)


def _pose(pose: Pose2D) -> str:
    return f"({pose.x:.2f}, {pose.y:.2f}, {math.degrees(pose.yaw):.0f}°)"


def _cut(text: str, limit: int = LIMIT) -> str:
    text = " ".join(text.split())
    return text if len(text) <= limit else text[: limit - 1] + "…"
