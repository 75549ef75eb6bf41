"""Instance memory on ray-cast frames: merging across views, parts and parents, stale voxels.

The scene is a tabletop after the RoboEXP tasks: a table, a two-door cabinet (hollow, so an
opened door shows its inside) with a handle on each door, and two cups far apart. Frames come
from `test_perception_scene.render`, with depth noise where the test is about robustness.
"""

from __future__ import annotations

import numpy as np
import pytest

from agent.mapping.camera import Intrinsics
from agent.perception.instances import Instance, MemoryConfig
from agent.perception.memory import InstanceMemory
from test_perception_scene import INTRINSICS, Box, Front, look_at, render, storage

TABLE = Box.at(1, "table", (0.0, 0.1, 0.73), (1.6, 0.9, 0.04))
CABINET_ID, LEFT_DOOR, LEFT_HANDLE, RIGHT_DOOR, RIGHT_HANDLE = 2, 3, 4, 5, 6
FRONTS = (Front("door", (0.152, 0.348), (0.77, 1.13), "left"), Front("door", (0.352, 0.548), (0.77, 1.13), "right"))
CABINET = storage(CABINET_ID, "cabinet", (0.15, 0.55), (0.23, 0.53), (0.75, 1.15), FRONTS)
CUP_A = Box.at(7, "cup", (-0.5, 0.05, 0.8), (0.08, 0.08, 0.1))
CUP_B = Box.at(8, "cup", (-0.05, -0.05, 0.8), (0.08, 0.08, 0.1))
SCENE = [TABLE, *CABINET, CUP_A, CUP_B]
TARGET = (0.0, 0.2, 0.85)
VIEW_A = look_at((-0.3, -0.9, 1.4), TARGET)
VIEW_B = look_at((0.3, -0.85, 1.3), TARGET)


def _integrate(memory: InstanceMemory, boxes, pose, noise_m: float = 0.0, seed: int = 0, relabel=None):
    depth, seg, labels = render(boxes, pose, noise_m=noise_m, rng=np.random.default_rng(seed))
    if relabel is not None:  # another frame, other segmentation ids: they must not matter
        table = np.arange(max(seg.max(), *relabel) + 1)
        table[list(relabel)] = list(relabel.values())
        seg = np.where(seg >= 0, table[np.maximum(seg, 0)], -1).astype(np.int32)
        labels = {relabel.get(i, i): label for i, label in labels.items()}
    return memory.integrate_frame(depth, seg, labels, INTRINSICS, pose)


def _labels(memory: InstanceMemory) -> list[str]:
    return sorted(inst.label for inst in memory.live())


def _holding(memory: InstanceMemory, label: str, box: Box, tol: float = 0.02) -> Instance:
    """The one live ``label`` instance whose voxels lie in ``box`` (grown by ``tol``)."""
    lo, hi = np.asarray(box.lo) - tol, np.asarray(box.hi) + tol
    found = [inst for inst in memory.with_label(label)
             if np.all(inst.bounds[0] >= lo) and np.all(inst.bounds[1] <= hi)]
    assert len(found) == 1, f"{len(found)} {label} instances inside {box}"
    return found[0]


def _part(boxes, id: int) -> Box:
    """The bounding box of every box with segmentation id ``id``."""
    parts = [b for b in boxes if b.id == id]
    return Box(id, parts[0].label, tuple(np.min([b.lo for b in parts], axis=0)), tuple(np.max([b.hi for b in parts], axis=0)))


@pytest.fixture
def two_views() -> InstanceMemory:
    """The scene seen from two sides with 2 mm depth noise; the second frame renumbers every id."""
    memory = InstanceMemory()
    _integrate(memory, SCENE, VIEW_A, noise_m=0.002, seed=1)
    shuffled = {1: 41, 2: 47, 3: 45, 4: 44, 5: 43, 6: 42, 7: 48, 8: 46}  # cups swap, doors swap, ...
    update = _integrate(memory, SCENE, VIEW_B, noise_m=0.002, seed=2, relabel=shuffled)
    memory.last_update = update  # type: ignore[attr-defined]
    return memory


def test_the_same_things_seen_from_two_views_merge_into_one_instance_each(two_views: InstanceMemory) -> None:
    assert _labels(two_views) == ["cabinet", "cup", "cup", "door", "door", "handle", "handle", "table"]
    update = two_views.last_update  # type: ignore[attr-defined]
    assert update.created == () and len(update.updated) == 8
    cabinet = _holding(two_views, "cabinet", _part(CABINET, CABINET_ID))
    assert cabinet.first_seen == 0 and cabinet.last_seen == 1
    # the second view saw more of the carcass than the first: the merged instance spans both
    assert cabinet.voxel_count > 0 and np.allclose(cabinet.extent, (0.4, 0.3, 0.4), atol=0.03)


