"""The robot of the coverage task on its grid: its pose, what it knows, and how it drives to a frontier.

What the robot knows:

- *observed* cells: hit by a ray (`agent.lfe.sensor`); free until the ray's first occupied cell;
- *traversable* cells: known free, farther from every known-occupied cell than the robot's radius
  plus half a cell (the test `worlds.freespace` uses for where the robot fits, so on a fully seen
  map the two agree). Unknown cells do not count as obstacles: frontiers border the unknown by
  definition, and the robot must be able to drive up to them. It still never drives into space
  it has not seen: paths run over known free cells only, the 360° sensor sees what lies within
  reach of the next move before it is made, and a move whose disc would overlap a true obstacle
  (one hidden from every viewpoint so far) is refused by the simulator; what the robot touched
  then becomes known occupied, as a bumper would tell.

Frontiers are those of the EQA tree's explorer (`agent.planning.frontier_plan.reachable_frontiers`):
clusters of frontier cells among the cells reachable over traversable ones. A frontier whose
centre lies within one forward move of the robot is not offered: the robot is already there.

Navigation follows the paper's local planner with Dijkstra in place of the Fast Marching Method:
a shortest path over traversable cells, weighted to keep off walls as the EQA tree's explorer
does, followed by turning toward a point a move ahead on the path (`agent.lfe.motion.next_action`).
"""

from __future__ import annotations

import math

import numpy as np
from skimage.graph import MCP_Geometric

from agent.lfe.motion import Action, stopping_cell, take_action
from agent.lfe.sensor import PanoramicSensor
from agent.lfe.task import CoverageConfig, Situation, TrueHome, clearance_to_obstacles
from agent.planning.frontier import Frontier, cluster_frontiers, frontier_cells
from agent.planning.paths import clearance_cost, distance_field
from agent.pose import Pose2D

MIN_UNKNOWN_NEIGHBOURS = 2
"""A frontier cell has at least this many unknown 8-neighbours, as in the EQA tree's explorer."""

_COMFORT_M = 0.3  # beyond the robot's radius, the clearance navigation paths prefer to keep
_WALL_COST = 3.0  # extra cost per metre of path right at the robot's radius from a known obstacle


class Route:
    """A path to a frontier's centre, and how far along it the robot is.

    Args:
        goal: the frontier the path leads to.
        points_xy: (N, 2) world points of the path, from the robot's cell to the frontier's centre.
        reach_m: how far ahead on the path the robot steers (one forward move).
    """

    def __init__(self, goal: Frontier, points_xy: np.ndarray, reach_m: float) -> None:
        self.goal = goal
        self.points = points_xy
        self.arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(points_xy, axis=0).T))])
        self.reach_m = reach_m
        self.progress = 0

    def target(self, pose: Pose2D) -> np.ndarray | None:
        """The point one move ahead along the path to steer for.

        Progress is the nearest path point from the last progress on, so the robot never steers
        back to a part of the path it has passed. Looking one move ahead, a 90° bend of the path
        is cut by under a tenth of a metre: less than the margin paths keep from walls.

        Args:
            pose: where the robot is now.

        Returns:
            The world point (x, y), or None once the goal is within a move.
        """
        here = np.array([pose.x, pose.y])
        if math.hypot(*(self.points[-1] - here)) <= self.reach_m:
            return None
        self.progress += int(np.argmin(np.hypot(*(self.points[self.progress:] - here).T)))
        ahead = int(np.searchsorted(self.arc, self.arc[self.progress] + self.reach_m))
        return self.points[min(ahead, len(self.points) - 1)]


