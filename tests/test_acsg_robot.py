"""Interactive exploration by the robot in PyBullet: Algorithm 1 driving the arm skills, perceiving
with its head and wrist cameras, scored against the tabletop scene's ground truth."""

from __future__ import annotations

import numpy as np
import pybullet as p
import pytest

from agent.acsg.graph import ACSG
from agent.app.eval.robot_tabletop import in_world_ids, part_states, run_robot
from agent.app.runtime.local_world import local_world
from agent.perception.instances import Instance
from agent.perception.memory import InstanceMemory
from agent.planning.route import Routes
from agent.pose import Pose2D
from skills.arm.skill_plan import SkillPlanError
from skills.robot import Robot
from worlds.bus.link import WorldLink
from worlds.robot import CameraConfig
from worlds.sim import World
from worlds.tabletop import tabletop_variant

pytestmark = pytest.mark.slow


def _explored_and_put_back(task: str, seed: int) -> dict:
    """The scene's exploration row, asserted to have no action failed, to have succeeded and to
    have left the scene as it was found."""
    row = run_robot(task, seed)
    assert row["failed_actions"] == []
    assert row["success"] and row["state_recovered"]
    return row


def test_a_door_scene_is_explored_to_its_ground_truth_graph_and_put_back() -> None:
    row = run_robot("door-only", 0)
    assert row["failed_actions"] == []
    assert row["success"] and row["graph_edit_distance"] == 0.0
    assert row["object_recovery"] == 1.0 and row["unexplored_space"] == 0.0
    assert row["state_recovered"] and row["returned_to_start"]
    assert row["skills"] == row["skills_ok"] >= 4  # two doors opened and closed


def test_what_a_drawer_hides_is_found_and_every_drawer_is_shut_again() -> None:
    row = run_robot("drawer-only", 0)
    assert row["object_recovery"] == 1.0  # the soap in the middle drawer of the second chest
    assert row["state_recovered"]
    # The two bottom drawers' handles sit too low over the table for the hand across the bar: they
    # are grasped from above, opened, looked into and shut like the others.
    assert row["failed_actions"] == []
    assert row["success"] and row["unexplored_space"] == 0.0


def test_things_picked_away_are_put_down_out_of_the_arm_s_way_to_the_door_they_hid() -> None:
    # A milk carton and a jar stand before the cabinet's door. Put down beside the lane to the
    # handle, the carton held the wrist back on its way to the handle, and the door stayed shut.
    assert _explored_and_put_back("occlusion", 3)["object_recovery"] == 1.0


def test_bottles_standing_close_together_are_picked_without_touching_each_other() -> None:
    # Closing around a bottle, with 5 mm to spare either side of the fingers, a finger came down
    # on the bottle beside it; the fingertips now rest on the bottle's top instead.
    assert _explored_and_put_back("occlusion", 4)["object_recovery"] == 1.0


def test_a_cup_below_the_head_camera_s_view_is_seen_from_further_back() -> None:
    # door-only 1: a cup stands on the table 0.34 m before the robot, nearer than the head camera's
    # lowest ray meets the top (0.49 m); the graph missed it. The robot backs away to look.
    row = run_robot("door-only", 1)
    assert row["success"] and row["graph_edit_distance"] == 0.0
    assert "move_camera" not in [run["skill"] for run in row["skill_times"]]  # no wrist looks: no drawers


def test_a_robot_that_cannot_back_away_looks_along_the_table_s_edge_with_the_wrist_camera() -> None:
    with local_world() as served:
        link = WorldLink(served.session, served.keys, timeout_s=60.0)
        try:
            link.call("reset", {"seed": 1, "tabletop": "door-only"})
            robot = Robot(link)
            drive = robot.parts.drive

            def blocked_behind(pose: Pose2D, routes: Routes | None = None) -> None:
                assert robot.home is not None
                if pose[1] < robot.home[1] - 0.01:
                    raise SkillPlanError("the base could not reach it: it touched a wall")
                drive(pose, routes)

            robot.parts.drive = blocked_behind  # type: ignore[method-assign]
            detections = robot.observe()
        finally:
            link.close()
    assert robot.body.lookout == robot.home
    looks = [run["skill"] for run in robot.skill_times]
    assert looks == ["move_camera"] * 3 + ["stow"]  # across the table's width, then folded
    assert "cup" in [d.label for d in detections]


