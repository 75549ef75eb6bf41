"""A place to look at a piece of storage from, and the next move towards it.

Seen from across a room, a cabinet is a few dozen pixels: enough to know it is there, too few to
find its handles, which the act branch needs before it can open anything. From about 1.6 m, facing
it, the head camera has the whole front in view, down to a nightstand's lowest drawer. A viewpoint
is such a place on a ring round the piece that the base can reach over the robot's map
(`agent.planning.route.Routes`) and from which nothing the map knows of stands between the camera
and the piece. Which side of the piece is its front is not known from afar, so a piece may be
looked at from more than one side: each new viewpoint lies at least ``apart_rad`` round the piece
from those already tried. Pure: the map's arrays in, a `MovePlan` out.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from agent.mapping.grid import GridSpec
from agent.planning.route import Routes

#: Spacing of the points checked along a line of sight, as a share of the map's cell size.
_SIGHT_STEP = 0.5


@dataclass(frozen=True)
class ViewpointConfig:
    """``distances_m``: how far from the piece's centre to stand, tried in this order; ``bearings``:
    how many directions round the piece are tried at each distance; ``own_m``: within this of the
    piece's centre, occupied cells on a line of sight are the piece itself; ``apart_rad``: how far
    round the piece a new viewpoint must lie from each one tried before."""

    distances_m: tuple[float, ...] = (1.6, 1.3, 2.0)
    bearings: int = 16
    own_m: float = 0.6
    apart_rad: float = math.pi / 2

    def __post_init__(self) -> None:
        if not self.distances_m or not all(d > 0 for d in self.distances_m):
            raise ValueError(f"act.approach.viewpoint.distances_m: {self.distances_m!r} must be positive distances")
        if self.bearings < 1:
            raise ValueError(f"act.approach.viewpoint.bearings: {self.bearings} must be at least 1")
        if not 0 <= self.own_m < min(self.distances_m):
            raise ValueError(f"act.approach.viewpoint.own_m: {self.own_m} must lie in [0, the nearest distance)")
        if not 0 <= self.apart_rad <= math.pi:
            raise ValueError(f"act.approach.viewpoint.apart_rad: {self.apart_rad} must lie in [0, pi]")


@dataclass(frozen=True)
class Viewpoint:
    """Where to stand (``xy``, facing the piece at ``yaw``), its ``bearing`` from the piece's centre
    and the length of the path there (``path_m``, metres over the map)."""

    xy: np.ndarray
    yaw: float
    bearing: float
    path_m: float


def in_plain_view(occupied: np.ndarray, spec: GridSpec, eye_xy: np.ndarray, piece_xy: np.ndarray,
                  own_m: float) -> bool:
    """Whether no occupied cell lies on the segment from ``eye_xy`` to ``piece_xy``, except within
    ``own_m`` of the piece (the piece itself). Cells off the map block nothing.

    Args:
        occupied: the cells seen occupied.
        spec: the grid.
        eye_xy: where the robot would look from.
        piece_xy: the piece looked at.
        own_m: how far round the piece its own cells are.

    Returns:
        Whether the view is clear.
    """
    eye, piece = np.asarray(eye_xy, dtype=float), np.asarray(piece_xy, dtype=float)
    length = float(np.linalg.norm(piece - eye)) - own_m
    if length <= 0:
        return True
    steps = np.arange(0.0, length, _SIGHT_STEP * spec.resolution)
    points = eye + steps[:, None] * (piece - eye) / float(np.linalg.norm(piece - eye))
    cells = spec.to_cell(points)
    cells = cells[spec.inside(cells)]
    return not bool(occupied[cells[:, 0], cells[:, 1]].any())


def _angle_between(a: float, b: float) -> float:
    return abs(math.remainder(a - b, 2 * math.pi))


def choose_viewpoint(routes: Routes, occupied: np.ndarray, piece_xy: np.ndarray, tried: Sequence[float] = (),
                     config: ViewpointConfig = ViewpointConfig()) -> Viewpoint | None:
    """The viewpoint of the piece at ``piece_xy`` with the shortest path, at the first of
    ``config.distances_m`` that has one, none within ``config.apart_rad`` of a bearing in ``tried``;
    None when no place round it is both reachable and in plain view.

    Args:
        routes: the routes from where the robot stands.
        occupied: the cells seen occupied.
        piece_xy: the piece to look at.
        tried: the bearings already looked from (rad).
        config: the distances, bearings and spacing tried.

    Returns:
        The viewpoint, or None.
    """
    piece = np.asarray(piece_xy, dtype=float)[:2]
    spec = routes.field.spec
    for distance in config.distances_m:
        found = []
        for k in range(config.bearings):
            bearing = math.remainder(2 * math.pi * k / config.bearings, 2 * math.pi)
            if any(_angle_between(bearing, t) < config.apart_rad for t in tried):
                continue
            xy = piece + distance * np.array([math.cos(bearing), math.sin(bearing)])
            if not routes.reaches(xy) or not in_plain_view(occupied, spec, xy, piece, config.own_m):
                continue
            cell = tuple(int(v) for v in spec.to_cell(xy))
            facing = piece - xy
            found.append(Viewpoint(xy, math.atan2(facing[1], facing[0]), bearing, float(routes.field.metres[cell])))
        if found:
            return min(found, key=lambda v: v.path_m)
    return None
