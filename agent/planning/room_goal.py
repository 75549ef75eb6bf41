"""Where the room a question names was seen, and the place to go to step into it.

"What is inside the cabinet in the laundry room?": until the cabinet itself is seen, the laundry
room is where to go. Its floor is often glimpsed early, through a doorway from the hall, and then
left behind: the semantic values make frontiers towards it likely, not certain, and a frontier
drawn anew each step may lead elsewhere the next. `RoomFloor` keeps every floor cell of the map
seen that the robot judged to be that room's (`agent.perception.rooms`, from the furniture
standing on it; no label names a room); `room_entry` picks the place to
drive to: a cell of that floor the base can reach, the one nearest the middle of what was seen of
it, else the reachable cell nearest to that floor (the near side of the doorway it was seen
through). Pure: plain arrays and the map's grid.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from agent.mapping.grid import GridSpec
from agent.planning.route import Routes

class RoomFloor:
    """The cells of a grid on which the named room's floor has been seen.

    Args:
        spec: the grid.
    """

    def __init__(self, spec: GridSpec) -> None:
        self.spec = spec
        self.seen = np.zeros(spec.shape, dtype=bool)

    def add(self, points_xy: np.ndarray) -> None:
        """Mark the cells under floor points (N, 2) seen of this room; points off the grid are dropped.

        Args:
            points_xy: the floor points (world x, y).
        """
        cells = self.spec.to_cell(np.asarray(points_xy, dtype=float).reshape(-1, 2))
        cells = cells[self.spec.inside(cells)]
        self.seen[cells[:, 0], cells[:, 1]] = True

    def contains(self, xy: np.ndarray, within_m: float) -> bool:
        """Whether a seen cell lies within ``within_m`` of ``xy``.

        Args:
            xy: the point (world).
            within_m: the distance.

        Returns:
            Whether one does.
        """
        return bool((self.seen & self.spec.disc(tuple(np.asarray(xy, dtype=float)[:2]), within_m)).any())


class RoomFloors:
    """The floor cells seen of each room kind (a `RoomFloor` per kind the frames told).

    Args:
        spec: the grid.
    """

    def __init__(self, spec: GridSpec) -> None:
        self.spec = spec
        self.by_kind: dict[str, RoomFloor] = {}

    def add(self, kind: str, points_xy: np.ndarray) -> None:
        """Mark floor points (N, 2) seen of a room of ``kind``.

        Args:
            kind: the room kind.
            points_xy: the floor points (world x, y); none is a no-op.
        """
        if len(points_xy):
            self.of(kind).add(points_xy)

    def of(self, kind: str) -> RoomFloor:
        """The floor seen of ``kind`` (none seen yet: an empty one, kept for the next frames).

        Args:
            kind: the room kind.

        Returns:
            The floor.
        """
        if kind not in self.by_kind:
            self.by_kind[kind] = RoomFloor(self.spec)
        return self.by_kind[kind]

    def kinds_near(self, xy: np.ndarray, within_m: float) -> set[str]:
        """The room kinds whose floor was seen within ``within_m`` of ``xy``.

        Args:
            xy: the point (world).
            within_m: the distance.

        Returns:
            The kinds.
        """
        return {kind for kind, floor in self.by_kind.items() if floor.contains(xy, within_m)}


def room_of_piece(told: str | None, floors: RoomFloors, xy: np.ndarray, within_m: float) -> str | None:
    """The room kind a piece of furniture stands in, as far as the frames tell: the kind a frame
    showing it told (``told``), else the one kind of floor seen around it (within ``within_m``);
    None when neither tells, or the floors around it are of more than one kind (a doorway).

    A cabinet seen close up shows nothing that names its room, though the floor it stands on may
    have been told from elsewhere: taken for the named room's, it was opened in the wrong room and
    its contents answered the question.

    Args:
        told: the kind a frame showing the piece told, or None.
        floors: the floors seen so far, by kind.
        xy: where the piece stands.
        within_m: how far round it the floor is looked at.

    Returns:
        The room kind, or None.
    """
    if told is not None:
        return told
    kinds = floors.kinds_near(xy, within_m)
    return next(iter(kinds)) if len(kinds) == 1 else None


def room_entry(routes: Routes, floor: RoomFloor) -> np.ndarray | None:
    """Where to drive to step into the room (world x, y): of the seen floor cells the base can reach
    and stand on, the one nearest the mean of all seen; with none, the reachable cell nearest to a
    seen one. None when nothing was seen or nothing is reachable.

    Args:
        routes: the routes from where the robot stands.
        floor: the room's seen floor.

    Returns:
        The point, or None.
    """
    if not floor.seen.any():
        return None
    spec = floor.spec
    standable = routes.standable()
    inside = floor.seen & standable
    if inside.any():
        middle = spec.to_world(np.argwhere(floor.seen)).mean(axis=0)
        cells = np.argwhere(inside)
        best = cells[np.argmin(np.linalg.norm(spec.to_world(cells) - middle, axis=1))]
    elif standable.any():
        to_floor = ndimage.distance_transform_edt(~floor.seen)
        candidates = np.where(standable, to_floor, np.inf)
        best = np.array(np.unravel_index(np.argmin(candidates), candidates.shape))
    else:
        return None
    return spec.to_world(best)
