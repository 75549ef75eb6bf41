"""Where to go to look at the named storage, or into its room: viewpoints, room entries, step moves,
and the leaf that chooses among them (`ApproachStorage`), on maps and frames built by hand."""

from __future__ import annotations

import math

import numpy as np
import py_trees
import pytest
from py_trees.common import Access, Status

from behaviours import blackboard as bb
from behaviours.episode_state import ActRecord, ApproachState
from agent.planning.map_fields import MapFields
from agent.mapping.camera import Intrinsics
from agent.mapping.occupancy import ExplorationMap, OccupancyConfig
from agent.observation import InstanceLabel, Observation
from agent.planning.paths import path_length
from agent.planning.room_goal import RoomFloor, RoomFloors, room_entry, room_of_piece
from agent.planning.route import routes_from, step_towards
from agent.planning.viewpoint import ViewpointConfig, choose_viewpoint, in_plain_view
from behaviours.approach_storage import ApproachConfig, ApproachStorage


def _map(occupied_at) -> ExplorationMap:
    """A 6 x 6 m room seen whole (|x|, |y| < 3), walls round it, plus what ``occupied_at(x, y)`` marks."""
    world_map = ExplorationMap((0.0, 0.0), OccupancyConfig(size_m=8))
    rows, cols = np.indices(world_map.spec.shape)
    xy = world_map.spec.to_world(np.stack([rows, cols], axis=-1))
    inside = (np.abs(xy[..., 0]) < 3.0) & (np.abs(xy[..., 1]) < 3.0)
    blocked = occupied_at(xy[..., 0], xy[..., 1])
    world_map.floor_seen = inside & ~blocked
    world_map.explored = inside.copy()
    world_map.occupied = ~inside | blocked
    world_map.stood = np.zeros_like(inside)
    return world_map


