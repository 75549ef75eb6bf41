"""ApproachStorage: go to the storage the question names once it has been seen, or else to its room.

The act branch (`behaviours.look_inside`) opens storage seen within 4 m with its handles in view.
Exploration rarely brings the robot there by itself: a cabinet seen across the bathroom from its
doorway leaves no frontier near it, so nothing draws the robot back, and a frontier drawn anew each
step towards the room the question names may be dropped for another the next step. This leaf,
tried before a frontier is chosen, keeps to one goal over several steps:

1. a piece of the named kind seen from as far as 8 m (`agent.perception.sightings`), not seen in
   another room than the named one: the step's move goes towards a viewpoint of the nearest one
   not dealt with yet (pieces seen in the named room first; `agent.planning.viewpoint`), about
   1.6 m from it, in plain view, reachable over the map. From there the next step's frame shows its front, and the act branch opens it.
   A piece is dealt with once the act branch has tried to open it (an act record within
   ``done_m`` of it), once it has been looked at from ``views`` sides, or after ``max_moves`` moves
   towards it (a path that keeps being cut short or blocked);
2. with no such piece, the named room, when its floor has been seen but the robot has not stood
   on it yet (within ``entered_m``): towards the middle of what was seen of it
   (`agent.planning.room_goal`), for at most ``max_moves`` moves. Inside, frontier exploration
   goes on, valued towards the room by the VLM.

Which room a piece or a floor is in is what the frames showed of it: the furniture standing there
(`agent.perception.rooms`; a toilet, a bathroom). Only a room's kind shows this way, so "the
second bedroom" is looked for as a bedroom.

Both kinds of move may squeeze through gaps the map draws a little narrower than the robot
(``squeeze_m``): the doorway the room was seen through, typically. It fails, saying why, when there
is nowhere to go, so the step explores on.
"""

from __future__ import annotations

from dataclasses import dataclass, field
import numpy as np
import py_trees
from py_trees.common import Access, Status

from behaviours import blackboard as bb
from behaviours.episode_state import ActRecord, ApproachState, PieceProgress
from agent.eqa.storage_question import room_in_question, storage_in_question
from agent.mapping.occupancy import ExplorationMap
from agent.observation import Observation
from agent.perception.rooms import floor_points_by_kind, read_rooms
from agent.perception.sightings import SightingConfig, Sightings, storage_centres
from agent.planning.map_fields import MapFields
from agent.planning.frontier_plan import ExploreConfig
from agent.planning.room_goal import RoomFloors, room_entry, room_of_piece
from agent.planning.route import Routes, routes_from, step_towards
from agent.planning.viewpoint import ViewpointConfig, choose_viewpoint
from worlds.vocabulary import room_kind

#: More than the map's surface band, a squeeze would send the base at walls it has seen.
MAX_SQUEEZE_M = 0.15


@dataclass(frozen=True)
class ApproachConfig:
    """``views``: sides a piece is looked at from before it is given up; ``max_moves``: moves
    towards one piece, or towards the room, at most; ``done_m``: an act record this near a piece
    means it was tried; ``entered_m``: the robot has been in the room once it stood this near a
    cell of its floor seen; ``room_floor_m``: a piece whose room no frame showing it told stands
    in the room whose floor was seen this near it (`agent.planning.room_goal.room_of_piece`);
    ``squeeze_m``: these moves may pass gaps this much narrower than the
    map allows exploration (`ExplorationMap.traversable`): a doorway the robot saw the room
    through often looks too narrow for it on the map, whose obstacles stand up to 0.15 m fatter
    than they are. A gap that really is too narrow stops the base on contact, and the map learns
    of it."""

    views: int = 2
    max_moves: int = 6
    done_m: float = 1.0
    entered_m: float = 1.0
    room_floor_m: float = 1.0
    squeeze_m: float = 0.1
    sightings: SightingConfig = field(default_factory=SightingConfig)
    viewpoint: ViewpointConfig = field(default_factory=ViewpointConfig)

    def __post_init__(self) -> None:
        for name in ("views", "max_moves"):
            if getattr(self, name) < 1:
                raise ValueError(f"act.approach.{name}: {getattr(self, name)} must be at least 1")
        for name in ("done_m", "entered_m", "room_floor_m"):
            if not getattr(self, name) > 0:
                raise ValueError(f"act.approach.{name}: {getattr(self, name)} must be positive")
        if not 0 <= self.squeeze_m <= MAX_SQUEEZE_M:
            raise ValueError(f"act.approach.squeeze_m: {self.squeeze_m} must lie in [0, {MAX_SQUEEZE_M}]")