def test_two_cups_far_apart_stay_two_instances(two_views: InstanceMemory) -> None:
    a, b = _holding(two_views, "cup", CUP_A), _holding(two_views, "cup", CUP_B)
    assert a.id != b.id
    for inst, box in ((a, CUP_A), (b, CUP_B)):
        assert np.linalg.norm(inst.centroid[:2] - box.center[:2]) < 0.04
        assert inst.hint in (box.id, {7: 48, 8: 46}[box.id])  # kept, as a hint only


def test_two_doors_side_by_side_stay_two_and_each_handle_finds_its_own(two_views: InstanceMemory) -> None:
    left = _holding(two_views, "door", _part(CABINET, LEFT_DOOR))
    right = _holding(two_views, "door", _part(CABINET, RIGHT_DOOR))
    cabinet = _holding(two_views, "cabinet", _part(CABINET, CABINET_ID))
    left_handle = _holding(two_views, "handle", _part(CABINET, LEFT_HANDLE))
    right_handle = _holding(two_views, "handle", _part(CABINET, RIGHT_HANDLE))
    assert left_handle.parent == left.id and right_handle.parent == right.id
    assert left.parent == cabinet.id and right.parent == cabinet.id
    assert sorted(cabinet.children) == sorted([left.id, right.id])
    assert left.children == [left_handle.id] and right.children == [right_handle.id]
    for other in ("table", "cup"):
        assert all(inst.parent is None for inst in two_views.with_label(other))


def test_a_part_seen_before_its_parent_is_attached_once_the_parent_is_seen() -> None:
    memory = InstanceMemory()
    doors_only = [b for b in SCENE if b.id != CABINET_ID]
    _integrate(memory, doors_only, VIEW_A)
    door = _holding(memory, "door", _part(CABINET, LEFT_DOOR))
    assert door.parent is None
    _integrate(memory, SCENE, VIEW_A)
    cabinet = _holding(memory, "cabinet", _part(CABINET, CABINET_ID))
    assert memory.get(door.id).parent == cabinet.id


def test_moving_a_cup_away_forgets_it_while_occluded_and_unseen_things_are_kept() -> None:
    memory = InstanceMemory()
    _integrate(memory, SCENE, VIEW_A)
    old_a, cup_b = _holding(memory, "cup", CUP_A), _holding(memory, "cup", CUP_B)
    kept = {inst.id: inst.voxel_count for inst in memory.live() if inst.id != old_a.id}
    moved_a = Box.at(7, "cup", (-0.6, -0.25, 0.8), (0.08, 0.08, 0.1))
    eye = VIEW_A[:3, 3]
    screen = Box.at(9, "tray", eye + 0.45 * (CUP_B.center - eye), (0.25, 0.02, 0.25))  # hides cup B entirely
    update = _integrate(memory, [TABLE, *CABINET, moved_a, CUP_B, screen], VIEW_A)
    assert old_a.id in update.gone and memory.get(old_a.id).gone
    assert memory.get(old_a.id).voxel_count == 0
    new_a = _holding(memory, "cup", moved_a)
    assert new_a.id != old_a.id and new_a.id in update.created
    assert memory.get(cup_b.id).voxel_count == kept[cup_b.id]  # occluded, not stale
    assert cup_b.id not in update.shrunk
    # a frame looking away from the table (a wall behind the robot) changes nothing it cannot see
    before = {inst.id: inst.voxel_count for inst in memory.live()}
    wall = Box(30, "wall", (-3.0, -3.0, 0.0), (3.0, -2.9, 3.0))
    away = look_at(eye, eye + np.array([0.0, -1.0, 0.0]))
    update = _integrate(memory, [wall], away)
    assert update.shrunk == {} and update.gone == ()
    assert all(memory.get(i).voxel_count == n for i, n in before.items())
    assert {i for i in kept if i != cup_b.id} <= set(before)


