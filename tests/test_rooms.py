"""Which room each part of a frame shows, read off what stands there, on frames built by hand."""

from __future__ import annotations

import numpy as np
import pytest

from agent.mapping.camera import Intrinsics
from agent.observation import InstanceLabel, Observation
from agent.perception.rooms import RoomReadingConfig, floor_points, read_rooms

H, W = 40, 40
#: A camera 1 m above the origin looking along +x: its right is -y, its down is -z.
LOOKING_ALONG_X = np.array([[0.0, 0.0, 1.0, 0.0], [-1.0, 0.0, 0.0, 0.0], [0.0, -1.0, 0.0, 1.0], [0.0, 0.0, 0.0, 1.0]])
FLOOR_A, FLOOR_B = InstanceLabel(1, "floor", "grey"), InstanceLabel(2, "floor", "blue")
BED, STOVE, COUNTER = InstanceLabel(3, "bed", "white"), InstanceLabel(4, "stove", "white"), InstanceLabel(5, "counter", "white")
MUG, WALL = InstanceLabel(6, "mug", "red"), InstanceLabel(7, "wall", "white")


def frame(*boxes: tuple[InstanceLabel, tuple[int, int, int, int], float]) -> Observation:
    """(label, (row, col, height, width), depth) boxes drawn in order on nothing."""
    seg = np.full((H, W), -1, dtype=np.int32)
    depth = np.zeros((H, W), dtype=np.float32)
    for label, (row, col, height, width), distance in boxes:
        seg[row: row + height, col: col + width] = label.id
        depth[row: row + height, col: col + width] = distance
    labels = tuple({label.id: label for label, _, _ in boxes}.values())
    return Observation(np.zeros((H, W, 3), np.uint8), depth, seg, labels, Intrinsics(W, H, 20.0, 20.0, 20.0, 20.0),
                       LOOKING_ALONG_X, (0.0, 0.0, 0.0))


def test_a_thing_stands_on_what_its_foot_meets_and_so_on_the_floor_beneath() -> None:
    """A mug on a counter on the left floor, a bed on the right floor: two rooms, each told by its
    furniture; the mug is in the kitchen through the counter it stands on."""
    reading = read_rooms(frame((FLOOR_A, (20, 0, 20, 20), 2.0), (FLOOR_B, (20, 20, 20, 20), 2.0),
                               (COUNTER, (10, 2, 12, 14), 2.0), (MUG, (6, 6, 5, 4), 2.0), (BED, (14, 24, 8, 14), 2.0)))
    assert reading.region == {1: 1, 2: 2, 5: 1, 6: 1, 3: 2}
    assert (reading.room_of(6), reading.room_of(3)) == ("kitchen", "bedroom")
    assert reading.room_of(5, ignoring=(5,)) is None  # without the counter itself nothing tells


def test_a_foot_hidden_behind_something_nearer_is_no_footing() -> None:
    """The stove's foot meets a box 1.5 m nearer: its footing is out of view, so with two floors
    in view the stove tells nothing about either."""
    box = InstanceLabel(8, "box", "brown")
    reading = read_rooms(frame((FLOOR_A, (20, 0, 20, 20), 2.0), (FLOOR_B, (20, 20, 20, 20), 4.0),
                               (STOVE, (10, 24, 10, 10), 4.0), (box, (20, 22, 6, 14), 2.5)))
    assert reading.region[4] == 4 and reading.kind(2) is None
    assert reading.room_of(4) == "kitchen"  # its own region: a stove is a kitchen's


def test_one_floor_in_view_is_one_room_whatever_stands_off_it() -> None:
    """The stove's foot is out of view, but one floor means one room: the stove tells it."""
    reading = read_rooms(frame((FLOOR_A, (30, 0, 10, 40), 2.0), (STOVE, (2, 10, 10, 10), 3.0), (WALL, (0, 0, 2, 40), 5.0)))
    assert reading.kind(1) == "kitchen" and reading.room_of(4) == "kitchen"
    assert 7 not in reading.region  # walls stand between rooms


def test_with_no_floor_in_view_the_frame_is_one_room() -> None:
    reading = read_rooms(frame((COUNTER, (10, 0, 20, 40), 1.0), (MUG, (5, 10, 5, 4), 1.0)))
    assert reading.room_of(6) == "kitchen" and not reading.floors


def test_a_sliver_of_furniture_and_small_things_are_no_cue() -> None:
    toothbrush = InstanceLabel(9, "toothbrush", "blue")  # kept in bathrooms, but carried about
    observation = frame((FLOOR_A, (20, 0, 20, 40), 2.0), (BED, (17, 0, 4, 5), 2.0), (toothbrush, (14, 20, 7, 8), 2.0))
    assert read_rooms(observation).kind(1) is None  # 15 pixels of bed
    assert read_rooms(observation, RoomReadingConfig(min_cue_px=10)).kind(1) == "bedroom"


def test_the_floor_of_a_room_kind_is_read_off_the_frame() -> None:
    seg_frame = frame((FLOOR_A, (20, 0, 20, 20), 2.0), (FLOOR_B, (20, 20, 20, 20), 2.0), (BED, (14, 2, 8, 14), 2.0),
                      (STOVE, (12, 24, 10, 10), 2.0))
    depth = seg_frame.depth.copy()
    depth[38, :] = 9.0  # beyond the range a floor point is trusted at
    observation = Observation(seg_frame.rgb, depth, seg_frame.segmentation, seg_frame.labels, seg_frame.intrinsics,
                              seg_frame.camera_to_world, seg_frame.base_pose)
    reading = read_rooms(observation)
    points = floor_points(observation, reading, "bedroom", max_depth_m=8.0)
    # every other row and column of the left floor (10 x 10), less the far row (10) and where the bed stands (7)
    assert len(points) == 10 * 10 - 10 - 7
    assert np.all(points[:, 1] > 0)  # the image's left half lies to the camera's left
    assert len(floor_points(observation, reading, "bathroom", max_depth_m=8.0)) == 0


@pytest.mark.parametrize("field, value", [("contact_m", 0.0), ("min_cue_px", 0)])
def test_bad_settings_are_refused_with_their_name(field: str, value: float) -> None:
    with pytest.raises(ValueError, match=f"rooms.{field}"):
        RoomReadingConfig(**{field: value})
