"""The network's view of a map: coarse cells, walls kept closed, doorways kept open."""

from __future__ import annotations

import numpy as np
import pytest

from agent.lfe.raster import FREE, OCCUPIED, UNKNOWN, coarse_cells, coarsening_factor, encode_map, frontier_pixel_mask


def test_a_coarse_cell_is_occupied_before_free_before_unknown() -> None:
    free = np.zeros((4, 4), dtype=bool)
    occupied = np.zeros_like(free)
    free[0, 0] = True  # top-left block: one free cell among unknown ones
    free[0, 2] = occupied[1, 3] = True  # top-right block: free and occupied cells
    occupied[3, 0] = True  # bottom-left block: one occupied cell
    encoded = encode_map(free, occupied, 0.05, 0.1)
    assert encoded.dtype == np.uint8
    assert encoded.tolist() == [[FREE, OCCUPIED], [OCCUPIED, UNKNOWN]]


def test_a_cell_both_free_and_occupied_counts_as_occupied() -> None:
    both = np.ones((2, 2), dtype=bool)
    assert encode_map(both, both, 0.1, 0.1).tolist() == [[OCCUPIED, OCCUPIED], [OCCUPIED, OCCUPIED]]


def test_odd_sides_are_padded_with_unknown_at_the_far_edges() -> None:
    free = np.ones((3, 5), dtype=bool)
    encoded = encode_map(free, np.zeros_like(free), 0.05, 0.1)
    assert encoded.shape == (2, 3)
    assert (encoded == FREE).all()  # every coarse cell holds at least one free fine cell
    fine = np.array([[2, 4]])
    assert coarse_cells(fine, 2).tolist() == [[1, 2]]  # the last fine cell lies in the last coarse one


def test_same_resolution_is_the_identity_encoding() -> None:
    rng = np.random.default_rng(3)
    occupied = rng.random((7, 9)) < 0.2
    free = ~occupied & (rng.random((7, 9)) < 0.6)
    encoded = encode_map(free, occupied, 0.1, 0.1)
    expected = np.where(occupied, OCCUPIED, np.where(free, FREE, UNKNOWN))
    np.testing.assert_array_equal(encoded, expected)


def test_coarse_cells_are_distinct_and_row_major() -> None:
    cells = np.array([[5, 5], [0, 1], [4, 4], [1, 0], [5, 4]])
    assert coarse_cells(cells, 2).tolist() == [[0, 0], [2, 2]]
    assert coarse_cells(cells, 1).tolist() == sorted(cells.tolist())
    with pytest.raises(ValueError, match="factor must be at least 1"):
        coarse_cells(cells, 0)


@pytest.mark.parametrize("resolution, model, message", [
    (0.05, 0.125, "do not tile"),
    (0.1, 0.05, "do not tile"),
    (0.0, 0.1, "resolution must be a positive number"),
    (0.05, float("nan"), "model_resolution must be a positive number"),
])
def test_resolutions_that_do_not_tile_are_refused(resolution: float, model: float, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        coarsening_factor(resolution, model)


def test_masks_must_be_bool_and_of_one_shape() -> None:
    with pytest.raises(ValueError, match="must be bool masks"):
        encode_map(np.zeros((2, 2)), np.zeros((2, 2), dtype=bool), 0.1, 0.1)
    with pytest.raises(ValueError, match="2-D masks of one shape"):
        encode_map(np.zeros((2, 2), dtype=bool), np.zeros((2, 3), dtype=bool), 0.1, 0.1)


def test_frontier_pixels_are_free_cells_next_to_the_unknown() -> None:
    encoded = np.full((5, 6), UNKNOWN, dtype=np.uint8)
    encoded[1:4, 0:3] = FREE
    encoded[1:4, 3] = OCCUPIED  # a wall on the right: its free neighbours see no unknown across it
    mask = frontier_pixel_mask(encoded)
    assert mask[1, 0] and mask[3, 2] and mask[1, 1]  # rows 0 and 4 are unknown
    assert not mask[2, 1]  # inside: every neighbour known
    assert not mask[2, 2]  # next to the wall, and the wall hides nothing from it
    assert not mask[0, 0] and not mask[2, 3]  # unknown and occupied cells are never frontier pixels
