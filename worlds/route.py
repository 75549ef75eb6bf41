"""The route a move_base actually drove: the requested polyline, cut where the base stopped.

The base follows its waypoints in straight steps and stops before the first contact
(`World.move_base`), so what it drove is the polyline from where it stood, through the waypoints it
passed, to where it stopped: the first ``travelled_m`` metres of the path. Drawing that, rather than
a straight line from start to end, never cuts through a wall the robot drove around.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

#: Rounding slack in metres: a waypoint this close to the distance driven was reached.
_SLACK_M = 1e-6

#: A stop this close to the last point reached is that point (the steps round in floating point).
_SAME_M = 1e-3

Point = tuple[float, float]


def driven_route(start: Point, path: Sequence[Point], travelled_m: float, end: Point) -> list[Point]:
    """Start, every waypoint within the first ``travelled_m`` metres of the path, and ``end``
    (where the base stopped, which replaces a last waypoint it stands on).

    Args:
        start: where the base started.
        path: the waypoints it was sent along.
        travelled_m: how far it went.
        end: where it stopped.

    Returns:
        The route.
    """
    route, here, left = [start], start, travelled_m
    for waypoint in path:
        length = math.dist(here, waypoint)
        if length > left + _SLACK_M:
            break
        if length > _SLACK_M:
            route.append(waypoint)
        here, left = waypoint, left - length
    if math.dist(route[-1], end) <= _SAME_M:
        route[-1] = end
    else:
        route.append(end)
    return route