def test_a_corner_of_a_cabinet_seen_apart_is_no_second_cabinet() -> None:
    # door-only 1003 (a tuning seed): the wrist camera's first looks saw a corner of the cabinet's
    # plinth beside its door, apart from the top the head camera saw; it was a second cabinet in
    # the graph, which the robot was asked to open (a cabinet with no door of its own), GED 4.
    assert _explored_and_put_back("door-only", 1003)["graph_edit_distance"] == 0.0


def test_memory_ids_are_put_in_the_ground_truth_s_terms_by_their_last_segmentation_id() -> None:
    memory = InstanceMemory()
    graph = ACSG()
    graph.add_object("o0", "cabinet", instance="0")
    graph.add_object("o1", "door", instance="1")
    graph.add_object("o2", "door", instance="2")
    graph.add_edge("o0", "o1", "object-object", "belongs")
    graph.add_edge("o0", "o2", "object-object", "belongs")
    graph.add_action("open:1", "open", "o1", "open_door", params={"handle": "o2"})
    for key, hint in ((0, 7), (1, 9), (2, 9)):  # two instances seen as one world thing: a split
        memory.instances[key] = _instance(key, hint)
    renamed = in_world_ids(graph, memory)
    assert {n.id for n in renamed.objects()} == {"o7", "o9", "om2"}
    [action] = renamed.actions()
    assert action.id == "open:9" and action.target == "o9" and action.params["handle"] == "om2"
    assert renamed.edge("o7", "o9").relation == "belongs"


def _instance(key: int, hint: int) -> Instance:
    return Instance(key, "thing", None, np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int32), 0.01, 0, 0, hint)



def test_a_drawer_that_sticks_a_little_way_out_is_pushed_shut_again() -> None:
    # drawer-door 1002 (tuning-wide) once: the first drawer's pull let go of the handle 2.3 cm out.
    # An open that failed is not undone by the exploration, and the drawer was left standing ajar.
    # Here the drawer's travel ends 2.3 cm out, so every pull stops there.
    with local_world() as served:
        link = WorldLink(served.session, served.keys, timeout_s=60.0)
        try:
            link.call("reset", {"seed": 0, "tabletop": "drawer-only"})
            stage = served.world.stage
            robot = Robot(link)
            robot.observe()
            drawer = next(i for i in robot.memory.instances.values() if i.label == "drawer")
            [(body, joint)] = [key for key, label in stage.built.labels.items() if label["id"] == drawer.hint]
            p.changeDynamics(body, joint, jointLowerLimit=0.0, jointUpperLimit=0.023, physicsClientId=stage.client)
            result = robot.parts.open_part(drawer)
            [piece] = [piece for piece in stage.built.storage.values() if piece.body == body]
            name = next(name for name, index in piece.links.items() if index == joint)
            left_at = served.world.part_states()[piece.placement.furniture_id][name]
        finally:
            link.close()
    assert not result.ok
    assert "did not open" in result.reason and result.reason.endswith("pushed shut again"), result.reason
    assert abs(left_at) < 0.005


def test_a_drawer_pushed_in_past_its_closed_end_is_not_counted_as_shut() -> None:
    # recursive 1039 (tuning-wide): a box lifted in the lower drawer pushed the closed drawer above
    # 55 cm into the chest, and the evaluation counted it closed, as it had been.
    scene = tabletop_variant("drawer-only", 0)
    world = World(CameraConfig())
    try:
        world.start_tabletop(scene)
        _, placement = scene.storage[0]
        part = placement.model.parts[0]
        piece = world.stage.built.storage[placement.furniture_id]
        part_id = str(placement.part_ids()[part.name])
        assert part_states(world, scene)[part_id] == 0.0
        p.resetJointState(piece.body, piece.links[part.name], part.lower - 0.3 * (part.upper - part.lower),
                          physicsClientId=world.client)
        assert part_states(world, scene)[part_id] == -1.0
    finally:
        world.close()


