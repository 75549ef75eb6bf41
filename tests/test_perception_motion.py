"""Things that move and things seen together: `InstanceMemory.move`, `fit_opening`, co-visibility,
relations of moved and opened things, and parts attached by footprint.

Frames are ray-cast from axis-aligned boxes (`test_perception_scene.render`); where a test is
about exact voxel arithmetic, instances are built from known voxel centres instead.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial import cKDTree

from agent.acsg.from_memory import memory_detections
from agent.perception.instances import Instance
from agent.perception.memory import InstanceMemory
from agent.perception.opening import fit_opening, opening_seen
from agent.perception.part_geometry import PartGeometry
from agent.perception.part_motion import part_motion, rotation_about
from agent.perception.voxels import pack, voxel_indices
from test_perception_scene import FRONT, INTRINSICS, Box, Front, handle_boxes, look_at, render, storage

VOXEL = 0.01
TABLE = Box.at(1, "table", (0.0, 0.1, 0.73), (1.6, 0.9, 0.04))  # top at z = 0.75
EYE = np.array([-0.25, -0.9, 1.45])


def _see(memory: InstanceMemory, boxes, eye=EYE, target=(0.1, 0.3, 0.9)):
    """Integrate one noiseless frame of ``boxes`` from ``eye``; returns the `FrameUpdate`."""
    pose = look_at(eye, target)
    depth, seg, labels = render(boxes, pose)
    return memory.integrate_frame(depth, seg, labels, INTRINSICS, pose)


def _one(memory: InstanceMemory, label: str) -> Instance:
    found = memory.with_label(label)
    assert len(found) == 1, f"{len(found)} live {label} instances"
    return found[0]


def _holding(memory: InstanceMemory, label: str, box: Box, tol: float = 0.02) -> Instance:
    """The one live ``label`` instance whose voxels lie in ``box`` grown by ``tol``."""
    lo, hi = np.asarray(box.lo) - tol, np.asarray(box.hi) + tol
    found = [inst for inst in memory.with_label(label) if np.all(inst.bounds[0] >= lo) and np.all(inst.bounds[1] <= hi)]
    assert len(found) == 1, f"{len(found)} {label} instances inside {box}"
    return found[0]


def _shifted(boxes, offset) -> list[Box]:
    d = np.asarray(offset, float)
    return [Box(b.id, b.label, tuple(np.asarray(b.lo) + d), tuple(np.asarray(b.hi) + d)) for b in boxes]


def _planted(memory: InstanceMemory, label: str, points: np.ndarray, hits: np.ndarray | None = None) -> Instance:
    """An instance put straight into the memory from known points (one voxel per point given)."""
    per_point = pack(voxel_indices(points, VOXEL))
    keys = np.unique(per_point)
    assert len(keys) == len(points), "each planted point must fall in its own voxel"
    counts = np.ones(len(keys), np.int32) if hits is None else np.asarray(hits, np.int32)[np.argsort(per_point)]
    # (np.unique sorts, so the hits given per point go in the order of their keys)
    inst = Instance(max(memory.instances, default=-1) + 1, label, None, keys, counts, VOXEL, 0, 0, frames={0})
    memory.instances[inst.id] = inst
    return inst


def _grid(lo, hi) -> np.ndarray:
    """Voxel centres of every voxel in the integer range [lo, hi) (voxel indices per axis)."""
    axes = [np.arange(a, b) for a, b in zip(lo, hi)]
    return (np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3) + 0.5) * VOXEL


# --- InstanceMemory.move -----------------------------------------------------------------------

#: A drawer chest facing -y with two stacked drawers, each with a handle (ids 10..14).
CHEST = storage(10, "drawer chest", (-0.2, 0.2), (0.23, 0.53), (0.75, 1.1),
                (Front("drawer", (-0.198, 0.198), (0.77, 0.93)), Front("drawer", (-0.198, 0.198), (0.932, 1.08))))
LOW_DRAWER, LOW_HANDLE, TOP_DRAWER, TOP_HANDLE = 11, 12, 13, 14


def _chest_memory() -> InstanceMemory:
    memory = InstanceMemory()
    _see(memory, [TABLE, *CHEST])
    return memory


def _part_box(boxes, id: int) -> Box:
    parts = [b for b in boxes if b.id == id]
    lo, hi = np.min([b.lo for b in parts], axis=0), np.max([b.hi for b in parts], axis=0)
    return Box(id, parts[0].label, tuple(lo), tuple(hi))


def test_a_translation_carries_a_drawer_and_its_handle_and_nothing_else() -> None:
    memory = _chest_memory()
    top = _holding(memory, "drawer", _part_box(CHEST, TOP_DRAWER))
    low = _holding(memory, "drawer", _part_box(CHEST, LOW_DRAWER))
    handle = _holding(memory, "handle", _part_box(CHEST, TOP_HANDLE))
    chest, table = _one(memory, "drawer chest"), _one(memory, "table")
    assert handle.parent == top.id and top.parent == chest.id  # what the move follows
    untouched = {inst.id: inst.keys.copy() for inst in memory.live() if inst.id not in (top.id, handle.id)}
    before = {inst.id: (inst.centroid, inst.voxel_count, int(inst.hits.sum())) for inst in (top, handle)}
    shift = np.array([0.013, -0.2137, 0.004])  # not a whole number of voxels: re-quantised
    motion = np.eye(4)
    motion[:3, 3] = shift

    moved = memory.move(top.id, motion)

    assert sorted(moved) == sorted([top.id, handle.id])
    for inst in (top, handle):
        centroid, count, hits = before[inst.id]
        assert np.all(np.abs(inst.centroid - (centroid + shift)) <= VOXEL / 2 + 1e-9)
        assert inst.voxel_count == count and int(inst.hits.sum()) == hits  # a translation is one-to-one
        assert np.all(np.diff(inst.keys) > 0)  # still a sorted set
    assert {low.id, chest.id, table.id} <= set(untouched)
    for inst_id, keys in untouched.items():
        assert np.array_equal(memory.get(inst_id).keys, keys), f"instance {inst_id} moved"


def test_moving_a_piece_carries_its_parts_recursively() -> None:
    memory = _chest_memory()
    chest = _one(memory, "drawer chest")
    family = {chest.id, *chest.children, *(c for d in chest.children for c in memory.get(d).children)}
    assert len(family) == 5  # the chest, two drawers, two handles
    centroids = {i: memory.get(i).centroid for i in family}
    table_keys = _one(memory, "table").keys.copy()
    motion = np.eye(4)
    motion[:3, 3] = (0.5, 0.0, 0.0)
    assert sorted(memory.move(chest.id, motion)) == sorted(family)
    for inst_id in family:
        assert np.allclose(memory.get(inst_id).centroid, centroids[inst_id] + (0.5, 0.0, 0.0), atol=VOXEL / 2)
    assert np.array_equal(_one(memory, "table").keys, table_keys)


def test_a_quarter_turn_about_a_vertical_axis_maps_a_known_point_set() -> None:
    memory = InstanceMemory()
    # an L of voxels, long along +x, with a foot along +y and a second layer at one end: no symmetry
    points = np.vstack([_grid((10, 20, 80), (30, 22, 81)), _grid((10, 22, 80), (12, 30, 81)),
                        _grid((28, 20, 81), (30, 22, 84))])
    thing = _planted(memory, "box", points)
    pivot = np.array([0.055, 0.105, 0.0])  # a vertical axis through a voxel centre's x, y
    rotation = rotation_about(np.array([0.0, 0.0, 1.0]), math.pi / 2)
    motion = np.eye(4)
    motion[:3, :3], motion[:3, 3] = rotation, pivot - rotation @ pivot
    expected = (points - pivot) @ rotation.T + pivot  # x, y -> pivot + (-(y - py), x - px)

    assert memory.move(thing.id, motion) == [thing.id]

    got = thing.points()
    assert len(got) == len(points)
    # every moved voxel lies within one voxel of where its point went, and every point is covered
    assert np.max(np.abs(got - expected[cKDTree(expected).query(got)[1]])) <= VOXEL + 1e-9
    assert np.max(np.abs(expected - got[cKDTree(got).query(expected)[1]])) <= VOXEL + 1e-9
    # the far end of the L's long arm (x = 0.295, y = 0.205) went to x = 0.055 - 0.1, y = 0.105 + 0.24
    assert np.min(np.linalg.norm(got[:, :2] - (-0.045, 0.345), axis=1)) <= VOXEL
    assert np.allclose(got[:, 2].mean(), points[:, 2].mean())  # a vertical axis keeps heights


def test_voxels_landing_together_keep_the_sum_of_their_hits() -> None:
    memory = InstanceMemory()
    points = _grid((0, 0, 50), (12, 12, 53))
    hits = np.arange(1, len(points) + 1)  # every voxel a different count
    thing = _planted(memory, "box", points, hits=hits)
    assert int(thing.hits.sum()) == int(hits.sum())
    motion = np.eye(4)
    motion[:3, :3] = rotation_about(np.array([0.0, 0.0, 1.0]), math.radians(45))
    motion[:3, 3] = (0.3, -0.1, 0.02)

    memory.move(thing.id, motion)

    assert thing.voxel_count < len(points)  # at 45 degrees some voxels fall into one
    assert int(thing.hits.sum()) == int(hits.sum())
    assert thing.hits.dtype == np.int32 and np.all(np.diff(thing.keys) > 0)


def test_a_motion_that_is_not_a_finite_4x4_is_refused_by_name_and_changes_nothing() -> None:
    memory = InstanceMemory()
    thing = _planted(memory, "box", _grid((0, 0, 0), (3, 3, 3)))
    keys = thing.keys.copy()
    bad = np.eye(4)
    bad[0, 3] = np.nan
    for motion in (np.eye(3), np.eye(4)[:3], bad, np.full((4, 4), np.inf)):
        with pytest.raises(ValueError, match="motion"):
            memory.move(thing.id, motion)
    assert np.array_equal(thing.keys, keys)


def test_a_drawer_moved_as_it_really_moved_is_found_again_where_it_now_is() -> None:
    """The point of `move`: after a skill pulls a drawer 20 cm out and says so, the next view of the
    drawer merges with it; without the move, the same view makes a new drawer (the control)."""
    pull = np.array([0.0, -0.2, 0.0])
    opened = [b for b in CHEST if b.id not in (TOP_DRAWER, TOP_HANDLE)]
    opened += _shifted([b for b in CHEST if b.id in (TOP_DRAWER, TOP_HANDLE)], pull)
    motion = np.eye(4)
    motion[:3, 3] = pull

    control = _chest_memory()
    update = _see(control, [TABLE, *opened])
    assert any(control.get(i).label == "drawer" for i in update.created)  # the view alone makes a new drawer

    memory = _chest_memory()
    top = _holding(memory, "drawer", _part_box(CHEST, TOP_DRAWER))
    handle = _holding(memory, "handle", _part_box(CHEST, TOP_HANDLE))
    memory.move(top.id, motion)
    update = _see(memory, [TABLE, *opened])
    assert update.created == () and update.absorbed == {}
    assert top.id in update.updated and handle.id in update.updated
    assert len(memory.with_label("drawer")) == 2 and len(memory.with_label("handle")) == 2
    assert _holding(memory, "drawer", _part_box(_shifted(CHEST, pull), TOP_DRAWER)) is top
    assert handle.parent == top.id and top.children == [handle.id]


#: A box 9 cm tall on the table, and a smaller one beside it, each picked away in the tests below.
BOX = Box.at(20, "box", (0.25, 0.35, 0.795), (0.2, 0.2, 0.09))
SMALL_BOX = Box.at(21, "box", (-0.05, 0.35, 0.8), (0.1, 0.1, 0.1))
PUT_DOWN = np.array([-0.75, -0.25, 0.0])  # where the big box is carried to, across the table


def _picked_away(memory: InstanceMemory, height_guess: float) -> Instance:
    """Remember the two boxes, then move the big one as a pick that took it for ``height_guess``
    tall says: to ``PUT_DOWN``, and up by how much taller it was taken than it is (its top is
    put down ``height_guess`` over the table)."""
    _see(memory, [TABLE, BOX, SMALL_BOX])
    box = _holding(memory, "box", BOX)
    motion = np.eye(4)
    motion[:3, 3] = PUT_DOWN + [0.0, 0.0, height_guess - (BOX.hi[2] - BOX.lo[2])]
    memory.move(box.id, motion, carried=True)
    return box


@pytest.mark.parametrize("height_guess", [0.25, 0.09])
def test_a_thing_put_down_is_the_thing_seen_where_it_was_put_whatever_height_it_was_taken_for(height_guess) -> None:
    """A box whose bottom the memory did not see was taken as 25 cm tall and put down by where its
    top would be: its voxels, moved up 16 cm, hang in the air over it, the next view looks through
    them all, and the box seen there was a new thing while the one moved was gone (its pick back
    then kept off the box itself and found no route: recursive 1178 of tuning-wide). Where the
    caller moved it, the box seen is the one moved, taller guess or right one; the box beside it,
    and a new box seen where it was picked from, are not."""
    memory = InstanceMemory()
    box = _picked_away(memory, height_guess)
    small = _holding(memory, "box", SMALL_BOX)
    inner = Box.at(22, "box", (0.25, 0.35, 0.775), (0.1, 0.1, 0.05))  # what the big box hid, now in sight
    put = _shifted([BOX], PUT_DOWN)[0]

    update = _see(memory, [TABLE, put, SMALL_BOX, inner])

    assert box.id not in update.gone and not box.gone
    assert _holding(memory, "box", put) is box and box.id in update.updated
    assert _holding(memory, "box", SMALL_BOX) is small
    assert [memory.get(i).label for i in update.created] == ["box"]  # the one it hid, and only it
    assert _holding(memory, "box", inner).id in update.created
    assert box.moved_to is None  # seen: the next view matches it by its voxels alone


def test_without_the_move_the_thing_put_down_is_a_new_thing_and_the_one_picked_is_gone() -> None:
    """The control: voxels moved 16 cm too high with nothing said of where the thing went make the
    box seen a new one, as it was before the memory kept where a caller moved a thing to (its
    voxels the view does not look through are left hanging)."""
    memory = InstanceMemory()
    box = _picked_away(memory, 0.25)
    box.moved_to = None
    update = _see(memory, [TABLE, _shifted([BOX], PUT_DOWN)[0], SMALL_BOX])
    assert len(update.created) == 1 and box.id not in update.updated


def test_a_thing_moved_elsewhere_does_not_take_a_detection_of_its_label_that_stands_apart() -> None:
    """The box moved is not another box of its label seen anew away from where it was put."""
    memory = InstanceMemory()
    box = _picked_away(memory, 0.09)
    elsewhere = Box.at(23, "box", (0.55, 0.05, 0.8), (0.1, 0.1, 0.1))
    update = _see(memory, [TABLE, SMALL_BOX, elsewhere], target=(0.4, 0.2, 0.8))
    assert _holding(memory, "box", elsewhere).id in update.created
    assert box.id not in update.updated and box.moved_to is not None


# --- fit_opening -------------------------------------------------------------------------------


def _unit(v) -> np.ndarray:
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def _panel(centre: np.ndarray, across: np.ndarray, up: np.ndarray, width: float, height: float) -> np.ndarray:
    """Points on a flat front, 1 cm apart."""
    u, v = np.meshgrid(np.arange(-width / 2, width / 2, 0.01), np.arange(-height / 2, height / 2, 0.01))
    return centre + u.reshape(-1, 1) * across + v.reshape(-1, 1) * up


def _carried(geometry: PartGeometry, points: np.ndarray, amount: float) -> np.ndarray:
    motion = part_motion(geometry, amount)
    return points @ motion[:3, :3].T + motion[:3, 3]


def test_a_drawer_held_back_by_its_travel_is_read_where_it_stopped_from_part_of_its_front() -> None:
    drawer = PartGeometry("drawer", np.array([0.0, 0.0, 0.9]), np.array([1.0, 0.0, 0.0]), np.array([0.0, -1.0, 0.0]))
    front = _panel(np.array([0.0, 0.0, 0.9]), np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0]), 0.4, 0.15)
    seen = _carried(drawer, front, 0.162)
    seen = seen[seen[:, 0] < 0.05]  # only the left part is in view
    amount, residual = fit_opening(drawer, front, seen, 1.25 * 0.19)  # the hand says 0.19 m
    assert amount == pytest.approx(0.162, abs=0.004) and residual < 0.005


def test_a_door_stopped_short_of_its_swing_is_read_at_its_angle() -> None:
    hinge, handle = np.array([0.3, 0.0, 0.5]), np.array([-0.3, 0.0, 0.5])
    door = PartGeometry("door", handle, np.array([0.0, 0.0, 1.0]), np.array([0.0, -1.0, 0.0]), hinge,
                        np.array([0.0, 0.0, 1.0]))
    panel = _panel(np.array([0.0, 0.0, 0.5]), np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0]), 0.6, 0.8)
    assert (_carried(door, handle[None], 0.3)[0] - handle) @ door.normal > 0  # opening moves the handle out
    for angle in (0.0, 0.5, 0.946, 1.3):
        amount, _ = fit_opening(door, panel, _carried(door, panel, angle), 1.25 * 1.3)
        assert amount == pytest.approx(angle, abs=0.025), angle


def test_the_opening_is_read_off_the_part_itself_not_the_neighbour_seen_where_it_hides() -> None:
    """A chest's second drawer pulled 0.2 m: with its handle hidden behind the arm, the handle seen
    nearest to where it should be is the closed one of the drawer below, 0.12 m lower; read off that,
    the drawer seemed shut (0.003 m) and its frames never went to the VLM."""
    drawer = PartGeometry("drawer", np.array([0.0, 0.0, 0.9]), np.array([1.0, 0.0, 0.0]), np.array([0.0, -1.0, 0.0]))
    handle = _panel(np.array([0.0, -0.02, 0.9]), np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0]), 0.12, 0.03)
    below = handle - np.array([0.0, 0.0, 0.12])
    opened = _carried(drawer, handle, 0.2)
    assert np.linalg.norm(below.mean(axis=0) - opened.mean(axis=0)) < 0.25  # near enough to be taken for it
    assert opening_seen(drawer, handle, [below], 0.2, near_m=0.25, fit_m=0.03) is None
    assert opening_seen(drawer, handle, [below, opened], 0.2, near_m=0.25, fit_m=0.03) == pytest.approx(0.2, abs=0.004)
    assert opening_seen(drawer, handle, [opened + np.array([0.0, 0.0, 0.3])], 0.2, near_m=0.25, fit_m=0.03) is None


def test_fit_opening_refuses_too_few_points_by_name() -> None:
    drawer = PartGeometry("drawer", np.zeros(3), np.array([1.0, 0.0, 0.0]), np.array([0.0, -1.0, 0.0]))
    with pytest.raises(ValueError, match="seen_points"):
        fit_opening(drawer, np.zeros((10, 3)), np.zeros((1, 3)), 0.2)


# --- co-visibility ------------------------------------------------------------------------------

#: Two drawer fronts stacked 2 mm apart, facing -y.
LOWER = Box(21, "drawer", (0.0, 0.2, 0.80), (0.4, 0.22, 0.95))
UPPER = Box(22, "drawer", (0.0, 0.2, 0.952), (0.4, 0.22, 1.10))
FRONT_EYE = np.array([0.2, -0.7, 1.3])
FRONT_TARGET = (0.2, 0.2, 0.95)


def _both_as_one(id: int = 23) -> list[Box]:
    """Both fronts under one segmentation id: a detector that took the two for one thing."""
    return [Box(id, "drawer", LOWER.lo, LOWER.hi), Box(id, "drawer", UPPER.lo, UPPER.hi)]


def test_drawers_seen_apart_are_not_merged_by_a_detection_spanning_both() -> None:
    memory = InstanceMemory()
    first = _see(memory, [LOWER, UPPER], FRONT_EYE, FRONT_TARGET)
    assert len(first.created) == 2
    lower, upper = _holding(memory, "drawer", LOWER), _holding(memory, "drawer", UPPER)
    update = _see(memory, _both_as_one(), FRONT_EYE, FRONT_TARGET)
    assert update.absorbed == {} and update.created == ()
    assert sorted(i.id for i in memory.with_label("drawer")) == sorted([lower.id, upper.id])
    assert memory.get(lower.id) is lower and memory.get(upper.id) is upper
    # and again from another view: still two
    update = _see(memory, _both_as_one(31), FRONT_EYE + (0.3, 0.1, 0.1), FRONT_TARGET)
    assert update.absorbed == {} and len(memory.with_label("drawer")) == 2


def test_a_fragment_of_a_piece_within_it_and_its_door_is_that_piece() -> None:
    """The head camera saw a cabinet's top and its door; the wrist camera then saw a corner of its
    plinth beside the door, sharing no surface with the top and outside its box. It became a second
    cabinet, in the graph before a later view merged the two, and the explorer tried to open it (a
    cabinet with no door). Lying within the box of the cabinet with its door, it is that cabinet."""
    top = Box(5, "cabinet", (0.0, 0.02, 1.2), (0.4, 0.4, 1.22))
    door = Box(6, "door", (0.0, 0.02, 0.76), (0.36, 0.04, 1.2))
    memory = InstanceMemory()
    _see(memory, [top, door], eye=(0.2, -0.7, 1.45), target=(0.2, 0.2, 1.0))
    cabinet, door_i = _one(memory, "cabinet"), _one(memory, "door")
    assert door_i.parent == cabinet.id  # the premise: the door is the cabinet's
    plinth = Box(9, "cabinet", (0.365, 0.02, 0.76), (0.4, 0.1, 0.82))
    lo, hi = cabinet.bounds
    assert plinth.lo[2] < lo[2]  # outside the top's own box
    update = _see(memory, [top, door, plinth], eye=(0.3, -0.5, 0.95), target=(0.38, 0.05, 0.8))
    assert update.created == () and _one(memory, "cabinet") is cabinet
    assert cabinet.bounds[0][2] < 0.83  # it holds the plinth's corner now


def test_pieces_never_seen_together_are_merged_when_a_detection_bridges_them() -> None:
    """Frame 0 shows only the lower front, frame 1 only the upper one (nothing behind the lower:
    no return, no evidence, so it is kept): two instances, never seen together. A detection
    spanning both then merges them into one, as before the co-visibility rule."""
    memory = InstanceMemory()
    _see(memory, [LOWER], FRONT_EYE, FRONT_TARGET)
    second = _see(memory, [UPPER], FRONT_EYE, FRONT_TARGET)
    assert len(second.created) == 1 and len(memory.with_label("drawer")) == 2
    a, b = sorted(memory.with_label("drawer"), key=lambda inst: inst.id)
    assert not a.frames & b.frames
    update = _see(memory, _both_as_one(), FRONT_EYE, FRONT_TARGET)
    assert len(update.absorbed) == 1 and set(update.absorbed.items()) <= {(a.id, b.id), (b.id, a.id)}
    merged = _one(memory, "drawer")
    assert memory.get(a.id) is merged and memory.get(b.id) is merged
    assert merged.frames == {0, 1, 2}
    lo, hi = merged.bounds
    assert lo[2] < 0.81 and hi[2] > 1.09  # it holds both fronts


def test_a_piece_detected_apart_in_the_same_frame_is_not_merged_either() -> None:
    """Co-visibility counts the frame being merged too. Frame 0 shows the lower front alone. Frame 1
    shows, apart, a thin strip (segment 5, a new instance: it is 5 cm above what is remembered) and a
    taller front (segment 6) whose top edge touches the strip: segment 6 matches both the lower front
    and the strip, which was just detected apart from it, so the strip stays its own instance."""
    memory = InstanceMemory()
    _see(memory, [LOWER], FRONT_EYE, FRONT_TARGET)
    lower = _one(memory, "drawer")
    strip = Box(5, "drawer", (0.0, 0.2, 1.002), (0.4, 0.22, 1.012))
    taller = Box(6, "drawer", LOWER.lo, (0.4, 0.22, 1.0))
    update = _see(memory, [strip, taller], FRONT_EYE, FRONT_TARGET)
    assert len(update.created) == 1 and update.absorbed == {}
    strip_i = memory.get(update.created[0])
    assert strip_i.bounds[0][2] > 0.99 and strip_i.frames == {memory.frame}
    assert sorted(i.id for i in memory.with_label("drawer")) == sorted([lower.id, strip_i.id])
    assert lower.id in update.updated and lower.bounds[1][2] > 0.99  # the taller front went to the lower


# --- relations read off the memory ---------------------------------------------------------------


def _relations(memory: InstanceMemory, **options) -> dict[int, tuple[str | None, str | None]]:
    return {int(d.instance): (d.parent, d.relation) for d in memory_detections(memory, EYE, **options)}


def test_a_thing_where_a_moved_thing_stood_lies_inside_what_was_there() -> None:
    cup = Box.at(7, "cup", (-0.1, 0.0, 0.8), (0.08, 0.08, 0.1))
    crate = Box.at(8, "crate", (0.4, 0.0, 0.81), (0.16, 0.16, 0.12))  # lifted off the cup, put down here
    memory = InstanceMemory()
    _see(memory, [TABLE, cup, crate])
    cup_i, crate_i, table_i = _one(memory, "cup"), _one(memory, "crate"), _one(memory, "table")
    assert _relations(memory)[cup_i.id] == (str(table_i.id), "on")
    where_it_was = (np.array([-0.18, -0.08, 0.75]), np.array([-0.02, 0.08, 0.87]))
    # the cup's own old place, just around it and smaller than the crate's: not a container of itself
    its_own = (np.array([-0.15, -0.05, 0.75]), np.array([-0.05, 0.05, 0.86]))
    relations = _relations(memory, vacated={crate_i.id: where_it_was, cup_i.id: its_own})
    assert relations[cup_i.id] == (str(crate_i.id), "inside")
    assert relations[crate_i.id] == (str(table_i.id), "on")  # nothing else changes
    assert relations[table_i.id] == (None, None)


def test_a_thing_whose_lowest_voxel_sinks_into_the_table_stands_on_it() -> None:
    """The table's highest voxels stand 2 cm over a mug's lowest (a lip at its back edge here; at a
    table's back corner, voxel noise did it): the mug still stands on the table (occlusion 1069 of
    tuning-wide, where it stood on nothing)."""
    lip = Box(1, "table", (-0.8, 0.5, 0.75), (0.8, 0.55, 0.76))
    mug = Box.at(6, "mug", (0.2, 0.1, 0.805), (0.1, 0.1, 0.11))
    memory = InstanceMemory()
    _see(memory, [TABLE, lip, mug])
    table_i, mug_i = _one(memory, "table"), _one(memory, "mug")
    assert table_i.bounds[1][2] - mug_i.bounds[0][2] == pytest.approx(0.02, abs=0.003)
    assert _relations(memory)[mug_i.id] == (str(table_i.id), "on")


def test_a_thing_under_a_box_seen_only_by_its_top_lies_inside_that_box_not_the_one_around_it() -> None:
    """A nest lifted apart: the outer box (seen whole from the side) and then the inner one (seen only
    from above, down inside the outer, by its top 4 cm) moved away, and a cup found where they stood.
    The cup's centre is below what was seen of the inner box; it lay under the inner box all the same
    (recursive 1066 and 1073 of tuning-wide), not loose in the outer one."""
    cup = Box.at(7, "cup", (0.0, 0.0, 0.795), (0.06, 0.06, 0.09))
    memory = InstanceMemory()
    _see(memory, [TABLE, cup])
    cup_i = _one(memory, "cup")
    outer = (np.array([-0.1, -0.1, 0.75]), np.array([0.1, 0.1, 0.9]))
    inner_top = (np.array([-0.075, -0.075, 0.84]), np.array([0.075, 0.075, 0.88]))
    assert cup_i.centroid[2] < inner_top[0][2]
    relations = _relations(memory, vacated={1001: outer, 1002: inner_top})
    assert relations[cup_i.id] == ("1002", "inside")
    beside = (np.array([0.05, -0.075, 0.84]), np.array([0.095, 0.075, 0.88]))  # not over the cup's centre
    assert _relations(memory, vacated={1001: outer, 1002: beside})[cup_i.id] == ("1001", "inside")


def _tray(id: int, x: tuple[float, float], y: tuple[float, float], z: tuple[float, float],
          t: float = 0.015) -> list[Box]:
    """An open drawer's body, one id: a bottom, two sides, a back and a front (facing -y)."""
    (x0, x1), (y0, y1), (z0, z1) = x, y, z
    return [Box(id, "drawer", lo, hi) for lo, hi in (
        ((x0, y0, z0), (x1, y1, z0 + t)), ((x0, y0, z0), (x0 + t, y1, z1)), ((x1 - t, y0, z0), (x1, y1, z1)),
        ((x0, y1 - t, z0), (x1, y1, z1)), ((x0, y0, z0), (x1, y0 + t, z1)))]


