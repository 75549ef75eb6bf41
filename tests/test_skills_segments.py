"""Distances to line segments (`skills.arm.segments`), from plain arrays."""

from __future__ import annotations

import numpy as np
import pytest

from skills.arm.segments import distance_to_segment, nearest_on_segments


def test_the_nearest_point_of_segments_is_the_foot_on_the_nearest_one_or_an_end() -> None:
    segments = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0], [0.0, 1.0, 1.0]]])
    points = np.array([[0.5, 0.2, 0.0], [1.5, 0.0, 0.0], [0.1, 0.9, 0.5]])
    assert np.allclose(nearest_on_segments(points, segments), [[0.5, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.5]])


@pytest.mark.parametrize("point, distance", [((0.5, 0.3, 0.0), 0.3), ((-0.4, 0.0, 0.3), 0.5), ((2.0, 0.0, 0.0), 1.0)])
def test_the_distance_to_a_segment_is_to_its_foot_or_its_nearer_end(point: tuple, distance: float) -> None:
    assert distance_to_segment(np.array(point), np.zeros(3), np.array([1.0, 0.0, 0.0])) == pytest.approx(distance)
    assert distance_to_segment(np.array(point), np.zeros(3), np.zeros(3)) == pytest.approx(np.linalg.norm(point))