def _cabinet_at_the_north_wall(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return (np.abs(x) < 0.6) & (y > 2.4)


PIECE = np.array([0.0, 2.7])


def test_a_piece_against_a_wall_is_looked_at_from_before_it_facing_it() -> None:
    world_map = _map(_cabinet_at_the_north_wall)
    routes = routes_from(world_map, np.array([0.0, -2.0]))
    view = choose_viewpoint(routes, world_map.occupied, PIECE)
    assert view is not None and routes.reaches(view.xy)
    assert np.linalg.norm(view.xy - PIECE) == pytest.approx(1.6)
    assert view.xy[1] < 2.4 and abs(view.xy[0]) < 0.7  # before its front, not beside it against the wall
    facing = np.array([math.cos(view.yaw), math.sin(view.yaw)])
    np.testing.assert_allclose(facing, (PIECE - view.xy) / np.linalg.norm(PIECE - view.xy), atol=1e-9)
    # looked at from there once, no other side of it is both open and at least 90° round
    assert choose_viewpoint(routes, world_map.occupied, PIECE, [view.bearing]) is None


def test_a_viewpoint_keeps_a_clear_line_of_sight_to_the_piece() -> None:
    def with_a_pillar(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return _cabinet_at_the_north_wall(x, y) | ((np.abs(x) < 0.15) & (np.abs(y - 1.7) < 0.15))

    world_map = _map(with_a_pillar)
    spec = world_map.spec
    assert not in_plain_view(world_map.occupied, spec, np.array([0.0, 1.1]), PIECE, own_m=0.6)
    assert in_plain_view(world_map.occupied, spec, np.array([0.8, 1.3]), PIECE, own_m=0.6)
    routes = routes_from(world_map, np.array([0.0, -2.0]))
    view = choose_viewpoint(routes, world_map.occupied, PIECE)
    assert view is not None and abs(view.xy[0]) > 0.3  # off to one side of the pillar
    assert in_plain_view(world_map.occupied, spec, view.xy, PIECE, own_m=0.6)


def test_a_piece_seen_through_a_wall_it_stands_behind_has_no_viewpoint_on_this_side() -> None:
    world_map = _map(lambda x, y: (y > 0.9) & (y < 1.1))  # a wall right across, the piece beyond the room
    routes = routes_from(world_map, np.array([0.0, -2.0]))
    assert choose_viewpoint(routes, world_map.occupied, np.array([0.0, 2.0]),
                            config=ViewpointConfig(distances_m=(1.6,))) is None


@pytest.mark.parametrize("field, value", [("distances_m", ()), ("bearings", 0), ("own_m", 2.0), ("apart_rad", 4.0)])
def test_bad_viewpoint_settings_are_refused_with_their_name(field: str, value: object) -> None:
    with pytest.raises(ValueError, match=f"act.approach.viewpoint.{field}"):
        ViewpointConfig(**{field: value})


def test_a_far_goal_is_reached_one_step_at_a_time() -> None:
    routes = routes_from(_map(lambda x, y: np.zeros_like(x, dtype=bool)), np.array([-2.0, -2.0]))
    plan, arrives = step_towards(routes, np.array([2.0, 2.0]), math.pi / 2, max_step_m=3.0)
    assert not arrives and path_length(plan.path_xy) == pytest.approx(3.0)
    assert plan.yaw == pytest.approx(math.atan2(1.0, 1.0), abs=0.05)  # facing the way it goes, not pi/2
    assert plan.frontier is None and plan.goal_distance_m == pytest.approx(4 * math.sqrt(2), rel=0.1)
    plan, arrives = step_towards(routes, np.array([-1.0, -1.0]), math.pi / 2, max_step_m=3.0)
    assert arrives and np.allclose(plan.path_xy[-1], [-1.0, -1.0]) and plan.yaw == math.pi / 2


def _two_rooms(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """A wall along x = 0 with a doorway at |y| < 0.5."""
    return (np.abs(x) < 0.1) & (np.abs(y) > 0.5)


def _floor(world_map: ExplorationMap, where) -> RoomFloor:
    floor = RoomFloor(world_map.spec)
    rows, cols = np.nonzero(np.ones(world_map.spec.shape, dtype=bool))
    xy = world_map.spec.to_world(np.stack([rows, cols], axis=-1))
    floor.add(xy[where(xy[:, 0], xy[:, 1])])
    return floor


def test_into_a_room_seen_through_its_doorway_towards_the_middle_of_what_was_seen() -> None:
    world_map = _map(_two_rooms)
    routes = routes_from(world_map, np.array([-2.0, 0.0]))
    floor = _floor(world_map, lambda x, y: (x > 0.2) & (x < 2.8) & (np.abs(y) < 1.0))  # seen through the doorway
    goal = room_entry(routes, floor)
    assert goal is not None and routes.reaches(goal)
    np.testing.assert_allclose(goal, [1.5, 0.0], atol=0.1)
    assert floor.contains(goal, 0.1) and not floor.contains(np.array([-2.0, 0.0]), 1.0)


def test_a_room_seen_but_out_of_reach_is_approached_as_near_as_the_map_allows() -> None:
    world_map = _map(lambda x, y: np.abs(x) < 0.1)  # no doorway: the far room is seen over the wall, say
    routes = routes_from(world_map, np.array([-2.0, 0.0]))
    goal = room_entry(routes, _floor(world_map, lambda x, y: (x > 0.5) & (np.abs(y) < 1.0)))
    assert goal is not None and routes.reaches(goal) and -0.8 < goal[0] < 0.0 and abs(goal[1]) < 1.0
    assert room_entry(routes, RoomFloor(world_map.spec)) is None  # nothing seen of it: nowhere to go


def test_a_piece_whose_room_no_frame_told_stands_in_the_room_of_the_floor_around_it() -> None:
    """Two rooms either side of a wall at x = 0: the laundry room's floor told from afar (west),
    the bathroom's (east). A cabinet seen close up, nothing naming its room, east of the wall is
    the bathroom's, not the laundry room's a question may name; in the doorway, both floors
    around it, it stays untold."""
    world_map = _map(_two_rooms)
    def points(where) -> np.ndarray:
        return world_map.spec.to_world(np.argwhere(_floor(world_map, where).seen))

    floors = RoomFloors(world_map.spec)
    floors.add("laundry room", points(lambda x, y: (x < -0.2) & (x > -2.8)))
    floors.add("bathroom", points(lambda x, y: (x > 0.2) & (x < 2.8)))
    floors.add("kitchen", np.zeros((0, 2)))  # a frame that tells nothing of the kitchen's floor adds nothing
    assert set(floors.by_kind) == {"laundry room", "bathroom"}
    assert room_of_piece(None, floors, np.array([2.0, 2.5]), 1.0) == "bathroom"
    assert room_of_piece(None, floors, np.array([-2.0, 2.5]), 1.0) == "laundry room"
    assert room_of_piece(None, floors, np.array([0.0, 0.0]), 1.0) is None  # both floors around it
    assert room_of_piece("bathroom", floors, np.array([-2.0, 2.5]), 1.0) == "bathroom"  # a frame told: that wins
    assert room_of_piece(None, RoomFloors(world_map.spec), np.array([2.0, 2.5]), 1.0) is None
    assert not floors.of("kitchen").seen.any()


@pytest.fixture
def board() -> py_trees.blackboard.Client:
    client = py_trees.blackboard.Client(name="test")
    for key in (bb.QUESTION, bb.OBSERVATION, bb.MAP, bb.ACTS, bb.PLAN, bb.MAP_FIELDS, bb.APPROACH_STATE):
        client.register_key(key, access=Access.WRITE)
    client.set(bb.ACTS, [])
    client.set(bb.MAP_FIELDS, MapFields())
    client.set(bb.APPROACH_STATE, ApproachState())
    yield client
    py_trees.blackboard.Blackboard.clear()


#: A camera 1 m above (0, -2) looking north (+y): its right is +x, its down is -z.
LOOKING_NORTH = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, -2.0], [0.0, -1.0, 0.0, 1.0], [0.0, 0.0, 0.0, 1.0]])