def test_opening_a_door_forgets_the_closed_door_and_its_handle() -> None:
    memory = InstanceMemory()
    _integrate(memory, SCENE, VIEW_B)
    door = _holding(memory, "door", _part(CABINET, RIGHT_DOOR))
    handle = _holding(memory, "handle", _part(CABINET, RIGHT_HANDLE))
    closed_count = door.voxel_count
    # the right door swung 90 degrees about its right edge (x = 0.548, y = 0.21): it now stands
    # along -y from the hinge and its handle points back at the left door
    open_door = Box(RIGHT_DOOR, "door", (0.528, 0.014, 0.77), (0.548, 0.21, 1.13))
    open_handle = Box.at(RIGHT_HANDLE, "handle", (0.583, 0.21 - 0.196 + 0.04, 0.95), (0.016, 0.016, 0.144))
    opened = [b for b in SCENE if b.id not in (RIGHT_DOOR, RIGHT_HANDLE)] + [open_door, open_handle]
    update = _integrate(memory, opened, VIEW_B)
    assert update.shrunk[door.id] > 0.8 * closed_count
    assert handle.id in update.gone
    centre = np.array([0.45, 0.215, 0.95])  # the middle of the closed door: nothing is remembered there now
    assert all(np.min(np.linalg.norm(inst.points() - centre, axis=1)) > 0.05 for inst in memory.live())
    # the hinge strip of the closed door is hidden behind the open one, not stale: the open door
    # overlaps it and carries on as the same instance, with the new handle as its child
    assert door.id in update.updated and not memory.get(door.id).gone
    new_handle = _holding(memory, "handle", open_handle)
    assert new_handle.parent == door.id and memory.get(door.id).children == [new_handle.id]
    assert _holding(memory, "door", open_door, tol=0.03).id == door.id


def test_a_caller_that_moved_a_thing_can_say_it_is_the_same_thing() -> None:
    memory = InstanceMemory()
    _integrate(memory, SCENE, VIEW_A)
    old_a = _holding(memory, "cup", CUP_A)
    moved_a = Box.at(7, "cup", (-0.6, -0.25, 0.8), (0.08, 0.08, 0.1))
    _integrate(memory, [TABLE, *CABINET, moved_a, CUP_B], VIEW_A)
    new_a = _holding(memory, "cup", moved_a)
    assert old_a.gone and new_a.id != old_a.id
    kept = memory.merge(old_a.id, new_a.id)  # the pick skill knows it moved cup A
    assert kept.id == old_a.id and not kept.gone and kept.voxel_count == new_a.voxel_count
    assert memory.get(new_a.id) is kept and _holding(memory, "cup", moved_a) is kept
    with pytest.raises(ValueError, match="other"):
        memory.merge(kept.id, _holding(memory, "table", TABLE).id)


def test_a_frame_whose_parts_disagree_is_refused_by_name() -> None:
    memory = InstanceMemory()
    depth, seg, labels = render(SCENE, VIEW_A)
    with pytest.raises(ValueError, match="depth"):
        memory.integrate_frame(depth[:-1], seg, labels, INTRINSICS, VIEW_A)
    with pytest.raises(ValueError, match="labels"):
        memory.integrate_frame(depth, seg, {k: v for k, v in labels.items() if k != 7}, INTRINSICS, VIEW_A)
    with pytest.raises(ValueError, match="camera_to_world"):
        memory.integrate_frame(depth, seg, labels, INTRINSICS, 2 * VIEW_A)
    with pytest.raises(ValueError, match="memory.merge_iou"):
        MemoryConfig(merge_iou=0.0)
    assert memory.frame == -1 and memory.instances == {}


def test_an_observation_object_is_accepted_as_it_comes() -> None:
    from agent.observation import InstanceLabel, Observation

    depth, seg, labels = render(SCENE, VIEW_A)
    entries = tuple(InstanceLabel(i, c, "white") for i, c in sorted(labels.items()))
    rgb = np.zeros((INTRINSICS.height, INTRINSICS.width, 3), np.uint8)
    observation = Observation(rgb, depth, seg, entries, INTRINSICS, VIEW_A, (0.0, -0.9, 0.0))
    memory = InstanceMemory()
    update = memory.integrate(observation)
    assert len(update.created) == 8 and all(inst.colour == "white" for inst in memory.live())
    assert isinstance(INTRINSICS, Intrinsics)


