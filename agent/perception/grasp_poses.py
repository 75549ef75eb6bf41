"""Where the gripper goes: TCP poses on a handle, along an opening, and on top of an object.

TCP convention (what the kinematics takes as targets). A TCP pose is a 4x4 world transform whose
rotation columns are the gripper's axes:

- z (approach) = -normal: the gripper comes at the front from outside, pointing into it;
- x = the handle's axis: the bar lies along x, between the fingers;
- y = z × x: the fingers close along y, across the bar;
- the origin is the grasp point: the centre of the handle's points.

The grasp is symmetric under a half turn about z (x, y -> -x, -y); an arm may take whichever of
the two suits its joint limits. Along an opening, the TCP rides with the part: a drawer's TCP keeps
its orientation and moves along the normal; a door's TCP turns with the door about the hinge.
"""

from __future__ import annotations

import math

import numpy as np

from agent.perception.directions import GeometryError, checked_points, unit_vector
from agent.perception.part_geometry import PartGeometry
from agent.perception.part_motion import part_motion

#: The paper's revolute step, and ours for drawers (2 cm), when no step count is given.
DOOR_STEP_RAD = math.radians(5.0)
DRAWER_STEP_M = 0.02
#: Pre-grasp stand-off along the normal (the paper's 3 cm).
PREGRASP_M = 0.03


def grasp_rotation(geometry: PartGeometry) -> np.ndarray:
    """The TCP orientation at the handle, fingers across the bar.

    Args:
        geometry: the part whose handle is grasped.

    Returns:
        A 3x3 rotation: columns x = handle axis, y = z × x, z = -normal.
    """
    z = -geometry.normal
    x = unit_vector(geometry.handle_axis - (geometry.handle_axis @ z) * z, "handle_axis")
    return np.column_stack([x, np.cross(z, x), z])


def grasp_pose(geometry: PartGeometry) -> np.ndarray:
    """The TCP pose closing on the handle (see the module docstring for the axes).

    Args:
        geometry: the part whose handle is grasped.

    Returns:
        A 4x4 world-frame TCP pose at the grasp point.
    """
    return _pose(grasp_rotation(geometry), geometry.handle_point)


def pregrasp_pose(geometry: PartGeometry, standoff_m: float = PREGRASP_M) -> np.ndarray:
    """Where the approach to the handle starts: the grasp pose backed off along the normal.

    Args:
        geometry: the part whose handle is grasped.
        standoff_m: how far in front of the handle.

    Returns:
        A 4x4 world-frame TCP pose.
    """
    return _pose(grasp_rotation(geometry), geometry.handle_point + standoff_m * geometry.normal)


def opening_waypoints(geometry: PartGeometry, amount: float, n: int | None = None) -> list[np.ndarray]:
    """TCP poses that open the part, riding with it: a door's TCP turns with the door, so the
    fingers stay across the bar.

    Args:
        geometry: the part as seen before this motion.
        amount: radians for a door (about ``hinge_axis``), metres for a drawer (along ``normal``);
            a negative amount moves the other way (closing a part whose geometry was taken
            while it stood open).
        n: how many steps of equal size; by default 5° or 2 cm per step.

    Returns:
        n + 1 poses (4x4) from `grasp_pose` to the part opened by ``amount``.

    Raises:
        GeometryError: ``n`` is not a positive whole number.
    """
    steps = _steps(geometry, amount, n)
    start = grasp_pose(geometry)
    poses = []
    for value in np.linspace(0.0, amount, steps + 1):
        poses.append(part_motion(geometry, float(value)) @ start)
    return poses


def closing_waypoints(geometry: PartGeometry, amount: float, n: int | None = None) -> list[np.ndarray]:
    """TCP poses that close the part again: `opening_waypoints` reversed.

    Args:
        geometry: the part as seen closed (what `part_geometry` measured before opening it).
        amount: how far it stands open (see `opening_waypoints`).
        n: how many steps of equal size; by default 5° or 2 cm per step.

    Returns:
        Poses (4x4) from the part opened by ``amount`` back to closed.
    """
    return opening_waypoints(geometry, amount, n)[::-1]


def top_grasp_point(points: np.ndarray, band_m: float = 0.01) -> np.ndarray:
    """The paper's top-down pick point, where a gripper coming from above first closes.

    Args:
        points: (N, 3) points of the object, at least 1.
        band_m: how far below the highest point still counts as its top.

    Returns:
        The mean of the points within ``band_m`` of the highest.
    """
    pts = checked_points(points, "points", minimum=1)
    return pts[pts[:, 2] >= pts[:, 2].max() - band_m].mean(axis=0)


#: The least a thing spans on any axis (m): two of the memory's voxels. A thing in a drawer is
#: seen from above only, its sides behind the drawer's, and its points lie in one layer; it still
#: stands some height, which a pick needs for how deep to grasp and how high to lift (recursive
#: 1039 of tuning-wide). Guessed low, the lowering that puts it down stops on what it meets first.
LEAST_EXTENT_M = 0.02


def seen_extent(points: np.ndarray, least_m: float = LEAST_EXTENT_M) -> np.ndarray:
    """The size of the box around an object's points, as a pick takes it.

    Args:
        points: (N, 3) points of the object, at least 1.
        least_m: the least it spans along each axis.

    Returns:
        (dx, dy, dz), each at least ``least_m``.
    """
    pts = checked_points(points, "points", minimum=1)
    return np.maximum(np.ptp(pts, axis=0), least_m)


