"""What a closed drawer fills behind its front (`agent.perception.hidden_bodies`), from plain points."""

from __future__ import annotations

import numpy as np
import pytest

from agent.perception.hidden_bodies import FACE_SPACING_M, closed_drawer_faces


def _grid(x: tuple[float, float], y: tuple[float, float], z: tuple[float, float], step: float = 0.01) -> np.ndarray:
    axes = [np.arange(lo, hi + 1e-9, step) if hi > lo else np.array([lo]) for lo, hi in (x, y, z)]
    return np.stack(np.meshgrid(*axes), axis=-1).reshape(-1, 3)


def _chest() -> tuple[np.ndarray, np.ndarray]:
    """A chest facing -y whose front stands at y = 0.09, its back at y = 0.38: its upper drawer's
    front (x -0.18..0.18, z 0.91..1.07) and its sides."""
    front = _grid((-0.18, 0.18), (0.09, 0.09), (0.91, 1.07))
    sides = np.vstack([_grid((x, x), (0.09, 0.38), (0.75, 1.07)) for x in (-0.18, 0.18)])
    return front, sides


def test_a_closed_drawer_fills_the_chest_behind_its_front_from_its_bottom_to_its_top() -> None:
    # the camera looks from before the chest
    front, carcass = _chest()
    faces = closed_drawer_faces(front, carcass, eye=np.array([0.0, -0.7, 1.4]))
    assert set(np.round(faces[:, 2], 3)) == {0.91, 1.07}
    assert faces[:, 0].min() == pytest.approx(-0.18) and faces[:, 0].max() == pytest.approx(0.18, abs=FACE_SPACING_M)
    assert faces[:, 1].min() == pytest.approx(0.09 + FACE_SPACING_M) and faces[:, 1].max() == pytest.approx(0.38, abs=FACE_SPACING_M)


def test_a_front_with_nothing_seen_behind_it_fills_nothing() -> None:
    front, _ = _chest()
    assert closed_drawer_faces(front, np.zeros((0, 3)), eye=np.array([0.0, -0.7, 1.4])).shape == (0, 3)
    assert closed_drawer_faces(front, front, eye=np.array([0.0, -0.7, 1.4])).shape == (0, 3)


def test_a_front_facing_another_way_fills_behind_it_that_way() -> None:
    # the same chest turned to face +x: its front at x = 0.5, its back at x = 0.2
    front = _grid((0.5, 0.5), (-0.18, 0.18), (0.91, 1.07))
    carcass = _grid((0.2, 0.5), (-0.18, -0.18), (0.75, 1.07))
    faces = closed_drawer_faces(front, carcass, eye=np.array([1.2, 0.0, 1.4]))
    assert faces[:, 0].max() == pytest.approx(0.5 - FACE_SPACING_M) and faces[:, 0].min() == pytest.approx(0.2, abs=FACE_SPACING_M)
    assert faces[:, 1].min() == pytest.approx(-0.18, abs=FACE_SPACING_M)


def test_a_drawer_remembered_with_the_floor_seen_inside_it_fills_the_chest_behind_its_front() -> None:
    # recursive 1120 (tuning-wide): looked into while open, a drawer is remembered with its floor
    # and walls; the floor's normals outnumbered the front's, and the box was laid out turned 40°,
    # out before the chest, over the spot a box was to be put down
    front, carcass = _chest()
    floor = _grid((-0.17, 0.17), (0.1, 0.37), (0.92, 0.92), step=0.005)
    walls = np.vstack([_grid((x, x), (0.1, 0.37), (0.92, 1.05)) for x in (-0.17, 0.17)])
    faces = closed_drawer_faces(np.vstack([front, floor, walls]), carcass, eye=np.array([0.0, -0.7, 1.4]))
    assert 0.09 < faces[:, 1].min() < 0.09 + 2 * FACE_SPACING_M  # behind the front, none before it
    assert faces[:, 1].max() == pytest.approx(0.38, abs=FACE_SPACING_M)
    assert -0.19 < faces[:, 0].min() < faces[:, 0].max() < 0.19 and np.ptp(faces[:, 0]) > 0.3  # across the chest
