"""The evaluator's record of one episode, kept by the world, which alone knows the ground truth.

Why an episode went wrong is a question about things the agent must never be told: where the
question's target is, which room the robot stood in, how much of the home's floor it has seen. The
world knows all of it, so the world server keeps this record beside the simulation, one per home
reset, updated on every head frame and every base move, and hands it out only on the
``episode_report`` command, which the runtime sends once the tree has finished and no behaviour
sends at all (docs/bus.md has the fields).

- Target in view: the share of a head frame's pixels whose instance id is the target's
  (`worlds.targets`). ``step`` counts the head frames before it: 0 is the first, at the start pose.
  The EQA tree takes one head frame per step, so this is the agent's step minus one; frames the
  act branch takes while it looks into storage count too.
- Rooms entered: the rooms the base's centre passed through, sampled every `ROUTE_SAMPLE_M` along
  what it drove (`worlds.route`), in the order first entered; the start room first.
- Floor seen: the home's free floor (`free_space` for a point on `FLOOR_CELL_M` cells: not under
  walls, furniture or things on the floor) whose cells a head frame's floor pixels landed in, at
  any distance. The agent's own map is not consulted: this is what was in view, not what the
  agent made of it.
- Progress: after every head frame, the floor seen so far and how many rooms the base has entered,
  so coverage can be drawn against time.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from worlds.camera import Frame
from worlds.freespace import free_space
from worlds.home import HomeSpec
from worlds.robot import CameraConfig
from worlds.route import Point
from worlds.scenario import Scenario
from worlds.targets import question_target

#: Cell size of the floor-seen grid, in metres.
FLOOR_CELL_M = 0.1
#: Spacing of the points along a driven route whose room is looked up, in metres.
ROUTE_SAMPLE_M = 0.05


class FloorSeen:
    """The home's free floor on a grid, and the cells of it that head frames have shown.

    Args:
        home: the home.
        camera: the head camera.
    """

    def __init__(self, home: HomeSpec, camera: CameraConfig) -> None:
        space = free_space(home, 0.0, FLOOR_CELL_M)
        self.free = space.components > 0
        self.seen = np.zeros_like(self.free)
        self.origin = np.asarray(space.origin, dtype=float)
        self.camera = camera
        self._floor_ids = np.array([room.instance_id for room in home.rooms])

    def add(self, frame: Frame) -> None:
        """Mark the cells under every floor pixel of ``frame`` (a head frame) as seen.

        Args:
            frame: the head frame.
        """
        rows, cols = np.nonzero(np.isin(frame.seg, self._floor_ids) & (frame.depth > 0))
        z = frame.depth[rows, cols].astype(float)
        camera = self.camera
        in_camera = np.stack([(cols + 0.5 - camera.cx) * z / camera.fx, (rows + 0.5 - camera.cy) * z / camera.fy, z])
        world_xy = (frame.camera_pose[:2, :3] @ in_camera).T + frame.camera_pose[:2, 3]
        cells = np.floor((world_xy - self.origin) / FLOOR_CELL_M).astype(int)
        inside = (cells >= 0).all(axis=1) & (cells[:, 0] < self.free.shape[1]) & (cells[:, 1] < self.free.shape[0])
        self.seen[cells[inside, 1], cells[inside, 0]] = True

    @property
    def free_m2(self) -> float:
        return float(self.free.sum()) * FLOOR_CELL_M**2

    @property
    def seen_m2(self) -> float:
        return float((self.free & self.seen).sum()) * FLOOR_CELL_M**2


class EpisodeRecord:
    """What happened in one home episode, from the evaluator's side (see the module's notes).

    Args:
        home: the home.
        scenario: the episode's scenario.
        camera: the head camera.
        start: where the base starts.
    """

    def __init__(self, home: HomeSpec, scenario: Scenario, camera: CameraConfig, start: Point) -> None:
        self.home = home
        self.target = question_target(home, scenario.target)
        self.floor = FloorSeen(home, camera)
        self.head_frames = 0
        self.first_seen: dict[str, Any] | None = None
        self.best_view: dict[str, Any] | None = None
        self.rooms_entered: list[str] = []
        self.floor_seen_by_frame: list[float] = []
        self.rooms_entered_by_frame: list[int] = []
        self.travelled_m = 0.0
        self._target_ids = np.array(sorted(self.target.ids))
        self._enter(start)

    def saw(self, frame: Frame, base_pose: Sequence[float]) -> None:
        """A head frame taken from ``base_pose``: the target's share of it, and the floor it shows.

        Args:
            frame: the head frame.
            base_pose: where the base stood (x, y, yaw).
        """
        share = float(np.isin(frame.seg, self._target_ids).mean())
        if share > 0:
            view = {"step": self.head_frames, "share": round(share, 5),
                    "base_pose": [round(float(v), 3) for v in base_pose]}
            if self.first_seen is None:
                self.first_seen = view
            if self.best_view is None or share > self.best_view["share"]:
                self.best_view = view
        self.floor.add(frame)
        self.head_frames += 1
        self.floor_seen_by_frame.append(round(self.floor.seen_m2, 2))
        self.rooms_entered_by_frame.append(len(self.rooms_entered))

    def drove(self, route: Sequence[Point], travelled_m: float) -> None:
        """A base move along ``route`` (`worlds.route.driven_route`), ``travelled_m`` long.

        Args:
            route: the route driven.
            travelled_m: its length.
        """
        self.travelled_m += travelled_m
        for (x0, y0), (x1, y1) in zip(route, route[1:]):
            samples = max(1, int(np.ceil(np.hypot(x1 - x0, y1 - y0) / ROUTE_SAMPLE_M)))
            for t in np.linspace(0.0, 1.0, samples + 1)[1:]:
                self._enter((x0 + t * (x1 - x0), y0 + t * (y1 - y0)))

    def _enter(self, point: Point) -> None:
        room = self.home.room_at(*point)
        if room is not None and room not in self.rooms_entered:
            self.rooms_entered.append(room)

    def report(self) -> dict[str, Any]:
        """The record as the ``episode_report`` reply carries it (docs/bus.md).

        Returns:
            The report.
        """
        return {
            "target": self.target.to_dict(),
            "target_seen": self.first_seen,
            "target_best_view": self.best_view,
            "head_frames": self.head_frames,
            "rooms_entered": list(self.rooms_entered),
            "rooms": [{"name": room.name, "polygon": room.polygon} for room in self.home.rooms],
            "free_floor_m2": round(self.floor.free_m2, 2),
            "floor_seen_m2": round(self.floor.seen_m2, 2),
            "floor_seen_by_frame": list(self.floor_seen_by_frame),
            "rooms_entered_by_frame": list(self.rooms_entered_by_frame),
            "travelled_m": round(self.travelled_m, 3),
        }
