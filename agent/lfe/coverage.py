"""The coverage task of learning-augmented frontier exploration on a 2-D grid (paper §IV, §VI-A).

A robot with a panoramic range sensor explores a home for a budget of primitive actions (forward
0.25 m, turn ±30°; 500 of them) and is scored by the share of the home's free floor it has seen.
Every few steps a *chooser* picks one of the reachable frontiers from what the robot knows; the
simulator drives there with primitive actions, sensing after each, until it is time to choose
again. The chooser is the only thing the methods of the paper's Table I differ in.

The simulator reads the ground truth (`TrueHome`) to sense and to stop the robot at obstacles;
the chooser sees only the partial map (`Situation`). What the robot knows:

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
does, followed by turning toward a point a move ahead on the path until the heading is within
half a turn, then moving forward.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import Enum
from typing import NamedTuple

import numpy as np
from scipy import ndimage
from skimage.graph import MCP_Geometric

from agent.lfe.bellman import nearest
from agent.lfe.sensor import PanoramicSensor
from agent.mapping.grid import GridSpec
from agent.planning.frontier import Frontier, cluster_frontiers, frontier_cells
from agent.planning.paths import clearance_cost, distance_field
from worlds.freespace import free_space
from worlds.home import HomeSpec
from worlds.robot import ROBOT_RADIUS

MIN_UNKNOWN_NEIGHBOURS = 2
"""A frontier cell has at least this many unknown 8-neighbours, as in the EQA tree's explorer."""

_COMFORT_M = 0.3  # beyond the robot's radius, the clearance navigation paths prefer to keep
_WALL_COST = 3.0  # extra cost per metre of path right at the robot's radius from a known obstacle
_EIGHT = np.ones((3, 3), dtype=bool)


