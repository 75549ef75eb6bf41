"""A door or drawer read off its handle's and front's points: RoboEXP's action module (App. D).

Everything the arm needs is taken from perception, not from a model of the furniture:

- the handle's direction is the first principal axis of its points; the paper snaps it to vertical
  when |axis·z| > 0.7 and flattens it to horizontal otherwise;
- the default rule tells the joint from the handle: a **horizontal handle means a drawer**
  (prismatic: pulled straight out), a **vertical handle means a door** (revolute about a vertical
  hinge). It is a convention of furniture makers, not physics: a caller that knows better (a
  detector that says "door" for a bottom-hinged flap with a horizontal handle) passes ``kind``;
  a door with a horizontal handle then turns about a horizontal hinge at the edge farthest from it;
- the opening direction is the most common surface normal of the front near the handle, turned
  towards the robot (the camera): the front faces whoever can see it;
- a door's hinge is on the side of its front farther from the handle (a handle sits near the
  free edge, where it gives the most leverage), along the front's outer face, parallel to the
  handle. Its axis is signed so that opening is a positive rotation about it (right-hand rule)
  that swings the handle outwards, along the normal.

Frames: every point, direction and pose is in the world frame (z up), metres and radians.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from agent.perception.directions import (
    VERTICAL_COS,
    GeometryError,
    checked_points,
    front_normal,
    principal_axis,
    snap_handle_axis,
    unit_vector,
)

if TYPE_CHECKING:
    from agent.perception.memory import InstanceMemory

KINDS = ("door", "drawer")


@dataclass(frozen=True, eq=False)  # arrays inside: compare fields with numpy, not ==
class PartGeometry:
    """A door or drawer as perception sees it (world frame; unit vectors).

    ``handle_point``: centre of the handle's points (the grasp point). ``handle_axis``: the bar's
    direction, snapped vertical (+z) or horizontal. ``normal``: outward front normal, towards the
    robot: the direction a drawer slides out and a door's free edge first moves. For doors,
    ``hinge_point`` is the point of the hinge line level with the handle, on the front's outer
    face, and ``hinge_axis`` the line's direction, signed so that opening is a positive rotation
    about it; both are None for drawers. ``width``: for doors, how far the front reaches from the
    hinge line (to its free edge, a little beyond the handle): the radius of what the door sweeps
    as it swings, which whoever opens it must stand clear of; None when unknown. ``front_depth``:
    how far the front's outer face lies behind the handle point (along -``normal``): the room
    between bar and front that a hand coming down on the bar from above must keep out of; None
    when unknown.

    Raises:
        GeometryError: ``kind`` is not one of `KINDS`, or a door lacks its hinge.
    """

    kind: str
    handle_point: np.ndarray
    handle_axis: np.ndarray
    normal: np.ndarray
    hinge_point: np.ndarray | None = None
    hinge_axis: np.ndarray | None = None
    width: float | None = None
    front_depth: float | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise GeometryError(f"kind: {self.kind!r} is not one of {KINDS}")
        if self.kind == "door" and (self.hinge_point is None or self.hinge_axis is None):
            raise GeometryError("hinge_point, hinge_axis: a door needs both")

    @property
    def joint(self) -> str:
        """'revolute' for doors, 'prismatic' for drawers."""
        return "revolute" if self.kind == "door" else "prismatic"

    @property
    def radius(self) -> float:
        """Distance from the handle to the hinge line (0 for drawers)."""
        if self.hinge_point is None or self.hinge_axis is None:
            return 0.0
        return _distance_to_line(self.handle_point, self.hinge_point, self.hinge_axis)

    @property
    def swing_radius(self) -> float:
        """How far from the hinge line the door's front reaches as it swings: its `width` when seen,
        else the handle's radius (0 for drawers)."""
        return max(self.radius, self.width or 0.0)


def classify_part(handle_axis: np.ndarray, vertical_cos: float = VERTICAL_COS) -> str:
    """The default rule of the module docstring: the handle's direction tells the joint.

    Args:
        handle_axis: the bar's direction.
        vertical_cos: |axis·z| above this counts as vertical.

    Returns:
        'door' for a vertical handle, 'drawer' for a horizontal one.
    """
    return "door" if abs(unit_vector(handle_axis, "handle_axis")[2]) > vertical_cos else "drawer"


