"""What stands over and around an object a pick lifts: the board of the cabinet it stands in,
the rim of the drawer, and the room they leave (`skills.arm.pick_plans` chooses its grasps and
routes by them; `skills.robot_picks` keeps a thing taken out from under a board out of its way
out). Pure: plain point arrays (``keep_off``: what stands near, neither the object nor what it
stands on), no world.
"""

from __future__ import annotations

import numpy as np

#: How high above its grasp and its release a pick carries an object, unless told.
LIFT_M = 0.15
#: A lift clears what it must by this much (m): the object's own height, a rim.
LIFT_SPARE_M = 0.015
#: How far over the pose above an object (m) a board makes the pick a confined one (`confined`).
CONFINED_M = 0.3
#: What stands within this much (m) around an object's box, up to `RIM_ABOVE_M` over its top, is a
#: rim the object is lifted over before it is carried (`over_the_rim`): the drawer it stands in.
RIM_M, RIM_ABOVE_M = 0.03, 0.08
#: How much further (m) the rim is looked for on the side the object is drawn out by: the front of
#: the drawer a box stood in, 6 cm beyond its near side, which the memory had 2 cm short, hidden
#: behind that front (recursive 1264 of tuning-wide).
RIM_OUT_M = 0.1


def under_a_board(top: np.ndarray, size: np.ndarray, keep_off: np.ndarray | None, lift_m: float = LIFT_M) -> bool:
    """Whether something stands over the object's own top, its top at ``top``, below where it is
    lifted to and `CONFINED_M` over that: over its middle, not only over the hand (`confined`).
    A box held by its near edge in a drawer pulled out from under a closed one stood half under
    that drawer, 10 cm from the hand, and a route taken unchecked lifted it into it (recursive 1039
    of tuning-wide); a cabinet's board 12 cm over a box's top, lower than the lift, did not count
    as over it, and a finger went up into the board (recursive 1043).

    Args:
        top: the middle of the object's top (world).
        size: its box (dx, dy, dz).
        keep_off: (N, 3) points of what stands near, or None.
        lift_m: how high it is to be lifted.

    Returns:
        Whether three or more of ``keep_off`` stand over its footprint there.
    """
    return len(_column(keep_off, top, size[:2] / 2, top[2] + LIFT_SPARE_M, top[2] + lift_m + CONFINED_M)) >= 3


def headroom(top: np.ndarray, size: np.ndarray, keep_off: np.ndarray | None, within: float) -> float:
    """How far over the object's top the lowest thing over its footprint stands: how much room
    a board leaves a hand or a lift there.

    Args:
        top: the middle of the object's top (world).
        size: its box (dx, dy, dz).
        keep_off: (N, 3) points of what stands near, or None.
        within: how far over the top to look (m).

    Returns:
        The height (m) of the lowest such point over the top; inf where none stands within.
    """
    over = _column(keep_off, top, size[:2] / 2, top[2] + LIFT_SPARE_M, top[2] + within)
    return float(over[:, 2].min() - top[2]) if len(over) else np.inf


def too_low_to_lift(top: np.ndarray, size: np.ndarray, keep_off: np.ndarray | None, lift_m: float) -> bool:
    """Whether what stands over the object, its top at ``top``, leaves it no room to be lifted by
    ``lift_m``: three or more of ``keep_off`` over its footprint, lower than that over its top. A
    box covering another cannot be lifted off it where a cabinet's board stands closer over its
    top than its own height, or where its drawer, pulled out, leaves its far side under the
    drawer above: of the 280 recursive tuning-wide variants, 15 nests in cabinets and 17 in
    drawers are refused so (none of them had succeeded; every route was sought at length first).

    Args:
        top: the middle of the object's top (world).
        size: its box (dx, dy, dz).
        keep_off: (N, 3) points of what stands near, or None.
        lift_m: how high it must be lifted at the least.

    Returns:
        Whether that lift would meet what stands over it.
    """
    return len(_column(keep_off, top, size[:2] / 2, top[2] + LIFT_SPARE_M, top[2] + lift_m)) >= 3


def over_the_rim(top: np.ndarray, size: np.ndarray, keep_off: np.ndarray | None,
                 out: np.ndarray | None = None) -> float:
    """How high (m) the object, its top at ``top``, must be lifted for its bottom to clear, by
    `LIFT_SPARE_M`, what stands around it (`RIM_M`, up to `RIM_ABOVE_M` over its top): a box 14
    cm tall in a drawer, lifted the usual 15 cm, was drawn out through the drawer's front, 6 cm
    over its top, and carried back into it the same way (recursive 1050 of tuning-wide). On the
    side it is drawn out by, `RIM_OUT_M` further, what stands lower than the usual lift over its
    top counts too: the front of the drawer a box 5 cm tall stood in rose 13 cm over its top.

    Args:
        top: the middle of the object's top (world).
        size: its box (dx, dy, dz).
        keep_off: (N, 3) points of what stands near, or None.
        out: the level unit vector it is drawn out along (towards the robot), or None.

    Returns:
        The lift (m); 0 where nothing stands around it.
    """
    bottom = float(top[2] - size[2])
    around = _column(keep_off, top, size[:2] / 2 + RIM_M, bottom + LIFT_SPARE_M, top[2] + RIM_ABOVE_M)
    if out is not None and len(ahead := _ahead(keep_off, top, size, out, bottom + LIFT_SPARE_M, top[2] + LIFT_M)):
        around = np.vstack([around, ahead])
    return float(around[:, 2].max() - bottom + LIFT_SPARE_M) if len(around) else 0.0