class ApproachStorage(py_trees.behaviour.Behaviour):
    """Writes a `MovePlan` towards the named storage (a view of a piece seen, else its room) and
    succeeds, or fails when there is nowhere to go (see the module docstring). What it has seen
    and tried over the episode is the blackboard's ``approach_state``.

    Args:
        config: how to approach storage.
        explore: the exploration settings (step length, paths).
        name: the node's name.
    """

    def __init__(self, config: ApproachConfig = ApproachConfig(), explore: ExploreConfig = ExploreConfig(),
                 name: str = "ApproachStorage") -> None:
        super().__init__(name)
        self.config = config
        self.explore = explore
        self.blackboard = self.attach_blackboard_client(name=name)
        for key in (bb.QUESTION, bb.OBSERVATION, bb.MAP, bb.ACTS):
            self.blackboard.register_key(key, access=Access.READ)
        for key in (bb.PLAN, bb.MAP_FIELDS, bb.APPROACH_STATE):
            self.blackboard.register_key(key, access=Access.WRITE)

    def update(self) -> Status:
        question = self.blackboard.get(bb.QUESTION)
        kind = storage_in_question(question)
        if kind is None:
            self.feedback_message = "the question asks about no storage"
            return Status.FAILURE
        room = room_in_question(question)
        world_map: ExplorationMap = self.blackboard.get(bb.MAP)
        observation: Observation = self.blackboard.get(bb.OBSERVATION)
        state: ApproachState = self.blackboard.get(bb.APPROACH_STATE)
        if state.floors is None:
            state.floors = RoomFloors(world_map.spec)
        if observation is not state.seen:
            state.seen = observation
            self._note(state, observation, kind, room)
        fields: MapFields = self.blackboard.get(bb.MAP_FIELDS)
        routes = routes_from(world_map, np.asarray(observation.base_pose[:2]), self.explore, self.config.squeeze_m,
                             fields)
        if self._to_piece(state, kind, room, routes, world_map) or self._to_room(state, room, routes):
            return Status.SUCCESS
        return Status.FAILURE

    def _note(self, state: ApproachState, observation: Observation, kind: str, room: str | None) -> None:
        """What this frame shows of the named storage and room; whether the robot stands in the room."""
        if state.sightings is None:
            state.sightings = Sightings(self.config.sightings)
        state.sightings.add(storage_centres(observation, kind, self.config.sightings))
        state.progress += [PieceProgress() for _ in range(len(state.sightings.pieces) - len(state.progress))]
        floors = state.floors
        assert floors is not None  # made before the first frame is noted
        for floor_kind, points in floor_points_by_kind(observation, read_rooms(observation),
                                                       self.config.sightings.max_depth_m).items():
            floors.add(floor_kind, points)
        if room is not None:
            named = floors.of(room_kind(room))
            state.entered |= named.contains(np.asarray(observation.base_pose[:2]), self.config.entered_m)

    def _to_piece(self, state: ApproachState, kind: str, room: str | None, routes: Routes,
                  world_map: ExplorationMap) -> bool:
        """Plan the move towards a view of the nearest piece still to be looked at, seen in the
        named room or in a room nothing told, those in the named room first; whether it did."""
        acts: list[ActRecord] = self.blackboard.get(bb.ACTS)
        named = None if room is None else room_kind(room)
        sightings, floors = state.sightings, state.floors
        assert sightings is not None and floors is not None  # made when the first frame was noted
        choices = []
        for index, piece in enumerate(sightings.pieces):
            seen_in = room_of_piece(piece.room, floors, np.asarray(piece.xy), self.config.room_floor_m)
            if self._dealt_with(state, index, acts) or seen_in not in (None, named):
                continue
            viewpoint = choose_viewpoint(routes, world_map.occupied, piece.xy, state.progress[index].tried,
                                         self.config.viewpoint)
            if viewpoint is not None:
                choices.append((seen_in != named, viewpoint.path_m, index, viewpoint))
        if not choices:
            self.feedback_message = f"no {kind} seen that is still to be looked at and can be reached"
            return False
        _, _, index, viewpoint = min(choices, key=lambda c: c[:3])
        plan, arrives = step_towards(routes, viewpoint.xy, viewpoint.yaw, self.explore.max_step_m)
        progress = state.progress[index]
        progress.moves += 1
        if arrives:
            progress.tried.append(viewpoint.bearing)
        self.blackboard.set(bb.PLAN, plan)
        x, y = sightings.pieces[index].xy
        self.feedback_message = (f"towards a view of the {kind} at ({x:.1f}, {y:.1f}), "
                                 f"{viewpoint.path_m:.1f} m away{'' if arrives else ' (part of the way)'}")
        return True

    def _to_room(self, state: ApproachState, room: str | None, routes: Routes) -> bool:
        """Plan the move into the named room, seen but not stood in yet; whether it did."""
        if room is None:
            return False
        if state.entered or state.room_moves >= self.config.max_moves:
            self.feedback_message += f"; {'has been in' if state.entered else 'gave up going into'} the {room}"
            return False
        assert state.floors is not None  # made when the first frame was noted
        goal = room_entry(routes, state.floors.of(room_kind(room)))
        if goal is None:
            self.feedback_message += f"; no way into the {room} seen yet"
            return False
        plan, _ = step_towards(routes, goal, None, self.explore.max_step_m)
        if plan.goal_distance_m < self.explore.min_frontier_distance_m:
            self.feedback_message += f"; as near the {room} as the map lets it come"
            return False
        state.room_moves += 1
        self.blackboard.set(bb.PLAN, plan)
        self.feedback_message = f"into the {room}, towards ({goal[0]:.1f}, {goal[1]:.1f}), {plan.goal_distance_m:.1f} m away"
        return True

    def _dealt_with(self, state: ApproachState, index: int, acts: list[ActRecord]) -> bool:
        """Whether piece ``index`` was looked at from enough sides, approached often enough, or
        tried by the act branch."""
        progress = state.progress[index]
        if len(progress.tried) >= self.config.views or progress.moves >= self.config.max_moves:
            return True
        assert state.sightings is not None
        xy = state.sightings.pieces[index].xy
        return any(float(np.linalg.norm(np.asarray(act.piece_xy) - xy)) <= self.config.done_m for act in acts)