def test_a_thing_standing_in_an_open_drawer_lies_inside_the_drawer() -> None:
    """A chest's carcass (hollow, facing -y) with its drawer pulled 25 cm out and a bottle standing
    in it: both the chest (its box counts the drawer) and the drawer hold the bottle's centre; the
    smaller, the drawer, is what it lies inside."""
    (x0, x1), (y0, y1), (z0, z1) = (-0.2, 0.2), (0.23, 0.53), (0.75, 1.0)
    carcass = [b for b in storage(10, "drawer chest", (x0, x1), (y0, y1), (z0, z1), ()) if b.label == "drawer chest"]
    drawer = _tray(11, (x0 + 0.02, x1 - 0.02), (y0 - 0.25, y1 - 0.05), (0.80, 0.95))
    bottle = Box.at(15, "bottle", (0.0, 0.1, 0.815 + 0.05), (0.06, 0.06, 0.1))
    memory = InstanceMemory()
    _see(memory, [TABLE, *carcass, *drawer, bottle], eye=(-0.1, -0.8, 1.6), target=(0.0, 0.1, 0.85))
    chest, drawer_i, bottle_i = (_one(memory, label) for label in ("drawer chest", "drawer", "bottle"))
    assert drawer_i.parent == chest.id
    lo, hi = drawer_i.bounds
    assert np.all(lo + 0.01 <= bottle_i.centroid) and np.all(bottle_i.centroid <= hi - 0.01)  # the premise
    relations = _relations(memory)
    assert relations[bottle_i.id] == (str(drawer_i.id), "inside")
    assert relations[drawer_i.id] == (str(chest.id), "belongs")