def over_the_way(top: np.ndarray, place: np.ndarray, size: np.ndarray, keep_off: np.ndarray | None) -> float:
    """How high (m) the object, its top at ``top``, must be lifted above its grasp and its release,
    at ``place``, for its bottom to clear by `LIFT_SPARE_M` what stands between the two, carried
    straight across: the box put down between where a smaller box waited and where it went back
    stood 1.4 cm over that box's bottom, carried the usual 15 cm over the table, and no route
    put the smaller box back (recursive 1217 of tuning-wide). What stands around either end is
    not counted: the rim a thing is lifted over (`over_the_rim`), what it goes down over.

    Args:
        top: the middle of the object's top where it stands (world).
        place: where that point goes (world).
        size: its box (dx, dy, dz).
        keep_off: (N, 3) points of what stands near, or None.

    Returns:
        The lift (m); 0 where nothing stands in the way.
    """
    if keep_off is None or not len(keep_off):
        return 0.0
    points = np.asarray(keep_off, dtype=float).reshape(-1, 3)
    start, end = np.asarray(top, dtype=float), np.asarray(place, dtype=float)
    span = end[:2] - start[:2]
    length = float(np.linalg.norm(span))
    if length < 1e-6:
        return 0.0
    ahead, across, half_along, half_across = _strip(points, start, size, span / length)
    offsets = points[:, :2] - start[:2]
    ends = np.asarray(size[:2], dtype=float) / 2 + RIM_M
    in_way = ((ahead >= -half_along) & (ahead <= length + half_along) & (across <= half_across + RIM_M)
              & np.any(np.abs(offsets) > ends, axis=1) & np.any(np.abs(points[:, :2] - end[:2]) > ends, axis=1))
    if not np.any(in_way):
        return 0.0
    level = start[2] + np.clip(ahead[in_way] / length, 0.0, 1.0) * (end[2] - start[2])  # the carried top's
    return max(0.0, float(np.max(points[in_way, 2] + LIFT_SPARE_M + size[2] - level)))


def _ahead(keep_off: np.ndarray | None, top: np.ndarray, size: np.ndarray, out: np.ndarray, low: float,
           high: float) -> np.ndarray:
    """The points of ``keep_off`` between the heights ``low`` and ``high`` in the strip `RIM_OUT_M`
    long beyond `RIM_M` from the object's side along ``out`` (a level unit vector), as wide as
    the object and `RIM_M` either side (`over_the_rim`)."""
    if keep_off is None or not len(keep_off):
        return np.zeros((0, 3))
    points = np.asarray(keep_off, dtype=float).reshape(-1, 3)
    ahead, across, half_along, half_across = _strip(points, top, size, np.asarray(out, dtype=float)[:2])
    inside = ((ahead > half_along + RIM_M) & (ahead <= half_along + RIM_M + RIM_OUT_M)
              & (across <= half_across + RIM_M) & (points[:, 2] > low) & (points[:, 2] < high))
    return points[inside]


def _strip(points: np.ndarray, top: np.ndarray, size: np.ndarray, along: np.ndarray
           ) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Where ``points`` stand from the object's middle along the level unit vector ``along`` (signed)
    and across it (unsigned), and the object's half extents along and across it: the frame of a
    strip the object is drawn out or carried along (`_ahead`, `over_the_way`)."""
    side = np.array([-along[1], along[0]])
    half = np.abs(np.asarray(size[:2], dtype=float)) / 2
    offsets = points[:, :2] - np.asarray(top, dtype=float)[:2]
    return offsets @ along, np.abs(offsets @ side), float(half @ np.abs(along)), float(half @ np.abs(side))


def confined(pose: np.ndarray, keep_off: np.ndarray | None) -> bool:
    """Whether something stands over a hand's pose within `CONFINED_M` (a cabinet's board over a
    box in it).

    Args:
        pose: the TCP's 4×4 world pose.
        keep_off: (N, 3) points of what stands near, or None.

    Returns:
        Whether three or more of ``keep_off`` stand within 8 cm of it across, above it.
    """
    if keep_off is None or not len(keep_off):
        return False
    points = np.asarray(keep_off, dtype=float)
    across = np.linalg.norm(points[:, :2] - pose[:2, 3], axis=1) < 0.08
    over = (points[:, 2] > pose[2, 3]) & (points[:, 2] < pose[2, 3] + CONFINED_M)
    return int(np.count_nonzero(across & over)) >= 3


def _column(keep_off: np.ndarray | None, top: np.ndarray, half: np.ndarray, low: float, high: float
            ) -> np.ndarray:
    """The points of ``keep_off`` within ``half`` (m, across x and y) of ``top`` and between the
    heights ``low`` and ``high``: what stands around an object (`over_the_rim`) or over it
    (`under_a_board`)."""
    if keep_off is None or not len(keep_off):
        return np.zeros((0, 3))
    points = np.asarray(keep_off, dtype=float).reshape(-1, 3)
    inside = (np.all(np.abs(points[:, :2] - top[:2]) <= half, axis=1)
              & (points[:, 2] > low) & (points[:, 2] < high))
    return points[inside]