def test_a_wide_box_is_put_down_where_a_door_already_shut_again_swung() -> None:
    # recursive 1004 (tuning-wide): a 32 cm shell before a cabinet whose door the robot had opened
    # and shut again; the door's sweep and the lane to its handle were still kept clear, and no
    # spot on the table within reach was left for the shell.
    _explored_and_put_back("recursive", 1004)


def test_the_way_to_a_thing_put_down_keeps_the_hand_off_it_and_its_neighbours() -> None:
    # occlusion 1019 (tuning-wide): the free move to high above a milk carton put down by the
    # table's edge swept a finger across the carton itself, and the carton was never put back.
    _explored_and_put_back("occlusion", 1019)


def test_a_thing_put_back_keeps_the_arm_above_the_table_it_goes_back_onto() -> None:
    # occlusion 1003 (tuning-wide): a can's height reaching down to the table it stands on, the
    # pick back looked for the surface under its place from the can's bottom, found none, and its
    # free move to high above the can went unchecked against the table and stopped on it.
    _explored_and_put_back("occlusion", 1003)


def test_a_box_whose_carry_would_meet_a_drawer_is_left_where_it_stood() -> None:
    # recursive 1037 (tuning-wide): the box carried on a route taken unchecked met a drawer, was
    # let go of on the drawer's edge, and the scene was never put back. Carried back, it was put
    # back; now that carry is refused before the arm moves (carrying back stays tested on its own in
    # tests/test_skills_world.py), and the scene is put back untouched.
    row = run_robot("recursive", 1037)
    assert any("would carry it through what stands near" in failed for failed in row["failed_actions"])
    assert row["state_recovered"]


def test_a_shell_is_put_back_around_the_one_it_covered() -> None:
    # recursive 1009 (tuning-wide): seen anew where it had been put down, the outer shell's top
    # moved 1.7 cm in the memory; put back by that top, it came down on the inner shell's wall,
    # 5 cm up, and was taken for a new box.
    _explored_and_put_back("recursive", 1009)


def test_drawers_pushed_shut_stand_shut() -> None:
    # drawer-only 1021 (tuning-wide): pushed back to where their handles were seen shut, three
    # drawers stood 9-11 mm out, more than the 5 % of their travel that counts as shut.
    _explored_and_put_back("drawer-only", 1021)


def test_drawers_pressed_against_their_closed_end_are_let_go_of_shut() -> None:
    # occlusion 1065 (tuning-wide): the hand pushing a drawer shut by its handle pressed it 17 mm
    # past its closed end, through PyBullet's joint limit, and let go of there the drawer sprang
    # back out 10 mm, counted open; a held part now stays within its end stops.
    _explored_and_put_back("occlusion", 1065)


def test_a_thing_is_put_back_by_a_way_round_the_handles_beside_its_place() -> None:
    # occlusion 1127 (tuning-wide): the way round the cabinet's handles to high above the can was
    # found, but refused for the fold out of the base, which grazes the margin over the table, and
    # for the trajectory passing its waypoints at speed, off the lines between them; the straight
    # move was taken unchecked, swept a finger into a handle, and the can was never put back.
    _explored_and_put_back("occlusion", 1127)


def test_a_thing_is_put_back_by_a_way_round_the_door_the_hand_just_closed() -> None:
    # occlusion 1021 (tuning-wide): from the handle of the cabinet door it had closed, the hand's
    # way to high above the carton beside the cabinet was found with its edges checked every
    # 0.04 rad, skimming the door; its trajectory was refused, the straight move taken unchecked
    # swept a finger into the door, and the carton was never put back.
    _explored_and_put_back("occlusion", 1021)