def test_voxel_keys_pack_round_trip_and_tolerant_overlap() -> None:
    from agent.perception.voxels import dilate, keys_of, near_count, pack, unpack

    rng = np.random.default_rng(12)
    indices = rng.integers(-5000, 5000, (200, 3))
    assert np.array_equal(unpack(pack(indices)), indices)
    keys, hits = keys_of(np.array([[0.001, -0.001, 0.0], [0.002, -0.002, 0.001], [0.5, 0.5, 0.5]]), 0.01)
    assert len(keys) == 2 and sorted(hits.tolist()) == [1, 2]
    assert unpack(keys[hits == 2]).tolist() == [[0, -1, 0]]
    assert len(dilate(pack(np.array([[0, 0, 0]])))) == 27
    a = pack(np.array([[0, 0, 0], [10, 0, 0]]))
    assert near_count(a, np.sort(pack(np.array([[1, 1, 1]])))) == 1  # one voxel off still counts
    assert near_count(a, np.sort(pack(np.array([[2, 0, 0]])))) == 0
    with pytest.raises(ValueError, match="voxel indices"):
        pack(np.array([[1 << 21, 0, 0]]))


def test_a_thing_seen_in_two_pieces_keeps_the_identity_it_was_first_known_by() -> None:
    # The left end of a book is seen first, then, in a frame without it, the rest of it: two
    # instances. A frame of the whole book is both; the older one lives on, though the newer,
    # bigger piece is the better match: the explorer has acted on the thing by its first id.
    memory = InstanceMemory()
    left = Box.at(9, "book", (-0.27, 0.0, 0.77), (0.1, 0.15, 0.04))
    rest = Box.at(9, "book", (0.0, 0.0, 0.77), (0.36, 0.15, 0.04))
    whole = Box.at(9, "book", (-0.05, 0.0, 0.77), (0.46, 0.15, 0.04))  # the left end's edge lies beyond it
    screen = Box.at(10, "box", (-0.28, -0.3, 0.85), (0.22, 0.02, 0.3))  # hides the left end from VIEW_A
    _integrate(memory, [TABLE, left], VIEW_A)
    first = _holding(memory, "book", left)
    _integrate(memory, [TABLE, screen, rest], VIEW_A)
    second = _holding(memory, "book", rest)
    assert second.id != first.id
    update = _integrate(memory, [TABLE, whole], VIEW_A)
    assert update.absorbed == {second.id: first.id}
    assert _holding(memory, "book", whole, tol=0.05).id == first.id


def test_a_low_drawer_belongs_to_its_own_chest_not_to_the_one_beside_it() -> None:
    # drawer-only 1024 (tuning-wide): two chests of drawers 2 cm apart; of the left one only the
    # top board shows above its fronts, 26 cm over its lowest drawer, while the right chest's side
    # board stands within adjacency of that drawer's edge. The drawer went to the right chest.
    drawers = [Front("drawer", (-0.338, 0.058), z) for z in ((0.77, 0.89), (0.90, 1.01), (1.02, 1.13))]
    left = [b for b in storage(20, "drawer chest", (-0.34, 0.06), (0.25, 0.55), (0.75, 1.15), drawers)
            if b.id != 20 or b.lo[2] > 1.0]  # the carcass shows only its top board
    right = storage(30, "drawer chest", (0.08, 0.50), (0.25, 0.55), (0.75, 1.15),
                    [Front("drawer", (0.082, 0.498), f.z) for f in drawers])
    memory = InstanceMemory()
    _integrate(memory, [TABLE, *left, *right], look_at((0.1, -0.8, 1.5), (0.1, 0.3, 0.95)))
    left_chest = _holding(memory, "drawer chest", _part(left, 20))
    right_chest = _holding(memory, "drawer chest", _part(right, 30))
    for k in range(3):
        assert memory.get(_holding(memory, "drawer", _part(left, 21 + 2 * k)).id).parent == left_chest.id, k
        assert memory.get(_holding(memory, "drawer", _part(right, 31 + 2 * k)).id).parent == right_chest.id, k


def test_a_sliver_of_a_thing_s_far_side_seen_alone_is_that_thing() -> None:
    # drawer-only 1 (tuning): looking into a drawer, the wrist camera saw only the lower edge of
    # the far side of a book on the table, a voxel beyond the box of the book the head camera saw
    # from the front (its top and near side), and touching none of its voxels: a second book.
    memory = InstanceMemory()
    book = Box.at(9, "book", (-0.06, -0.25, 0.775), (0.16, 0.23, 0.05))
    _integrate(memory, [TABLE, book], VIEW_A)
    first = _holding(memory, "book", book)
    (x0, _, z0), (x1, y1, _) = book.lo, book.hi
    sliver = Box(9, "book", (x0, y1 - 0.004, z0), (x1, y1 + 0.008, z0 + 0.02))  # all this view sees of it
    _integrate(memory, [TABLE, sliver], look_at((0.0, 0.5, 1.2), (0.0, -0.2, 0.77)))
    assert [inst.id for inst in memory.with_label("book")] == [first.id]