#: How far (m) below an object's lowest seen point what it stands on is sought, and how far in from
#: the edges of its footprint (a voxel: not the walls beside it).
SUPPORT_BELOW_M, SUPPORT_INSET_M = 0.2, 0.01


def standing_extent(points: np.ndarray, others: np.ndarray | None, least_m: float = LEAST_EXTENT_M,
                    floor_z: float | None = None, stands_on_z: float | None = None) -> np.ndarray:
    """`seen_extent`, its height reaching down to what the object stands on.

    From the robot's cameras an object's lower part is often hidden (a box standing in a cabinet,
    seen over the cabinet's floor from above, was remembered 7 cm tall of its 13); below it stands
    what it stands on, and the object reaches down to that: the highest of ``others`` under its
    footprint (`SUPPORT_INSET_M` in from its edges), lower than its lowest seen point by at most
    `SUPPORT_BELOW_M`, and no lower than ``floor_z``. Where nothing is seen there, the seen extent.

    Args:
        points: (N, 3) points of the object, at least 1.
        others: (M, 3) points of everything else, the surface it may stand on among them, or None.
        least_m: as for `seen_extent`.
        floor_z: the top of the table or counter the object stands on, which it reaches no lower
            than: a box standing over a table's corner, its top hiding the top under it, reached
            down to the leg seen below and was taken 23 cm tall of its 10; put down by that height,
            its voxels were carried 12 cm over where it stood, and the few the next view did not
            look through drew its top, and the pick back's grasp, 9 cm aside (recursive 1250 of
            tuning-wide). None: no such bound.
        stands_on_z: the top of what the object is seen to stand on (a drawer's floor showing
            around it, `drawer_floor`), down to which it reaches whatever the memory has under it;
            None: sought among ``others``.

    Returns:
        (dx, dy, dz), each at least ``least_m``.
    """
    pts = checked_points(points, "points", minimum=1)
    extent = seen_extent(pts, least_m)
    if stands_on_z is not None:
        extent[2] = max(float(pts[:, 2].max() - stands_on_z), least_m)
        return extent
    if others is None or not len(others):
        return extent
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    near = np.asarray(others, dtype=float).reshape(-1, 3)
    across = np.all((near[:, :2] >= lo[:2] + SUPPORT_INSET_M) & (near[:, :2] <= hi[:2] - SUPPORT_INSET_M), axis=1)
    under = across & (near[:, 2] < lo[2]) & (near[:, 2] >= lo[2] - SUPPORT_BELOW_M)
    if not np.any(under):
        return extent
    support = float(near[under, 2].max()) if floor_z is None else max(float(near[under, 2].max()), floor_z)
    extent[2] = max(float(hi[2] - support), least_m)
    return extent


#: How far (m) around an object's footprint the floor of a drawer it stands in is sought, and how
#: far a level of the drawer's points must spread both ways to be its floor (not its front or sides).
FLOOR_AROUND_M, FLOOR_SPREAD_M = 0.04, 0.03


def drawer_floor(points: np.ndarray, drawer: np.ndarray) -> tuple[float, bool] | None:
    """How low an object standing in an open drawer reaches: down to the drawer's floor where that
    shows around it (`FLOOR_AROUND_M`) below its lowest seen point, else no lower than the
    drawer's lowest point. Seen from above in a drawer, a box shows only its top, and what the
    memory has under its footprint was seen there before the drawer was pulled out over it: a box
    5 cm tall reached down to the drawer below and was taken 17 cm tall (recursive 1264 of
    tuning-wide), one 14 cm tall 28 (recursive 1103), and one 7 cm tall, with nothing under it,
    2 (recursive 1279).

    Args:
        points: (N, 3) points of the object, at least 1.
        drawer: (M, 3) points of the drawer, as it stands now.

    Returns:
        (height, seen): the floor's top and True, or the drawer's lowest point and False; None
        where the object does not stand in the drawer (its middle outside the drawer's footprint,
        or its lowest point not below the drawer's highest: on the chest's top).
    """
    pts = checked_points(points, "points", minimum=1)
    near = np.asarray(drawer, dtype=float).reshape(-1, 3)
    if not len(near):
        return None
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    middle = (lo[:2] + hi[:2]) / 2
    if np.any(middle < near[:, :2].min(axis=0)) or np.any(middle > near[:, :2].max(axis=0)) \
            or lo[2] >= near[:, 2].max():
        return None
    around = np.all((near[:, :2] >= lo[:2] - FLOOR_AROUND_M) & (near[:, :2] <= hi[:2] + FLOOR_AROUND_M), axis=1)
    below = near[around & (near[:, 2] < lo[2])]
    heights = np.round(below[:, 2], 3)
    levels, counts = np.unique(heights, return_counts=True)
    # the floor is a layer: of the levels that spread both ways, the one with the most points (a
    # front and a side wall near the object spread both ways too, a line each)
    spread = [np.all(np.ptp(below[heights == level][:, :2], axis=0) >= FLOOR_SPREAD_M) for level in levels]
    if any(spread):
        return float(levels[np.flatnonzero(spread)[np.argmax(counts[spread])]]), True
    return float(near[:, 2].min()), False


def _steps(geometry: PartGeometry, amount: float, n: int | None) -> int:
    if n is not None:
        if int(n) != n or n < 1:
            raise GeometryError(f"n: {n!r} must be a positive number of steps")
        return int(n)
    step = DOOR_STEP_RAD if geometry.kind == "door" else DRAWER_STEP_M
    return max(1, math.ceil(abs(amount) / step - 1e-9))


def _pose(rotation: np.ndarray, position: np.ndarray) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = rotation, position
    return pose