def test_a_piece_seen_only_high_up_stands_on_the_table_its_drawers_reach_down_to() -> None:
    """A chest whose front is one tall drawer under a top board: its own voxels are all 20 cm above
    the table, its drawer's reach the table top; with its parts counted it stands on the table."""
    top_board = Box(10, "drawer chest", (-0.2, 0.23, 0.95), (0.2, 0.53, 0.968))
    front = Front("drawer", (-0.198, 0.198), (0.752, 0.948))
    drawer = Box(11, "drawer", (front.x[0], 0.23 - FRONT, front.z[0]), (front.x[1], 0.23, front.z[1]))
    memory = InstanceMemory()
    _see(memory, [TABLE, top_board, drawer, *handle_boxes(front, 12, 0.23 - FRONT)])
    chest, drawer_i, handle, table = (_one(memory, label) for label in ("drawer chest", "drawer", "handle", "table"))
    assert drawer_i.parent == chest.id and handle.parent == drawer_i.id
    assert chest.bounds[0][2] > 0.9 and drawer_i.bounds[0][2] < 0.76  # the premise
    relations = _relations(memory)
    assert relations[chest.id] == (str(table.id), "on")
    assert relations[table.id] == (None, None)


# --- parts attached by footprint -----------------------------------------------------------------


def test_a_drawer_far_from_its_chests_carcass_is_attached_to_the_piece_it_stands_under() -> None:
    """A chest whose carcass shows only as a top board, with two drawers below: the upper touches the
    board, the lower is 12 cm from it (beyond part_gap_m) and is attached by the board's footprint:
    not to the cabinet beside it (nearer, but its footprint does not hold the drawer), nor to the
    wall cabinet above (its footprint holds the drawer too, but its centre is farther). A drawer
    under no footprint stays without a parent."""
    top_board = Box(10, "drawer chest", (-0.2, 0.23, 1.0), (0.2, 0.53, 1.018))
    fronts = (Front("drawer", (-0.198, 0.198), (0.76, 0.88)), Front("drawer", (-0.198, 0.198), (0.882, 0.998)))
    y_face = 0.23 - FRONT
    boxes = [TABLE, top_board]
    for k, front in enumerate(fronts):
        boxes.append(Box(11 + 2 * k, "drawer", (front.x[0], y_face, front.z[0]), (front.x[1], 0.23, front.z[1])))
        boxes.extend(handle_boxes(front, 12 + 2 * k, y_face))
    cabinet = Box(20, "cabinet", (0.3, 0.23, 0.75), (0.6, 0.53, 0.95))  # beside the chest, nearer the low drawer
    wall_cabinet = Box(22, "cabinet", (-0.1, 0.23, 1.25), (0.5, 0.53, 1.45))  # over both: its footprint holds too
    stray = Box(21, "drawer", (-0.7, 0.0, 0.75), (-0.5, 0.2, 0.8))  # lying on the table, under nothing
    memory = InstanceMemory()
    _see(memory, [*boxes, cabinet, wall_cabinet, stray], target=(0.0, 0.3, 0.9))
    chest, cabinet_i = _one(memory, "drawer chest"), _holding(memory, "cabinet", cabinet)
    wall_i = _holding(memory, "cabinet", wall_cabinet)
    low, high = _holding(memory, "drawer", _part_box(boxes, 11)), _holding(memory, "drawer", _part_box(boxes, 13))
    stray_i = _holding(memory, "drawer", stray)
    gaps = {c.id: cKDTree(c.points()).query(low.points())[0].min() for c in (chest, cabinet_i, wall_i)}
    assert min(gaps.values()) > memory.config.part_gap_m  # the premise: no candidate is adjacent
    assert gaps[cabinet_i.id] < gaps[chest.id]  # the cabinet is even nearer than the chest
    wall_lo, wall_hi = wall_i.bounds
    centre = low.centroid[:2]
    assert np.all(wall_lo[:2] - 0.05 <= centre) and np.all(centre <= wall_hi[:2] + 0.05)  # it holds the drawer too
    assert high.parent == chest.id  # by adjacency
    assert low.parent == chest.id and low.id in chest.children
    assert stray_i.parent is None and all(stray_i.id not in c.children for c in (chest, cabinet_i, wall_i))


