"""The four sides of the table a robot works at: where along each the base may stand, facing the
table, and the way round the table from one stand to another.

A tabletop robot starts before the table's front side, facing it; a thing at the table's back stands
beyond the arm's reach from there (a nest of boxes 0.9–1.05 m out, next to the storage at the back:
recursive 1182 of tuning-wide), but within it from the back side. The base stands off every side
as far as it stood off the front at the start, and drives between two sides round the table's
corners, never across it.

Pure: the table's top seen from above and the start pose in, stands and paths out.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np

from agent.pose import Pose2D

#: The sides, numbered counter-clockwise as seen from above from the start's: the base facing the
#: table from the front (0), from its right (1), from its back (2), from its left (3).
FRONT, RIGHT, BACK, LEFT = 0, 1, 2, 3
SIDES = (FRONT, RIGHT, BACK, LEFT)
SIDE_NAMES = ("front", "right", "back", "left")
#: How much nearer the table (m) than the stands a drive round it may pass: the stands' lines
#: themselves are clear of it.
PASS_MARGIN_M = 0.01


@dataclass(frozen=True)
class TableSides:
    """A table's footprint in the frame of the start pose, and how far off it the base stands.

    Attributes:
        centre: (x, y) of the footprint's middle (world).
        half: half the footprint's size across the start's heading and along it (m).
        heading: the start's yaw: the way the base faces the table from the front.
        standoff: how far from a side (m) the base's axis stands, as it stood from the front.
    """

    centre: np.ndarray
    half: np.ndarray
    heading: float
    standoff: float

    @classmethod
    def around(cls, top_xy: np.ndarray, start: Pose2D) -> TableSides:
        """The sides of the table whose top has the points ``top_xy``, for a robot that starts at
        ``start`` before it, facing it.

        Args:
            top_xy: (N, 2) points of the table's top (world x, y).
            start: where the robot started, facing the table.

        Returns:
            The sides.

        Raises:
            ValueError: no points, or the start stands on the table's footprint.
        """
        points = np.atleast_2d(np.asarray(top_xy, dtype=float))
        if points.size == 0 or points.shape[1] != 2:
            raise ValueError(f"top_xy: expected (N, 2) points, got shape {points.shape}")
        turn = _rotation(start.yaw)
        local = points @ turn  # (across, ahead) of the start's frame
        lo, hi = local.min(axis=0), local.max(axis=0)
        middle = (lo + hi) / 2
        start_ahead = float(np.asarray(start[:2]) @ turn[:, 1])
        standoff = float(lo[1]) - start_ahead
        if standoff <= 0:
            raise ValueError(f"start {tuple(round(v, 3) for v in start)} stands on the table's footprint "
                             f"({standoff:.3f} m before its front side)")
        return cls(turn @ middle, (hi - lo) / 2, float(start.yaw), standoff)

    def facing(self, side: int) -> float:
        """The base's yaw standing at ``side``, facing the table.

        Args:
            side: `FRONT`, `RIGHT`, `BACK` or `LEFT`.

        Returns:
            The yaw (radians, in (-π, π]).
        """
        return math.remainder(self.heading + side * math.pi / 2, math.tau)

    def local(self, side: int, xy: np.ndarray) -> np.ndarray:
        """World points in ``side``'s frame: along its line, and towards the table from the
        table's middle; the base stands at out = `line` (``side``) facing +out.

        Args:
            side: `FRONT`, `RIGHT`, `BACK` or `LEFT`.
            xy: (N, 2) or (2,) world points (x, y).

        Returns:
            (N, 2) of (along, out).
        """
        turn = _rotation(self.facing(side))
        return (np.atleast_2d(np.asarray(xy, dtype=float)) - self.centre) @ turn

    def along(self, side: int, xy: np.ndarray) -> float:
        """Where along ``side``'s line a point stands level with it.

        Args:
            side: `FRONT`, `RIGHT`, `BACK` or `LEFT`.
            xy: a world point (its x, y count).

        Returns:
            `local`'s ``along`` of the point (m).
        """
        return float(self.local(side, np.asarray(xy, dtype=float)[:2])[0, 0])

    def line(self, side: int) -> float:
        """Where the base's axis stands at ``side``: the standoff before it.

        Args:
            side: `FRONT`, `RIGHT`, `BACK` or `LEFT`.

        Returns:
            Its ``out`` in `local`'s frame (m, negative: before the table's middle).
        """
        return -(float(self.half[1 if side % 2 == 0 else 0]) + self.standoff)

    def stand(self, side: int, along: float) -> Pose2D:
        """The base's pose on ``side``'s line, facing the table.

        Args:
            side: `FRONT`, `RIGHT`, `BACK` or `LEFT`.
            along: where along the line (m, `local`'s ``along``).

        Returns:
            The pose (world).
        """
        turn = _rotation(self.facing(side))
        x, y = self.centre + turn @ np.array([along, self.line(side)])
        return Pose2D(float(x), float(y), self.facing(side))

    def way(self, start_xy: np.ndarray, goal_xy: np.ndarray) -> list[tuple[float, float]]:
        """The shortest way from ``start_xy`` to ``goal_xy`` that keeps the base's axis out of the
        footprint grown by the standoff (less `PASS_MARGIN_M`): straight where that passes, else
        by the corners of the stands' lines, round the side the way is shorter.

        Args:
            start_xy: where the base's axis is (world x, y).
            goal_xy: where it is to go.

        Returns:
            The waypoints after the start, ``goal_xy`` last.
        """
        start, goal = np.asarray(start_xy, dtype=float)[:2], np.asarray(goal_xy, dtype=float)[:2]
        corners = [self.centre + _rotation(self.heading) @ (np.array([sx, sy]) * (self.half + self.standoff))
                   for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        nodes = [start, goal, *corners]
        grown = self.half + self.standoff - PASS_MARGIN_M
        best, before, queue = {0: 0.0}, {}, [(0.0, 0)]
        while queue:
            cost, node = heapq.heappop(queue)
            if node == 1:
                break
            if cost > best.get(node, math.inf):
                continue
            for other in range(1, len(nodes)):
                if other == node or self._crosses(nodes[node], nodes[other], grown):
                    continue
                through = cost + float(np.linalg.norm(nodes[other] - nodes[node]))
                if through < best.get(other, math.inf) - 1e-12:
                    best[other], before[other] = through, node
                    heapq.heappush(queue, (through, other))
        if 1 not in before:
            return [(float(goal[0]), float(goal[1]))]  # it starts or ends on the footprint: as asked
        path, node = [], 1
        while node != 0:
            path.append((float(nodes[node][0]), float(nodes[node][1])))
            node = before[node]
        return path[::-1]

    def _crosses(self, a: np.ndarray, b: np.ndarray, grown: np.ndarray) -> bool:
        """Whether the segment a–b passes through the open footprint grown to ``grown`` half sizes."""
        turn = _rotation(self.heading)
        p, q = (a - self.centre) @ turn, (b - self.centre) @ turn
        enter, leave = 0.0, 1.0  # clip the segment to the box (Liang–Barsky)
        for axis in range(2):
            step = q[axis] - p[axis]
            if abs(step) < 1e-12:
                if abs(p[axis]) >= grown[axis]:
                    return False
                continue
            t1, t2 = (-grown[axis] - p[axis]) / step, (grown[axis] - p[axis]) / step
            enter, leave = max(enter, min(t1, t2)), min(leave, max(t1, t2))
        return leave - enter > 1e-9


def _rotation(yaw: float) -> np.ndarray:
    """Columns: the unit vector across a base at ``yaw`` (its right) and the one it faces."""
    ahead = np.array([math.cos(yaw), math.sin(yaw)])
    return np.column_stack([np.array([ahead[1], -ahead[0]]), ahead])
