"""Where nothing may be put down on a table: what its doors and drawers sweep, and the arm's ways to them.

A thing picked away and put down in a door's swing blocks the door it was moved away for; put
down beside the lane to a handle, it holds back the wrist reaching for it. `kept_clear` gives the
points of that space, from what the instance memory holds, for `skills.arm.idle_space.idle_spot` to
keep away from.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping

import numpy as np

from agent.perception.directions import GeometryError
from agent.perception.memory import InstanceMemory
from agent.perception.part_geometry import PartGeometry, handle_geometry
from agent.perception.part_motion import DEFAULT_AMOUNT, part_motion


#: How far to either side of a handle's lane nothing is put down: the wrist and forearm reaching
#: for the handle pass up to ~20 cm beside the hand's own line.
LANE_HALF_WIDTH_M = 0.15
#: How far out of a handle a lane reaches at least, whichever way it faces (m): the hand at its
#: pre-grasp pose 10 cm out and the hand itself behind that. The handle of a door standing open
#: faces aside, away from the robot as often as not, and the hand comes to it from that side all
#: the same. At 0.3 m the lane took the place a box out of a cabinet had gone to and come back
#: from, and it found no way back (recursive 1025 of tuning-wide); at 0.15 m the bottle beside an
#: open door's handle was back in the hand's way (occlusion 1155); at 0.2 m a bottle put down by
#: a door's hinge held the hand backing off the door's handle (occlusion 1092).
LANE_LEAST_M = 0.25
#: Openings sampled along each part's travel, and the spacing of a lane's points (m).
OPENINGS_SAMPLED, LANE_STEP_M = 6, 0.05


def kept_clear(memory: InstanceMemory, eye: np.ndarray, robot_xy: np.ndarray,
               done_with: Collection[int] = (),
               standing_open: Mapping[int, tuple[PartGeometry, float]] | None = None) -> list[np.ndarray]:
    """Point sets (each (N, 3)) of the space every remembered door and drawer with a handle sweeps as
    the skills open it (`DEFAULT_AMOUNT`), and of the lanes its handle is reached along, shut and
    open (a door is closed again from where it stands open): from the handle out the way it faces
    at that opening, as far as the robot at ``robot_xy`` and `LANE_LEAST_M` at least,
    `LANE_HALF_WIDTH_M` to either side. ``eye``: where the parts were seen from (it orients their
    fronts). A part whose geometry cannot be read is left out, and so are the parts ``done_with``:
    opened and shut again, never to be reached for again, their space is the table's like the rest.

    A part standing open (``standing_open``) is where the skill that opened it left it in the
    memory; its sweep is the way back to closed, from the geometry seen closed. Read off its open
    points, it would be swept on from there, and the way it shuts left free: a box out of a
    cabinet was put down in the closing door's way, and the door stopped on it (recursive 1227 of
    tuning-wide).

    Args:
        memory: the remembered instances.
        eye: where the parts were seen from.
        robot_xy: where the robot stands.
        done_with: the memory ids of parts that will not be opened again.
        standing_open: memory id -> (geometry seen closed, how far it stands open) of the parts
            standing open.

    Returns:
        The point sets.
    """
    kept = []
    for handle in memory.with_label("handle"):
        if handle.parent is None or memory.get(handle.parent).id in done_with:
            continue
        part = memory.get(handle.parent)
        opened = (standing_open or {}).get(part.id)
        if opened is not None:
            geometry, open_by = opened
            back = np.linalg.inv(part_motion(geometry, open_by))
            points = part.points() @ back[:3, :3].T + back[:3, 3]
            widest = max(open_by, DEFAULT_AMOUNT[geometry.kind])
        else:
            try:
                geometry = handle_geometry(memory, handle.id, eye, kind=part.label)
            except GeometryError:
                continue
            points, widest = part.points(), DEFAULT_AMOUNT[geometry.kind]
        offsets = np.arange(-LANE_HALF_WIDTH_M, LANE_HALF_WIDTH_M + 1e-9, LANE_STEP_M)
        for amount in np.linspace(0.0, widest, OPENINGS_SAMPLED):
            motion = part_motion(geometry, float(amount))
            kept.append(points @ motion[:3, :3].T + motion[:3, 3])
            handle_at = motion[:3, :3] @ geometry.handle_point + motion[:3, 3]
            facing = motion[:3, :3] @ geometry.normal  # an open door's handle faces aside
            across = np.cross(facing, [0.0, 0.0, 1.0])
            across /= max(float(np.linalg.norm(across)), 1e-9)
            out = max(LANE_LEAST_M, float((np.asarray(robot_xy, dtype=float)[:2] - handle_at[:2]) @ facing[:2]))
            lane = handle_at + np.arange(0.0, out, LANE_STEP_M)[:, None] * facing
            kept.extend(lane + offset * across for offset in offsets)
    return kept


def way_out(point: np.ndarray, half_width: float, robot_xy: np.ndarray, z: float) -> np.ndarray:
    """Points of the lane a thing taken out of storage came out along, for `idle_spot` to keep the
    thing off: from ``point`` (where it stood) straight towards the robot at ``robot_xy``,
    ``half_width`` (m) to either side, at height ``z``. Put down in that lane, in front of the
    cabinet it came from, a box hid the lower half of the smaller box it had covered from the
    robot's cameras and stood in the way of the hand reaching in for it (recursive 1075 of
    tuning-wide).

    Args:
        point: where the thing stood (world; its x, y count).
        half_width: how far to either side of its line the lane reaches (m).
        robot_xy: where the robot stands (world x, y).
        z: the height to give the points (above the surface the lane crosses).

    Returns:
        (N, 3) points, `LANE_STEP_M` apart along and across the lane; none where the robot stands
        at ``point``.
    """
    start = np.asarray(point, dtype=float)[:2]
    toward = np.asarray(robot_xy, dtype=float)[:2] - start
    length = float(np.linalg.norm(toward))
    if length < 1e-6:
        return np.zeros((0, 3))
    toward /= length
    across = np.array([-toward[1], toward[0]])
    along = np.arange(0.0, length, LANE_STEP_M)
    offsets = np.linspace(-half_width, half_width, max(2, int(np.ceil(2 * half_width / LANE_STEP_M)) + 1))
    xy = (start + along[:, None, None] * toward + offsets[None, :, None] * across).reshape(-1, 2)
    return np.column_stack([xy, np.full(len(xy), z)])