class GridRobot:
    """The robot in one home: its pose and what it knows, updated by every action it takes.

    It starts at the home's start pose, having sensed once.

    Args:
        home: the ground truth it senses and bumps into.
        config: the sensor, the motion and the frontiers offered.
    """

    def __init__(self, home: TrueHome, config: CoverageConfig) -> None:
        self.home = home
        self.config = config
        self.spec = home.spec
        self.sensor = PanoramicSensor(home.occupied, config.resolution, config.sensor_range_m)
        self.true_clearance, self._nearest_obstacle = clearance_to_obstacles(home.occupied, config.resolution)
        self.known_free = np.zeros(self.spec.shape, dtype=bool)
        self.known_occupied = np.zeros(self.spec.shape, dtype=bool)
        self.pose = Pose2D(float(home.start_xy[0]), float(home.start_xy[1]), float(home.start_yaw))
        self._free_cells = int(home.free.sum())
        self._planning: tuple[np.ndarray, np.ndarray] | None = None
        self._sense()

    @property
    def cell(self) -> tuple[int, int]:
        """The (row, col) of the cell the robot stands in."""
        row, col = self.spec.to_cell(np.array([self.pose.x, self.pose.y]))
        return int(row), int(col)

    def coverage(self) -> float:
        """How much of the home's free floor the robot has seen.

        Returns:
            The share of `agent.lfe.task.TrueHome.free` known free, in [0, 1].
        """
        return int(np.count_nonzero(self.known_free & self.home.free)) / self._free_cells

    def act(self, action: Action) -> bool:
        """Take one action and sense.

        A stopped robot feels what it touched: the true obstacle cell nearest to where its
        centre would have been becomes known occupied, so the next path keeps clear of it.

        Args:
            action: the primitive action.

        Returns:
            True when it was a forward move an obstacle stopped.
        """
        pose, blocked = take_action(self.pose, action, self.true_clearance, self.spec, self.config)
        if blocked:
            stop = stopping_cell(self.pose, self.true_clearance, self.spec, self.config)
            if stop is not None and self.spec.inside(np.array(stop)):
                touched = self._nearest_obstacle[:, stop[0], stop[1]]
                if self.spec.inside(touched):
                    self.known_occupied[touched[0], touched[1]] = True  # _sense() below drops the planning maps
        self.pose = pose
        self._sense()
        return blocked

    def is_frontier(self, frontier: Frontier) -> bool:
        """Whether ``frontier`` is still one.

        Args:
            frontier: a frontier offered earlier.

        Returns:
            True when any of its cells still borders enough unknown space.
        """
        open_unknown = np.pad(~(self.known_free | self.known_occupied), 1)
        rows, cols = frontier.cells[:, 0] + 1, frontier.cells[:, 1] + 1
        counts = sum(open_unknown[rows + dr, cols + dc].astype(int)
                     for dr in (-1, 0, 1) for dc in (-1, 0, 1) if dr or dc)
        return bool((counts >= MIN_UNKNOWN_NEIGHBOURS).any())

    def situation(self, steps_left: int) -> Situation | None:
        """The chooser's view now.

        Args:
            steps_left: primitive actions left in the budget.

        Returns:
            The partial map with the reachable frontiers, or None when no frontier is reachable.
        """
        observed = self.known_free | self.known_occupied
        _, traversable = self._planning_maps()
        cell = self.cell
        field_ = distance_field(self.spec, traversable, cell)
        reachable = np.isfinite(field_.metres)
        mask = frontier_cells(reachable, observed, self.known_occupied, MIN_UNKNOWN_NEIGHBOURS)
        here = np.array([self.pose.x, self.pose.y])
        frontiers = [f for f in cluster_frontiers(self.spec, mask, observed, self.known_occupied,
                                                  self.config.min_frontier_size)
                     if math.hypot(*(self.spec.to_world(np.array(f.centre)) - here)) > self.config.forward_m]
        if not frontiers:
            return None
        from_robot = np.array([field_.metres[f.centre] for f in frontiers])
        return Situation(self.spec, self.known_free.copy(), self.known_occupied.copy(), observed, traversable,
                         (self.pose.x, self.pose.y), cell, frontiers, from_robot, steps_left)

    def route_to(self, frontier: Frontier) -> Route:
        """The path to ``frontier``'s centre over traversable cells, kept off walls where there is room.

        Dijkstra stops as soon as it reaches the goal: a near goal costs a few hundred cells, not
        the whole map (the field `situation` needs is the whole map anyway).

        Args:
            frontier: the chosen frontier, one `situation` offered.

        Returns:
            The route from the robot's cell.
        """
        clearance, traversable = self._planning_maps()
        costs = np.where(traversable, clearance_cost(clearance, self.config.robot_radius_m, _COMFORT_M, _WALL_COST),
                         np.inf)
        cell = self.cell
        costs[cell] = 1.0
        search = MCP_Geometric(costs, fully_connected=True)
        search.find_costs([cell], [frontier.centre])
        path = np.asarray(search.traceback(frontier.centre), dtype=int)
        return Route(frontier, self.spec.to_world(path), self.config.forward_m)

    def _sense(self) -> None:
        scan = self.sensor.scan(self.cell)
        self.known_free |= scan.free
        self.known_occupied |= scan.occupied
        self._planning = None

    def _planning_maps(self) -> tuple[np.ndarray, np.ndarray]:
        """(clearance from known obstacles, traversable cells), worked out once per pose and map."""
        if self._planning is None:
            clearance = clearance_to_obstacles(self.known_occupied, self.config.resolution)[0]
            self._planning = clearance, self._traversable(clearance)
        return self._planning

    def _traversable(self, clearance: np.ndarray) -> np.ndarray:
        """Known free cells where the robot fits, plus a way out from where it stands.

        The robot may stand nearer an obstacle than the fit test allows (it follows its path only
        to within a few centimetres); around it, cells no nearer an obstacle than it is now stay
        open, so it can always back away, never push on.
        """
        fits = self.config.robot_radius_m + self.config.resolution / 2
        row, col = self.cell
        around = self.spec.disc((self.pose.x, self.pose.y), self.config.robot_radius_m + self.config.resolution)
        way_out = around & (clearance >= min(float(clearance[row, col]), fits))
        traversable = self.known_free & ((clearance > fits) | way_out)
        traversable[row, col] = True
        return traversable