def test_after_a_spanning_detection_each_drawer_still_gets_its_own_views() -> None:
    """Not merging the two drawers is not enough: a detection spanning both, folded whole into the
    best match (the lower drawer), made its voxels cover the upper one too; every later detection of
    the upper drawer then had containment 1 with both and went to the lower id (ties break by id),
    and the upper instance was never updated again: a ghost, and what the upper drawer held was read
    as the lower's. The spanning detection is now cut between the drawers it spans."""
    memory = InstanceMemory()
    _see(memory, [LOWER, UPPER], FRONT_EYE, FRONT_TARGET)
    lower, upper = _holding(memory, "drawer", LOWER), _holding(memory, "drawer", UPPER)
    spanning = _see(memory, _both_as_one(), FRONT_EYE, FRONT_TARGET)
    assert set(spanning.updated) == {lower.id, upper.id} and spanning.absorbed == {}
    update = _see(memory, [UPPER], FRONT_EYE, FRONT_TARGET)
    assert upper.id in update.updated and upper.last_seen == memory.frame
    assert lower.id not in update.updated
    assert lower.bounds[1][2] < 0.96  # the lower drawer's box stays on the lower front
    assert upper.bounds[0][2] > 0.94 and lower.hint == LOWER.id and upper.hint == UPPER.id