@dataclass(frozen=True)
class CoverageConfig:
    """The coverage task's numbers: the paper's where it gives them.

    ``sensor_range_m`` is 5 m, the depth cut-off of the authors' Habitat configuration; at 0.05 m
    cells a 360° scan then sees up to ~78 m² from one pose. ``robot_radius_m`` is the repo's robot
    (`worlds.robot.ROBOT_RADIUS`, also the EQA map's radius), for which the home generator
    guarantees that every room is reachable through its 0.9–1.1 m doorways.
    """

    resolution: float = 0.05  # map cells (m), the paper's
    sensor_range_m: float = 5.0
    forward_m: float = 0.25
    turn_deg: float = 30.0
    budget_steps: int = 500
    robot_radius_m: float = ROBOT_RADIUS
    replan_every: int = 5  # steps between frontier choices; sooner on arrival or when the goal is no frontier
    min_frontier_size: int = 3  # cells of the smallest frontier offered

    def __post_init__(self) -> None:
        for name in ("resolution", "sensor_range_m", "forward_m", "turn_deg", "robot_radius_m"):
            value = getattr(self, name)
            number = isinstance(value, (int, float)) and not isinstance(value, bool)
            if not (number and math.isfinite(value) and value > 0):
                raise ValueError(f"{name}: must be a positive number, got {value!r}")
        for name in ("budget_steps", "replan_every", "min_frontier_size"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value <= 0:
                raise ValueError(f"{name}: must be a positive integer, got {value!r}")
        if self.turn_deg > 180:
            raise ValueError(f"turn_deg: must be at most 180, got {self.turn_deg!r}")
        if self.sensor_range_m < self.resolution:
            raise ValueError(f"sensor_range_m: must be at least one cell ({self.resolution:g} m), "
                             f"got {self.sensor_range_m!r}")


@dataclass(frozen=True, eq=False)  # arrays: compared by identity
class TrueHome:
    """Ground truth of one home on the grid: what the simulator and the oracle may read, never a chooser."""

    spec: GridSpec
    # bool: floor cells not covered by an obstacle, in the region reachable from the start (the coverage denominator)
    free: np.ndarray
    # bool: what blocks the sensor's rays (walls, furniture, floor objects); outside the grid counts too
    occupied: np.ndarray
    start_xy: tuple[float, float]
    start_yaw: float

    def __post_init__(self) -> None:
        for name in ("free", "occupied"):
            mask = getattr(self, name)
            if not isinstance(mask, np.ndarray) or mask.dtype != bool or mask.shape != self.spec.shape:
                raise ValueError(f"{name}: must be a bool mask of the grid's shape {self.spec.shape}, got "
                                 f"{getattr(mask, 'dtype', type(mask).__name__)} {getattr(mask, 'shape', '')}")
        if (self.free & self.occupied).any():
            raise ValueError("free: overlaps occupied")
        if not self.free.any():
            raise ValueError("free: has no cell")
        cell = self.spec.to_cell(np.asarray(self.start_xy, dtype=float))
        if not (self.spec.inside(cell) and self.free[cell[0], cell[1]]):
            raise ValueError(f"start_xy: {self.start_xy} is not on a free cell")
        if not math.isfinite(self.start_yaw):
            raise ValueError(f"start_yaw: must be finite, got {self.start_yaw!r}")

    @classmethod
    def from_home(cls, home: HomeSpec, config: CoverageConfig = CoverageConfig(), seed: int = 0) -> TrueHome:
        """Rasterise ``home`` (`worlds.freespace`) and draw a start pose from ``seed``.

        The start is a cell where the robot fits, in the free-space component that reaches the most
        rooms; the heading is uniform. Free floor is then the floor connected to the start: a
        pocket no ray can ever enter would otherwise count against every method alike.
        """
        space = free_space(home, config.robot_radius_m, config.resolution)
        occupied = space.clearance_m == 0
        main = space.main_component()
        if main == 0:
            raise ValueError(f"home {home.seed}: nowhere for a robot of radius {config.robot_radius_m:g} m to stand")
        fits = np.argwhere(space.components == main)
        rng = np.random.default_rng(seed)
        start = fits[rng.integers(len(fits))]
        yaw = float(rng.uniform(-math.pi, math.pi))
        spec = GridSpec(space.origin, space.resolution, occupied.shape)
        labels, _ = ndimage.label(~occupied, structure=_EIGHT)
        free = labels == labels[start[0], start[1]]
        x, y = spec.to_world(start)
        return cls(spec, free, occupied, (float(x), float(y)), yaw)

    @property
    def area_m2(self) -> float:
        """The free floor to cover, in m²."""
        return float(self.free.sum()) * self.spec.resolution**2

    def clearance_m(self) -> np.ndarray:
        """Metres from each cell's centre to the nearest occupied cell's (outside the grid counts as
        occupied): what `take_action` checks a forward move against."""
        return _clearance(self.occupied, self.spec.resolution)[0]


@dataclass(frozen=True, eq=False)  # arrays: compared by identity
class Situation:
    """What a frontier chooser sees at a planning step: the partial map only."""

    spec: GridSpec
    free: np.ndarray  # known free
    occupied: np.ndarray  # known occupied
    observed: np.ndarray  # free | occupied
    traversable: np.ndarray  # known free cells where the robot fits (for `agent.lfe.bellman.distance_matrix`)
    robot_xy: tuple[float, float]
    robot_cell: tuple[int, int]
    frontiers: list[Frontier]  # reachable frontiers, non-empty
    from_robot_m: np.ndarray  # known-space path length from the robot's cell to each frontier's centre
    steps_left: int


FrontierChooser = Callable[[Situation], int]
"""Returns an index into ``situation.frontiers``."""


@dataclass(frozen=True, eq=False)  # arrays: compared by identity
class CoverageResult:
    """How one exploration went."""

    # (budget_steps + 1,) share of TrueHome.free observed after each step (index 0: before the first),
    # padded with the last value if exploration ends early
    coverage: np.ndarray
    steps_used: int
    exhausted: bool  # no reachable frontier was left before the budget ran out
    plan_seconds: list[float]  # time the chooser took at each planning step
    frontier_counts: list[int]  # frontiers offered at each planning step
    poses: np.ndarray  # (steps_used + 1, 3) x, y, yaw after each step (row 0: the start)
    blocked_steps: list[int] = field(default_factory=list)  # steps (1-based) whose forward move an obstacle stopped


class Pose(NamedTuple):
    x: float
    y: float
    yaw: float


class Action(Enum):
    """The paper's primitive actions (STOP aside: the episode ends when the budget or the frontiers do)."""

    FORWARD = "forward"
    TURN_LEFT = "turn_left"
    TURN_RIGHT = "turn_right"


def take_action(pose: Pose, action: Action, clearance_m: np.ndarray, spec: GridSpec,
                config: CoverageConfig = CoverageConfig()) -> tuple[Pose, bool]:
    """The pose after one action, and whether it was a forward move an obstacle stopped.

    Turns always succeed (the robot is round). A forward move is checked every half cell along
    the way (`stopping_cell`) against the true ``clearance_m``; a stopped move leaves the pose as
    it was: the step is spent all the same.
    """
    if action is not Action.FORWARD:
        turn = math.radians(config.turn_deg) * (1 if action is Action.TURN_LEFT else -1)
        return Pose(pose.x, pose.y, _wrap(pose.yaw + turn)), False
    if stopping_cell(pose, clearance_m, spec, config) is not None:
        return pose, True
    return Pose(pose.x + config.forward_m * math.cos(pose.yaw), pose.y + config.forward_m * math.sin(pose.yaw),
                pose.yaw), False


def stopping_cell(pose: Pose, clearance_m: np.ndarray, spec: GridSpec,
                  config: CoverageConfig = CoverageConfig()) -> tuple[int, int] | None:
    """Where a forward move from ``pose`` would first put the robot's disc into an obstacle, or None.

    The disc fits where the true ``clearance_m`` of the cell under its centre (metres to the
    nearest occupied cell) is at least the robot's radius, and never outside the grid; positions
    are checked every half cell along the move, so no obstacle is jumped over.
    """
    samples = math.ceil(config.forward_m / (spec.resolution / 2))
    along = config.forward_m * np.arange(1, samples + 1) / samples
    points = np.column_stack([pose.x + along * math.cos(pose.yaw), pose.y + along * math.sin(pose.yaw)])
    cells = spec.to_cell(points)
    inside = spec.inside(cells)
    fits = inside.copy()
    fits[inside] = clearance_m[cells[inside, 0], cells[inside, 1]] >= config.robot_radius_m
    if fits.all():
        return None
    row, col = cells[int(np.argmin(fits))]
    return int(row), int(col)


def fbe_near(situation: Situation) -> int:
    """FBE-Near: the frontier with the shortest known-space path (ties: the lower index)."""
    return nearest(situation.from_robot_m)


def run_coverage(home: TrueHome, choose: FrontierChooser, config: CoverageConfig = CoverageConfig(),
                 on_plan: Callable[[Situation, int], None] | None = None) -> CoverageResult:
    """Explore ``home`` for ``config.budget_steps`` primitive actions, choosing frontiers with ``choose``.

    A frontier is chosen at the start, every ``replan_every`` steps, when the robot reaches the
    goal or its goal stops being a frontier, and after a blocked move; ``on_plan(situation, index)``
    hears of every choice. The run ends when the budget is spent or no reachable frontier is left.
    Nothing here is random: the same home, chooser and config give the same result.
    """
    if home.spec.resolution != config.resolution:
        raise ValueError(f"home: its grid is at {home.spec.resolution:g} m, the config's at {config.resolution:g} m")
    robot = _Robot(home, config)
    coverage = [robot.coverage()]
    poses = [robot.pose]
    plan_seconds: list[float] = []
    frontier_counts: list[int] = []
    blocked_steps: list[int] = []
    route: _Route | None = None
    since_plan = 0
    exhausted = False
    while len(coverage) <= config.budget_steps:
        steps_left = config.budget_steps - len(coverage) + 1
        keep = route is not None and since_plan < config.replan_every and robot.is_frontier(route.goal)
        target = route.target(robot.pose) if keep and route is not None else None
        if target is None:
            situation = robot.situation(steps_left)
            if situation is None:
                exhausted = True
                break
            started = time.perf_counter()
            index = choose(situation)
            plan_seconds.append(time.perf_counter() - started)
            frontier_counts.append(len(situation.frontiers))
            if not 0 <= index < len(situation.frontiers):
                raise ValueError(f"choose: returned {index}, not an index into {len(situation.frontiers)} frontiers")
            if on_plan is not None:
                on_plan(situation, index)
            route = robot.route_to(situation.frontiers[index])
            since_plan = 0
            target = route.target(robot.pose)
            assert target is not None, "an offered frontier lies farther than one move"
        blocked = robot.act(_next_action(robot.pose, target, config))
        since_plan = config.replan_every if blocked else since_plan + 1
        if blocked:
            blocked_steps.append(len(coverage))
        coverage.append(robot.coverage())
        poses.append(robot.pose)
    padded = np.concatenate([coverage, np.full(config.budget_steps + 1 - len(coverage), coverage[-1])])
    return CoverageResult(padded, len(coverage) - 1, exhausted, plan_seconds, frontier_counts,
                          np.array(poses, dtype=float), blocked_steps)


class _Route:
    """A path to a frontier's centre (world points from the robot's cell), and how far along it the robot is."""

    def __init__(self, goal: Frontier, points_xy: np.ndarray, reach_m: float) -> None:
        self.goal = goal
        self.points = points_xy
        self.arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(points_xy, axis=0).T))])
        self.reach_m = reach_m
        self.progress = 0

    def target(self, pose: Pose) -> np.ndarray | None:
        """The point one move ahead along the path to steer for; None once the goal is within a move.

        Progress is the nearest path point from the last progress on, so the robot never steers
        back to a part of the path it has passed. Looking one move ahead, a 90° bend of the path
        is cut by under a tenth of a metre: less than the margin paths keep from walls.
        """
        here = np.array([pose.x, pose.y])
        if math.hypot(*(self.points[-1] - here)) <= self.reach_m:
            return None
        self.progress += int(np.argmin(np.hypot(*(self.points[self.progress:] - here).T)))
        ahead = int(np.searchsorted(self.arc, self.arc[self.progress] + self.reach_m))
        return self.points[min(ahead, len(self.points) - 1)]