def test_a_drawer_pushed_past_where_it_was_seen_shut_is_remembered_shut() -> None:
    # drawer-only 1053 (tuning-wide): the hand pushing a drawer shut went 2 cm past where the drawer
    # was seen shut; the memory carried the drawer as far, and its front, seen again where it stood,
    # became a second drawer.
    assert _explored_and_put_back("drawer-only", 1053)["graph_edit_distance"] == 0.0


def test_a_wide_box_is_carried_round_a_cabinet_standing_between_its_place_and_its_idle_spot() -> None:
    # recursive 1013 (tuning-wide): carried straight across to its idle spot beside a cabinet, a
    # 28 cm shell would sweep the cabinet's front corner; no straight carry was clear, the unchecked
    # one ran the hand into the cabinet's door, and the shell was let go of on the way.
    _explored_and_put_back("recursive", 1013)


def test_a_nest_beyond_the_front_s_reach_is_lifted_from_the_table_s_back_and_put_back() -> None:
    # recursive 1059 (tuning-wide): the nest stands 1.02 m from the front's line, beyond the arm's
    # reach from there; from the back it stands 0.42 m out, but a drawer chest stands at the back
    # edge right beside it, and an arm folded in before the chest swept a finger into it.
    row = _explored_and_put_back("recursive", 1059)
    assert row["graph_edit_distance"] == 0.0 and row["returned_to_start"]


def test_a_short_box_in_a_drawer_is_taken_as_tall_as_it_stands_lifted_over_the_front_and_put_back() -> None:
    # recursive 1264 (tuning-wide): a box 5 cm tall in a chest's top drawer, seen from above only,
    # was taken 17 cm tall, down to what the memory had seen under it before the drawer was
    # pulled out; then lifted the usual 15 cm, its bottom stood lower than the drawer's front,
    # 6 cm before it and 13 cm over its top, and no route was clear.
    assert _explored_and_put_back("recursive", 1264)["graph_edit_distance"] == 0.0


def test_a_tall_box_in_a_drawer_lifts_off_the_drawer_s_floor_it_began_on() -> None:
    # recursive 1050 (tuning-wide): a box 14 cm tall in a drawer, lifted only as high as the rim
    # sought 3 cm round it, was carried into the drawer's front (its bottom 1.5 cm under the
    # front's top, which no check counted), and lifted higher, it stopped at once on the drawer's
    # floor it stood on, pressed a millimetre into it by the fingertips on its top.
    assert _explored_and_put_back("recursive", 1050)["graph_edit_distance"] == 0.0


def test_a_nest_beyond_a_hand_s_reach_from_above_is_lifted_by_its_near_edge_and_put_back() -> None:
    # recursive 1182 (tuning-wide): a nest on the table 1.0 m out, beside the storage at its back:
    # from the front no route reached its top clear and every unchecked one carried it through what
    # stood near; from the back no free place was in reach. Held by its near edge, checked clear,
    # once every side has failed, it is lifted; put back, the fingertips come down well inside that
    # edge, seen at a slant.
    assert _explored_and_put_back("recursive", 1182)["graph_edit_distance"] == 0.0


def test_a_box_goes_back_over_what_it_covered_without_touching_what_stands_beside_it() -> None:
    # recursive 1016 (tuning-wide): the clock the inner shell covered counted as a thing to keep off
    # while the shell came down over it again, so no route was checked clear; the unchecked carry
    # swept the shell across a chest's handles and pulled both drawers open.
    _explored_and_put_back("recursive", 1016)


def test_a_box_goes_on_top_of_the_one_lifted_off_it_when_the_table_is_full() -> None:
    # recursive 1014 (tuning-wide): the outer shell put down, no place 0.34 m across was left within
    # reach for the inner one, and what it covered was never seen.
    assert _explored_and_put_back("recursive", 1014)["graph_edit_distance"] == 0.0