def test_a_cup_on_the_table_beside_an_open_door_is_not_inside_the_cabinet() -> None:
    """A piece contains by its own box, not its parts': a door swung open reaches 20 cm out over the
    table, and a cup standing there in front of the carcass, beside the door, is *on* the table."""
    fronts = (Front("door", (0.152, 0.348), (0.77, 1.13), "left"), Front("door", (0.352, 0.548), (0.77, 1.13), "right"))
    closed = storage(2, "cabinet", (0.15, 0.55), (0.23, 0.53), (0.75, 1.15), fronts)
    open_door = Box(5, "door", (0.528, 0.014, 0.77), (0.548, 0.21, 1.13))  # the right door turned 90 degrees
    open_handle = Box.at(6, "handle", (0.583, 0.054, 0.95), (0.016, 0.016, 0.144))
    cabinet = [b for b in closed if b.id not in (5, 6)] + [open_door, open_handle]
    cup = Box.at(7, "cup", (0.45, 0.12, 0.8), (0.06, 0.06, 0.1))  # on the table, in front of the carcass
    memory = InstanceMemory()
    _see(memory, [TABLE, *cabinet, cup], eye=(0.1, -0.9, 1.45), target=(0.3, 0.2, 0.9))
    cup_i, cabinet_i, table = _one(memory, "cup"), _one(memory, "cabinet"), _one(memory, "table")
    assert cup_i.centroid[1] < cabinet_i.bounds[0][1]  # the premise: in front of the carcass
    assert _relations(memory)[cup_i.id] == (str(table.id), "on")
