"""Where pieces of the named storage were seen, from frames built by hand."""

from __future__ import annotations

import numpy as np
import pytest

from agent.mapping.camera import Intrinsics
from agent.observation import InstanceLabel, Observation
from agent.perception.sightings import Centre, SightingConfig, Sightings, storage_centres

H, W = 60, 80
INTRINSICS = Intrinsics(W, H, 40.0, 40.0, 40.0, 30.0)
#: A camera 1 m above the origin looking along +x: its right is -y, its down is -z.
LOOKING_ALONG_X = np.array([[0.0, 0.0, 1.0, 0.0], [-1.0, 0.0, 0.0, 0.0], [0.0, -1.0, 0.0, 1.0], [0.0, 0.0, 0.0, 1.0]])


def frame(boxes: list[tuple[InstanceLabel, tuple[int, int, int, int], float]]) -> Observation:
    """Nothing in view but the boxes: (label, (row, col, height, width), depth)."""
    depth = np.zeros((H, W), dtype=np.float32)
    seg = np.full((H, W), -1, dtype=np.int32)
    for label, (row, col, height, width), distance in boxes:
        seg[row: row + height, col: col + width] = label.id
        depth[row: row + height, col: col + width] = distance
    return Observation(np.zeros((H, W, 3), np.uint8), depth, seg, tuple(label for label, _, _ in boxes),
                       INTRINSICS, LOOKING_ALONG_X, (0.0, 0.0, 0.0))


CABINET = InstanceLabel(5, "cabinet", "white")


def test_a_piece_is_placed_where_its_pixels_stand_on_the_floor() -> None:
    [centre] = storage_centres(frame([(CABINET, (25, 35, 10, 10), 3.0)]), "cabinet")
    assert centre.pixels == 100 and centre.room is None  # nothing in view says which room
    np.testing.assert_allclose(centre.xy, [3.0, 0.0], atol=0.05)  # straight ahead, 3 m out
    [left] = storage_centres(frame([(CABINET, (25, 0, 10, 10), 3.0)]), "cabinet")
    assert left.xy[1] > 1.0  # pixels on the image's left lie to the camera's left, +y


def test_only_pieces_of_the_kind_seen_well_enough_count() -> None:
    observation = frame([
        (CABINET, (25, 35, 10, 10), 3.0),
        (InstanceLabel(7, "wardrobe", "white"), (0, 20, 10, 10), 3.0),  # another kind
        (InstanceLabel(8, "cabinet", "white"), (50, 70, 5, 5), 3.0),  # 25 pixels, too few
        (InstanceLabel(9, "cabinet", "white"), (40, 40, 10, 10), 9.0),  # too far to place
    ])
    assert [centre.pixels for centre in storage_centres(observation, "cabinet")] == [100]


def test_the_room_a_piece_stands_in_is_what_stands_beside_it_on_its_floor() -> None:
    """A floor on the lower half with the cabinet and a toilet standing on it: a bathroom's cabinet.
    With a second floor in view and the toilet on that one, the cabinet's room is not told."""
    floor, other = InstanceLabel(1, "floor", "grey"), InstanceLabel(2, "floor", "grey")
    toilet = InstanceLabel(6, "toilet", "white")
    whole = [(floor, (35, 0, 25, 80), 3.0), (CABINET, (25, 10, 12, 12), 3.0), (toilet, (25, 50, 12, 12), 3.0)]
    [centre] = storage_centres(frame(whole), "cabinet")
    assert centre.room == "bathroom"
    split = [(floor, (35, 0, 25, 40), 3.0), (other, (35, 40, 25, 40), 3.0), *whole[1:]]
    [centre] = storage_centres(frame(split), "cabinet")
    assert centre.room is None


def test_sightings_of_one_piece_merge_weighted_by_pixels_and_others_stay_apart() -> None:
    sightings = Sightings(SightingConfig(merge_m=0.8))
    sightings.add([Centre(np.array([3.0, 0.0]), 100, None)])
    sightings.add([Centre(np.array([3.4, 0.0]), 300, "bathroom"), Centre(np.array([6.0, 1.0]), 50, None)])
    assert len(sightings.pieces) == 2
    np.testing.assert_allclose(sightings.pieces[0].xy, [3.3, 0.0])
    assert sightings.pieces[0].pixels == 400
    np.testing.assert_allclose(sightings.pieces[1].xy, [6.0, 1.0])
    assert sightings.pieces[0].room == "bathroom" and sightings.pieces[1].room is None
    sightings.add([Centre(np.array([3.3, 0.1]), 200, "kitchen"), Centre(np.array([3.3, 0.0]), 150, "kitchen")])
    assert sightings.pieces[0].room == "kitchen"  # most of the frames that told said so


@pytest.mark.parametrize("field, value", [("max_depth_m", 0.0), ("merge_m", -1.0), ("min_pixels", 0)])
def test_bad_settings_are_refused_with_their_name(field: str, value: float) -> None:
    with pytest.raises(ValueError, match=f"act.approach.sightings.{field}"):
        SightingConfig(**{field: value})
