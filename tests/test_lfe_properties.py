"""R_A, D_in and D_out on hand-drawn maps whose answers can be worked out on paper."""

from __future__ import annotations

import math

import numpy as np
import pytest

from agent.lfe.properties import (
    FrontierProperties,
    frontier_properties,
    label_frontiers,
    region_beyond,
    unseen_space,
)
from agent.mapping.grid import GridSpec
from agent.planning.frontier import cluster_frontiers, frontier_cells

SQRT2 = math.sqrt(2.0)
RES = 0.05


def cells(*rc: tuple[int, int]) -> np.ndarray:
    return np.array(rc, dtype=int)


def corridor(length: int = 30, width: int = 1, seen: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """A horizontal corridor from column 2, its first ``seen`` columns observed."""
    free = np.zeros((9, length + 4), dtype=bool)
    free[4 - width // 2 : 4 - width // 2 + width, 2 : 2 + length] = True
    observed = np.zeros_like(free)
    observed[:, : 2 + seen] = True
    return free, observed


# --- R_A ---------------------------------------------------------------------------------------


def test_room_beyond_a_doorway_has_exactly_its_area() -> None:
    """Left room seen, right room not: R_A is the right room plus the unseen doorway, to the cell."""
    free = np.zeros((30, 50), dtype=bool)
    free[2:28, 2:20] = True  # seen room
    free[12:15, 20:22] = True  # doorway through a two-cell wall, 3 wide
    free[5:25, 22:48] = True  # unseen room, 20 x 26
    observed = np.zeros_like(free)
    observed[:, :21] = True  # the first doorway column is seen
    frontier = cells((12, 20), (13, 20), (14, 20))
    space = unseen_space(free, observed, RES)
    props = frontier_properties(space, frontier)
    assert props.area_m2 == pytest.approx((20 * 26 + 3) * RES**2)
    expected = np.zeros_like(free)
    expected[5:25, 22:48] = True
    expected[12:15, 21] = True
    np.testing.assert_array_equal(region_beyond(space, frontier), expected)
    # Thinning leaves a short medial line in the middle of the room (the doorway stub is absorbed):
    # some way in and out, less than half the room's perimeter (2.3 m)
    assert 0.1 < props.d_out_m <= props.d_in_m < 1.15


def test_frontiers_from_cluster_frontiers_work_directly() -> None:
    """The `Frontier` objects of the planner (seen free cells next to the unknown) are accepted."""
    free = np.zeros((30, 50), dtype=bool)
    free[2:28, 2:20] = True
    free[12:15, 20:22] = True
    free[5:25, 22:48] = True
    observed = np.zeros_like(free)
    observed[:, :21] = True
    seen_free = free & observed
    spec = GridSpec((0.0, 0.0), RES, free.shape)
    mask = frontier_cells(seen_free, observed, observed & ~free, min_unexplored_neighbours=1)
    frontiers = cluster_frontiers(spec, mask, observed, observed & ~free, min_size=1)
    assert len(frontiers) == 1
    [props] = label_frontiers(free, observed, frontiers, RES)
    assert props.area_m2 == pytest.approx((20 * 26 + 3) * RES**2)


def test_frontier_with_nothing_beyond_is_all_zero() -> None:
    free, observed = corridor()
    observed[:] = True
    props = label_frontiers(free, observed, [cells((4, 9))], RES)[0]
    assert props == FrontierProperties(0.0, 0.0, 0.0)


def test_unseen_space_out_of_reach_of_the_frontier_does_not_count() -> None:
    """Unseen free space two cells away from every frontier cell is someone else's region."""
    free, observed = corridor(length=30, seen=8)
    free[4, 10] = False  # a wall cell: the unseen part starts at column 11, out of reach of (4, 9)
    props = label_frontiers(free, observed, [cells((4, 9))], RES)[0]
    assert props == FrontierProperties(0.0, 0.0, 0.0)


def test_regions_are_eight_connected() -> None:
    """A diagonal corridor is one region, as the robot (which moves diagonally) would find it."""
    free = np.zeros((20, 20), dtype=bool)
    free[np.arange(4, 15), np.arange(4, 15)] = True  # (4, 4) seen, then ten unseen diagonal steps
    observed = np.zeros_like(free)
    observed[4, 4] = True
    props = label_frontiers(free, observed, [cells((4, 4))], 1.0)[0]
    assert props.area_m2 == 10
    assert props.d_in_m == pytest.approx(9 * SQRT2)
    assert props.d_out_m == pytest.approx(9 * SQRT2)


def test_two_frontiers_into_the_same_region_share_its_area() -> None:
    """A corridor seen at both ends: both frontiers open onto the same unseen middle."""
    free, observed = corridor(length=30, seen=8)
    observed[:, 25:] = True  # columns 10..24 unseen: 15 cells
    space = unseen_space(free, observed, RES)
    left, right = cells((4, 9)), cells((4, 25))
    a, b = (frontier_properties(space, f) for f in (left, right))
    assert a.area_m2 == b.area_m2 == pytest.approx(15 * RES**2)
    np.testing.assert_array_equal(region_beyond(space, left), region_beyond(space, right))
    assert a.d_in_m == pytest.approx(14 * RES) and b.d_in_m == pytest.approx(14 * RES)


def test_label_frontiers_keeps_order_and_matches_one_at_a_time() -> None:
    free, observed = corridor(length=30, seen=8)
    observed[:, 25:] = True
    frontiers = [cells((4, 25)), cells((0, 0)), cells((4, 9))]
    labelled = label_frontiers(free, observed, frontiers, RES)
    space = unseen_space(free, observed, RES)
    assert labelled == [frontier_properties(space, f) for f in frontiers]
    assert labelled[1] == FrontierProperties(0.0, 0.0, 0.0)


# --- D_in and D_out ----------------------------------------------------------------------------


def test_straight_corridor_entered_at_one_end() -> None:
    """A one-cell corridor is its own skeleton: in to the far end and back out, (n - 1) cells each."""
    free, observed = corridor(length=30, seen=8)  # 22 unseen cells
    props = label_frontiers(free, observed, [cells((4, 9))], RES)[0]
    assert props.area_m2 == pytest.approx(22 * RES**2)
    assert props.d_in_m == pytest.approx(21 * RES)
    assert props.d_out_m == pytest.approx(21 * RES)
    # the paper's convention, frontier cells on the unknown side, finds the same
    assert label_frontiers(free, observed, [cells((4, 10))], RES)[0] == props


def test_wide_corridor_is_about_its_length() -> None:
    """Thinning shortens a wide corridor by about its half-width at the far end, no more."""
    free, observed = corridor(length=40, width=5, seen=8)  # 32 x 5 unseen
    props = label_frontiers(free, observed, [cells((4, 9))], RES)[0]
    assert props.area_m2 == pytest.approx(32 * 5 * RES**2)
    assert 28 * RES <= props.d_in_m <= 32 * RES
    assert props.d_out_m == pytest.approx(props.d_in_m)


def test_corridor_entered_in_the_middle_explores_the_near_side_first() -> None:
    """Entry 7 cells from one end, 14 from the other: in = 7 + 21, out = 14 (not 14 + 21, 7)."""
    free = np.zeros((9, 30), dtype=bool)
    free[4, 2:24] = True  # 22 cells, columns 2..23
    free[3, 9] = True  # a seen doorway above column 9
    observed = np.zeros_like(free)
    observed[:4] = True
    props = label_frontiers(free, observed, [cells((3, 9))], 1.0)[0]
    assert props.area_m2 == 22
    assert props.d_in_m == pytest.approx(7 + 21)
    assert props.d_out_m == pytest.approx(14)


def test_l_shape_cuts_the_corner_diagonally() -> None:
    """Arms of 15 and 20 cells: the 8-connected way round the bend is 14 + √2 + 19."""
    free = np.zeros((30, 30), dtype=bool)
    free[5, 3:21] = True  # row 5, columns 3..20
    free[5:26, 20] = True  # column 20, rows 5..25
    observed = np.zeros_like(free)
    observed[:, :5] = True  # seen up to column 4: the region starts at (5, 5)
    props = label_frontiers(free, observed, [cells((5, 4))], 1.0)[0]
    assert props.area_m2 == 16 + 20
    assert props.d_in_m == pytest.approx(33 + SQRT2)
    assert props.d_out_m == pytest.approx(33 + SQRT2)


def test_t_junction_tour_visits_the_junction_and_both_ends() -> None:
    """Entry E at the bar's left end, junction J, right end R, stem tip S: E-J-R-S-E is shortest.

    EJ = JR = JS = 10, RS = SE = 18 + √2 (cutting the corners at J), ER = 20. Of the two shortest
    tours E-J-R-S-E (in 38 + √2, out 18 + √2) and E-S-R-J-E (in 46 + 2√2, out 10) the first wins.
    """
    free = np.zeros((20, 30), dtype=bool)
    free[5, 4:26] = True
    free[6:16, 15] = True
    observed = np.zeros_like(free)
    observed[:, :5] = True
    props = label_frontiers(free, observed, [cells((5, 4))], 1.0)[0]
    assert props.d_in_m == pytest.approx(38 + SQRT2)
    assert props.d_out_m == pytest.approx(18 + SQRT2)


def test_two_regions_behind_one_frontier_are_toured_one_after_the_other() -> None:
    """Corridors of 10 and 5 cells, not touching each other: out of the short one, into the long."""
    free = np.zeros((9, 30), dtype=bool)
    free[4, 5:11] = True  # the seen approach, ending in the frontier cell (4, 10)
    free[3, 11:21] = True  # 10 cells: 9 in, 9 out
    free[5, 11:16] = True  # 5 cells: 4 in, 4 out
    observed = np.zeros_like(free)
    observed[4, :11] = True
    props = label_frontiers(free, observed, [cells((4, 10))], 1.0)[0]
    assert props.area_m2 == 15
    assert props.d_in_m == pytest.approx(4 + 4 + 9)
    assert props.d_out_m == pytest.approx(9)


def test_single_cell_region() -> None:
    """One unseen cell: its skeleton is that pixel, nothing to travel."""
    free, observed = corridor(length=9, seen=8)
    props = label_frontiers(free, observed, [cells((4, 9))], RES)[0]
    assert props == FrontierProperties(pytest.approx(RES**2), 0.0, 0.0)


def test_closed_loop_is_travelled_round() -> None:
    """A ring has no ends and no junctions: the tour goes to its far side and back, once round.

    Thinning removes the four corner pixels of a one-cell square ring of side 12, leaving
    4 × 9 unit steps and 4 diagonals.
    """
    free = np.zeros((20, 20), dtype=bool)
    free[3, 3:15] = free[14, 3:15] = True
    free[3:15, 3] = free[3:15, 14] = True
    free[8, 0:3] = True  # the seen approach to the ring's left side
    observed = np.zeros_like(free)
    observed[8, :3] = True
    props = label_frontiers(free, observed, [cells((8, 2))], 1.0)[0]
    loop = 36 + 4 * SQRT2
    assert props.d_in_m == pytest.approx(props.d_out_m)
    assert loop - SQRT2 <= props.d_in_m + props.d_out_m <= loop


def test_steps_use_the_papers_factor() -> None:
    """1 m at 0.25 m a move is 4 moves, 6.8 steps with turns."""
    assert FrontierProperties(1.0, 1.0, 0.5).steps(0.25) == pytest.approx((6.8, 3.4))


# --- errors ------------------------------------------------------------------------------------


def test_bad_inputs_name_the_argument() -> None:
    free, observed = corridor()
    with pytest.raises(ValueError, match="free"):
        unseen_space(free.astype(np.uint8), observed, RES)
    with pytest.raises(ValueError, match="observed"):
        unseen_space(free, observed[:, :-1], RES)
    with pytest.raises(ValueError, match="observed"):
        unseen_space(free, observed.astype(float), RES)
    with pytest.raises(ValueError, match="resolution"):
        unseen_space(free, observed, 0.0)
    space = unseen_space(free, observed, RES)
    with pytest.raises(ValueError, match="outside"):
        frontier_properties(space, cells((4, 200)))
    with pytest.raises(ValueError, match="frontier cells"):
        frontier_properties(space, np.zeros((0, 2), dtype=int))
    with pytest.raises(ValueError, match="integers"):
        frontier_properties(space, np.array([[4.0, 9.0]]))