def test_a_box_with_no_clear_way_out_of_its_drawer_is_left_there_and_the_chest_as_it_was() -> None:
    # recursive 1018 (tuning-wide): no route out of the open drawer kept the wrist off the board
    # over it; the unchecked one pushed the chest's drawers 10 and 27 cm in past their end stops.
    # The drawer above stands 3 cm over the box's top, lower than the box must be lifted to clear
    # what it covers: the pick is refused as that, at once.
    row = run_robot("recursive", 1018)
    assert any("no room to lift it" in failed for failed in row["failed_actions"]), row["failed_actions"]
    assert row["state_recovered"]


def test_a_base_coming_back_to_a_door_it_opened_folds_the_arm_before_it_comes_forward() -> None:
    # drawer-door 1011 (tuning-wide): driving back to the stand of the door it had opened, to shut
    # it, with its arm out as a look into a drawer had left it, the robot drove the arm into the
    # door's handle; the door stayed open and the drawer beside it was never reached.
    _explored_and_put_back("drawer-door", 1011)


def test_a_base_coming_back_to_a_door_resting_where_it_stood_shuts_it_from_there() -> None:
    # occlusion 1249 (tuning-wide): the door swung open against the base and rested where the base
    # had stood; coming back to that stand to shut it, the base touched the door at its last step,
    # the drive failed, and the door and the jar were never put back.
    _explored_and_put_back("occlusion", 1249)


def test_an_arm_folded_on_its_way_elsewhere_does_not_leave_a_door_open() -> None:
    # drawer-door 1094 (tuning-wide): folded on its way from a door it had opened, the arm later came
    # out of the stowed pose to that door's handle by no way clear of the door, pushed it on, and
    # the door was left open. The arm is folded on the way only when coming back to close a part.
    _explored_and_put_back("drawer-door", 1094)


def test_a_box_taken_out_of_a_cabinet_by_its_near_edge_goes_back_the_way_it_came() -> None:
    # recursive 1025 (tuning-wide): grasped again by the edge nearest the robot where it stood on
    # the table, the box came into the cabinet turned and no route put it back; held as it was taken
    # out, its top, 1.4 cm lower than the memory had it, was not found by a touch along the leaning
    # hand's axis. It goes back held as it came out, its top sought straight down.
    row = run_robot("recursive", 1025)
    assert not any(failed.startswith("pick_back") for failed in row["failed_actions"]), row["failed_actions"]
    assert row["state_recovered"]


def test_a_box_in_a_lower_drawer_is_not_lifted_into_the_closed_drawer_above() -> None:
    # recursive 1039 (tuning-wide): a box held by its near edge in the chest's lower drawer, half
    # under the closed drawer above, was lifted 15 cm on a route taken unchecked and pushed that
    # drawer 55 cm into the chest; what the closed drawer fills behind its front is kept off, and
    # the box is left where it stands rather than lifted into it.
    row = run_robot("recursive", 1039)
    assert row["state_recovered"], row["failed_actions"]


def test_a_box_lifted_off_a_smaller_one_is_not_put_down_in_the_way_to_it() -> None:
    # recursive 1160 (tuning-wide): the outer shell was put down right before the nest, between it
    # and the robot; the hand leaning back over it to the inner shell's near edge stood on it 2.5 cm
    # over the inner shell's top, and closed on nothing. The lane from where a thing that may cover
    # another stood to the robot is kept clear where a place beside it is free and reached.
    _explored_and_put_back("recursive", 1160)


def test_a_box_with_no_route_past_the_lane_to_what_it_covers_goes_where_a_route_reaches() -> None:
    # recursive 1064 (tuning-wide): a box 0.31 m wide, 0.94 m out. Kept off the lane to the
    # smaller box it covered, its spots lay beside the lane, and no route reached them; the spots
    # the lane does not rule out are tried next, from the same side.
    _explored_and_put_back("recursive", 1064)