def _next_action(pose: Pose, target: np.ndarray, config: CoverageConfig) -> Action:
    """Turn toward ``target`` until the heading is within half a turn of it, then move forward."""
    error = _wrap(math.atan2(target[1] - pose.y, target[0] - pose.x) - pose.yaw)
    if abs(error) <= math.radians(config.turn_deg) / 2:
        return Action.FORWARD
    return Action.TURN_LEFT if error > 0 else Action.TURN_RIGHT


class _Robot:
    """The robot in one home: its pose and what it knows, updated by every action it takes."""

    def __init__(self, home: TrueHome, config: CoverageConfig) -> None:
        self.home = home
        self.config = config
        self.spec = home.spec
        self.sensor = PanoramicSensor(home.occupied, config.resolution, config.sensor_range_m)
        self.true_clearance, self._nearest_obstacle = _clearance(home.occupied, config.resolution)
        self.known_free = np.zeros(self.spec.shape, dtype=bool)
        self.known_occupied = np.zeros(self.spec.shape, dtype=bool)
        self.pose = Pose(float(home.start_xy[0]), float(home.start_xy[1]), float(home.start_yaw))
        self._free_cells = int(home.free.sum())
        self._planning: tuple[np.ndarray, np.ndarray] | None = None
        self._sense()

    @property
    def cell(self) -> tuple[int, int]:
        row, col = self.spec.to_cell(np.array([self.pose.x, self.pose.y]))
        return int(row), int(col)

    def coverage(self) -> float:
        return int(np.count_nonzero(self.known_free & self.home.free)) / self._free_cells

    def act(self, action: Action) -> bool:
        """Take one action and sense; True when it was a forward move an obstacle stopped.

        A stopped robot feels what it touched: the true obstacle cell nearest to where its
        centre would have been becomes known occupied, so the next path keeps clear of it.
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
        """Whether any of ``frontier``'s cells still borders enough unknown space."""
        open_unknown = np.pad(~(self.known_free | self.known_occupied), 1)
        rows, cols = frontier.cells[:, 0] + 1, frontier.cells[:, 1] + 1
        counts = sum(open_unknown[rows + dr, cols + dc].astype(int)
                     for dr in (-1, 0, 1) for dc in (-1, 0, 1) if dr or dc)
        return bool((counts >= MIN_UNKNOWN_NEIGHBOURS).any())

    def situation(self, steps_left: int) -> Situation | None:
        """The chooser's view now; None when no frontier is reachable."""
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

    def route_to(self, frontier: Frontier) -> _Route:
        """The path to ``frontier``'s centre over traversable cells, kept off walls where there is room.

        Dijkstra stops as soon as it reaches the goal: a near goal costs a few hundred cells, not
        the whole map (the field `situation` needs is the whole map anyway).
        """
        clearance, traversable = self._planning_maps()
        costs = np.where(traversable, clearance_cost(clearance, self.config.robot_radius_m, _COMFORT_M, _WALL_COST),
                         np.inf)
        cell = self.cell
        costs[cell] = 1.0
        search = MCP_Geometric(costs, fully_connected=True)
        search.find_costs([cell], [frontier.centre])
        path = np.asarray(search.traceback(frontier.centre), dtype=int)
        return _Route(frontier, self.spec.to_world(path), self.config.forward_m)

    def _sense(self) -> None:
        scan = self.sensor.scan(self.cell)
        self.known_free |= scan.free
        self.known_occupied |= scan.occupied
        self._planning = None

    def _planning_maps(self) -> tuple[np.ndarray, np.ndarray]:
        """(clearance from known obstacles, traversable cells), worked out once per pose and map."""
        if self._planning is None:
            clearance = _clearance(self.known_occupied, self.config.resolution)[0]
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


def _clearance(occupied: np.ndarray, resolution: float) -> tuple[np.ndarray, np.ndarray]:
    """Metres from each cell's centre to the nearest occupied cell's, and that cell as a (2, H, W)
    array of (row, col). Outside the grid counts as occupied (its cells read -1 or the grid's size)."""
    padded = np.pad(occupied, 1, constant_values=True)
    distances, nearest = ndimage.distance_transform_edt(~padded, return_indices=True)
    return distances[1:-1, 1:-1] * resolution, nearest[:, 1:-1, 1:-1] - 1


def _wrap(angle: float) -> float:
    """``angle`` in (-π, π]."""
    return math.pi - (math.pi - angle) % (2 * math.pi)