def _looking_north(*things: tuple[InstanceLabel, tuple[int, int, int, int]], distance: float) -> Observation:
    """A frame from (0, -2) with the things, (label, (row, col, height, width)) boxes drawn in
    order, ``distance`` straight ahead, and nothing else in view."""
    height, width = 60, 80
    seg = np.full((height, width), -1, dtype=np.int32)
    for label, (row, col, h, w) in things:
        seg[row: row + h, col: col + w] = label.id
    depth = np.where(seg >= 0, distance, 0.0).astype(np.float32)
    return Observation(np.zeros((height, width, 3), np.uint8), depth, seg, tuple(label for label, _ in things),
                       Intrinsics(width, height, 40.0, 40.0, 40.0, 30.0), LOOKING_NORTH, (0.0, -2.0, math.pi / 2))


AHEAD = (25, 35, 10, 10)


def _tick(behaviour: ApproachStorage) -> Status:
    behaviour.tick_once()
    return behaviour.status


def test_the_robot_heads_for_a_view_of_the_named_storage_seen_afar_until_it_was_tried(board) -> None:
    board.set(bb.QUESTION, "What is inside the cabinet in the bathroom?")
    board.set(bb.MAP, _map(_cabinet_at_the_north_wall))
    board.set(bb.OBSERVATION, _looking_north((InstanceLabel(5, "cabinet", "white"), AHEAD), distance=4.7))
    board.set(bb.ACTS, [])
    behaviour = ApproachStorage()
    assert _tick(behaviour) == Status.SUCCESS, behaviour.feedback_message
    plan = board.get(bb.PLAN)
    np.testing.assert_allclose(plan.path_xy[0], [0.0, -2.0])
    assert np.linalg.norm(plan.path_xy[-1] - PIECE) == pytest.approx(1.6, abs=0.15)  # there in one step
    assert "towards a view of the cabinet" in behaviour.feedback_message
    board.set(bb.ACTS, [ActRecord("cabinet", "door 6", [0.1, 2.6], "opening_deg")])  # the act branch tried it since
    board.set(bb.PLAN, None)
    assert _tick(behaviour) == Status.FAILURE and board.get(bb.PLAN) is None
    assert "no cabinet seen that is still to be looked at" in behaviour.feedback_message


def test_a_piece_seen_in_another_room_than_the_named_one_is_left_alone(board) -> None:
    """The cabinet stands on a floor with a stove: a kitchen's cabinet, not the bathroom's."""
    board.set(bb.QUESTION, "What is inside the cabinet in the bathroom?")
    board.set(bb.MAP, _map(_cabinet_at_the_north_wall))
    floor, stove = InstanceLabel(1, "floor", "grey"), InstanceLabel(2, "stove", "white")
    board.set(bb.OBSERVATION, _looking_north((floor, (30, 20, 20, 40)), (InstanceLabel(5, "cabinet", "white"), AHEAD),
                                             (stove, (25, 50, 10, 8)), distance=4.7))
    behaviour = ApproachStorage()
    assert _tick(behaviour) == Status.FAILURE and "no cabinet seen" in behaviour.feedback_message
    assert board.get(bb.APPROACH_STATE).sightings.pieces[0].room == "kitchen"


def test_with_no_piece_seen_the_robot_heads_into_the_named_room_seen_afar(board) -> None:
    """A floor 4 m ahead with a toilet standing on it: a bathroom's floor, although nothing names it."""
    board.set(bb.QUESTION, "What is inside the cabinet in the bathroom?")
    board.set(bb.MAP, _map(lambda x, y: np.zeros_like(x, dtype=bool)))
    floor, toilet = InstanceLabel(1, "floor", "grey"), InstanceLabel(2, "toilet", "white")
    board.set(bb.OBSERVATION, _looking_north((floor, AHEAD), distance=4.0))
    behaviour = ApproachStorage()
    assert _tick(behaviour) == Status.FAILURE  # a floor, but nothing says it is the bathroom's
    board.set(bb.OBSERVATION, _looking_north((floor, AHEAD), (toilet, (18, 38, 9, 5)), distance=4.0))
    board.set(bb.APPROACH_STATE, ApproachState())  # a robot that has seen only this frame
    behaviour = ApproachStorage()
    assert _tick(behaviour) == Status.SUCCESS, behaviour.feedback_message
    assert "into the bathroom" in behaviour.feedback_message
    assert board.get(bb.PLAN).path_xy[-1][1] > 0.5  # north, towards the floor seen 4 m ahead
    board.set(bb.QUESTION, "How many cups are there in the bathroom?")
    assert _tick(behaviour) == Status.FAILURE and behaviour.feedback_message == "the question asks about no storage"


def test_a_gap_the_map_draws_a_little_narrower_than_the_robot_may_be_squeezed_through() -> None:
    world_map = _map(lambda x, y: (np.abs(x) < 0.1) & (np.abs(y) > 0.15))  # 0.2 m clear of its middle on the map
    start, beyond = np.array([-2.0, 0.0]), np.array([2.0, 0.0])
    assert not routes_from(world_map, start).reaches(beyond)
    squeezed = routes_from(world_map, start, squeeze_m=0.1)
    assert squeezed.reaches(beyond) and not squeezed.reaches(np.array([0.0, 0.0]))  # through, not stood in
    with pytest.raises(ValueError, match="act.approach.squeeze_m"):
        ApproachConfig(squeeze_m=0.5)