def part_geometry(
    handle_points: np.ndarray,
    front_points: np.ndarray,
    toward: np.ndarray,
    kind: str | None = None,
    vertical_cos: float = VERTICAL_COS,
    level: bool = True,
    near_m: float = 0.15,
) -> PartGeometry:
    """The geometry of the door or drawer whose handle and front are given (world frame).

    Args:
        handle_points: (N, 3) points of the handle, at least 2.
        front_points: the moving part's front (its own instance; the parent's points near the
            handle do for the normal, but a door's hinge needs the door's own extent), at least 3.
        toward: where the robot sees from (the camera position), to orient the normal.
        kind: 'door' or 'drawer', overriding the handle rule; None to apply it.
        vertical_cos: the handle snap's threshold (`snap_handle_axis`).
        level: whether the front's normal is levelled (`front_normal`).
        near_m: the normal is taken from the front points within this of the handle (all of
            them if fewer than 10 lie that close).

    Returns:
        The part's geometry; a door's hinge comes from its front's extent.

    Raises:
        GeometryError: too few or bad points, or an unknown ``kind``.
    """
    handle = checked_points(handle_points, "handle_points", minimum=2)
    front = checked_points(front_points, "front_points", minimum=3)
    if kind is not None and kind not in KINDS:
        raise GeometryError(f"kind: {kind!r} is not one of {KINDS}")
    handle_point = handle.mean(axis=0)
    axis = snap_handle_axis(principal_axis(handle), vertical_cos)
    kind = kind or classify_part(axis, vertical_cos)
    near = front[np.linalg.norm(front - handle_point, axis=1) <= near_m]
    around = near if len(near) >= 10 else front
    normal = front_normal(around, toward, level)
    axis = unit_vector(axis - (axis @ normal) * normal, "handle_axis: parallel to the front normal")
    depth = -float(np.median((around - handle_point) @ normal))
    if kind == "drawer":
        return PartGeometry("drawer", handle_point, axis, normal, front_depth=depth)
    hinge_point = hinge_line_point(front, handle_point, axis, normal)
    return PartGeometry("door", handle_point, axis, normal, hinge_point, hinge_axis(handle_point, hinge_point, normal),
                        door_width(front, handle_point, hinge_point, axis, normal), depth)


def hinge_line_point(front_points: np.ndarray, handle_point: np.ndarray, handle_axis: np.ndarray,
                     normal: np.ndarray) -> np.ndarray:
    """Where the hinge line passes level with the handle: the front's edge farther from the handle.

    The front's points are measured across the handle (in the front's plane, perpendicular to the
    bar); the edge is the 1st or 99th percentile, whichever lies farther from the handle, so a few
    stray points do not move it.

    Args:
        front_points: (N, 3) points of the door's front.
        handle_point: the grasp point.
        handle_axis: the bar's direction (unit).
        normal: the front's outward normal (unit).

    Returns:
        The hinge line's point on the front's outer face (median depth along the normal), where
        the hinges of a storage door sit.
    """
    front = checked_points(front_points, "front_points", minimum=3)
    across = unit_vector(np.cross(normal, handle_axis), "handle_axis x normal")
    offsets = (front - handle_point) @ across
    lo, hi = np.percentile(offsets, [1.0, 99.0])
    edge = lo if -lo > hi else hi
    face = float(np.median((front - handle_point) @ normal))
    return handle_point + edge * across + face * normal


def door_width(front_points: np.ndarray, handle_point: np.ndarray, hinge_point: np.ndarray,
               handle_axis: np.ndarray, normal: np.ndarray) -> float:
    """How far a door's front reaches from its hinge line, across the handle: what it sweeps.

    Args:
        front_points: (N, 3) points of the door's front.
        handle_point: the grasp point.
        hinge_point: the hinge line's point (`hinge_line_point`).
        handle_axis: the bar's direction (unit).
        normal: the front's outward normal (unit).

    Returns:
        The 99th percentile of the points' offsets from the hinge line (stray points aside),
        never less than the handle's own offset.
    """
    front = checked_points(front_points, "front_points", minimum=3)
    across = unit_vector(np.cross(normal, handle_axis), "handle_axis x normal")
    toward_handle = 1.0 if (np.asarray(handle_point, float) - hinge_point) @ across >= 0 else -1.0
    offsets = toward_handle * ((front - hinge_point) @ across)
    return float(max(np.percentile(offsets, 99.0), toward_handle * (handle_point - hinge_point) @ across))


def hinge_axis(handle_point: np.ndarray, hinge_point: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """The hinge direction about which a positive rotation swings the handle out along ``normal``.

    With r the in-plane direction from the hinge to the handle, (r, normal, axis) is right-handed:
    axis = r × normal, so axis × r = normal is the handle's initial velocity.

    Args:
        handle_point: the grasp point.
        hinge_point: a point of the hinge line.
        normal: the front's outward normal (unit).

    Returns:
        The signed unit hinge axis.
    """
    r = np.asarray(handle_point, float) - np.asarray(hinge_point, float)
    r = r - (r @ normal) * normal
    return unit_vector(np.cross(unit_vector(r, "handle_point - hinge_point"), normal), "hinge axis")


def handle_geometry(memory: InstanceMemory, handle_id: int, toward: np.ndarray, kind: str | None = None,
                    **options: float | bool) -> PartGeometry:
    """`part_geometry` of a remembered handle and the part it is attached to (its parent).

    Args:
        memory: the instance memory holding the handle.
        handle_id: the handle's instance id.
        toward: where the robot sees from (the camera position).
        kind: 'door' or 'drawer' to override the handle rule.
        **options: further keywords of `part_geometry`.

    Returns:
        The geometry of the handle's part.

    Raises:
        GeometryError: the handle has no parent part, or the points do not determine it.
    """
    handle = memory.get(handle_id)
    if handle.parent is None:
        raise GeometryError(f"handle_id: instance {handle.id} ({handle.label}) has no parent part")
    part = memory.get(handle.parent)
    return part_geometry(handle.points(), part.points(), toward, kind, **options)  # type: ignore[arg-type]


def _distance_to_line(point: np.ndarray, origin: np.ndarray, direction: np.ndarray) -> float:
    d = np.asarray(point, float) - np.asarray(origin, float)
    return float(np.linalg.norm(d - (d @ direction) * direction))
