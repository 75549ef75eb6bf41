"""Views into every compartment of a piece, side by side, and what the simulated VLM makes of them."""

from __future__ import annotations

import numpy as np
import pytest

from agent.eqa.prompts import YES_NO, answer_prompt, relevance_prompt
from agent.mapping.camera import Intrinsics
from agent.observation import InstanceLabel, Observation
from agent.vlm.mosaic import side_by_side
from agent.vlm.protocol import VisualQuery
from agent.vlm.sim import SimParams, SimulatedVLM
from worlds.bus.questions import LETTERS, PAD_CHOICE

CABINET = InstanceLabel(3, "cabinet", "white", state="open")
HAMMER = InstanceLabel(9, "hammer", "grey", inside="cabinet")


def view(height: int, width: int, boxes: list[tuple[InstanceLabel, tuple[int, int, int, int]]],
         pose: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> Observation:
    """A view 1 m from what it shows: (label, (row, col, height, width)) boxes on nothing."""
    seg = np.full((height, width), -1, dtype=np.int32)
    for label, (row, col, h, w) in boxes:
        seg[row: row + h, col: col + w] = label.id
    depth = np.where(seg >= 0, 1.0, 0.0).astype(np.float32)
    rgb = np.where(seg[..., None] >= 0, 200, 0).astype(np.uint8).repeat(3, axis=2)
    return Observation(rgb, depth, seg, tuple(label for label, _ in boxes),
                       Intrinsics(width, height, width / 2, width / 2, width / 2, height / 2), np.eye(4), pose)


def test_views_are_put_side_by_side_each_thing_labelled_as_it_shows_most() -> None:
    left_door = InstanceLabel(4, "door", "white", state="open")
    first = view(40, 60, [(CABINET, (0, 0, 40, 30)), (left_door, (0, 30, 40, 5))])
    second = view(30, 50, [(CABINET, (0, 0, 30, 20)), (InstanceLabel(4, "door", "white"), (0, 20, 30, 20)),
                           (HAMMER, (10, 40, 5, 8))], pose=(1.0, 2.0, 0.5))
    both = side_by_side([first, second])
    assert both.rgb.shape == (40, 110, 3) and both.depth.shape == both.segmentation.shape == (40, 110)
    assert (both.intrinsics.width, both.intrinsics.height) == (110, 40)
    np.testing.assert_array_equal(both.segmentation[:30, 60:], second.segmentation)
    assert np.all(both.segmentation[30:, 60:] == -1) and np.all(both.depth[30:, 60:] == 0)  # padding below
    labels = {label.id: label for label in both.labels}
    assert set(labels) == {3, 4, 9} and len(both.labels) == 3
    assert labels[4].state == "open"  # shows most in the second view, closed there, but was seen open in the first
    assert both.base_pose == second.base_pose  # where the robot stood last


def test_one_view_is_its_own_mosaic_and_none_is_refused() -> None:
    only = view(20, 20, [(CABINET, (0, 0, 20, 20))])
    assert side_by_side([only]) is only
    with pytest.raises(ValueError, match="views"):
        side_by_side([])


def test_shown_both_compartments_the_vlm_finds_what_lies_behind_the_second_door() -> None:
    """The empty compartment alone backs "No"; beside the one that holds the hammer, "Yes"."""
    question = "Is there any hammer in the cabinet in the bathroom?"
    choices = ["Yes", "No", PAD_CHOICE, PAD_CHOICE]
    prompt = answer_prompt(question, choices)

    def best(observation: Observation, seed: int) -> str:
        vlm = SimulatedVLM(SimParams(seed=seed, skill=1.0, notice_area_px=10.0))  # misses nothing this near
        probs = vlm.probabilities(VisualQuery(observation, prompt, LETTERS))
        return choices[LETTERS.index(max(probs, key=probs.__getitem__))]

    empty = view(40, 60, [(CABINET, (0, 0, 40, 60))])
    holding = view(40, 60, [(CABINET, (0, 0, 40, 60)), (HAMMER, (10, 20, 15, 20))])
    assert [best(empty, seed) for seed in range(20)].count("No") >= 18
    assert [best(side_by_side([empty, holding]), seed) for seed in range(20)].count("Yes") >= 18


def test_a_drawer_left_shut_keeps_an_open_and_empty_chest_from_settling_no() -> None:
    """Shown one empty drawer of a chest beside a drawer still shut, the VLM cannot be sure the chest
    holds no hammer; once every drawer has been seen open (each in its own view), it can."""
    question = "Is there any hammer in the drawer chest in the bedroom?"
    prompt = answer_prompt(question, ["Yes", "No", PAD_CHOICE, PAD_CHOICE])
    chest = InstanceLabel(3, "drawer chest", "white", state="open")
    top, bottom = (2, 5, 17, 50), (21, 5, 17, 50)  # the drawers' fronts on the chest's face

    def drawers(top_state: str, bottom_state: str) -> Observation:
        return view(40, 60, [(chest, (0, 0, 40, 60)), (InstanceLabel(4, "drawer", "white", state=top_state), top),
                             (InstanceLabel(5, "drawer", "white", state=bottom_state), bottom)])

    def relevance(observation: Observation, seed: int) -> float:
        vlm = SimulatedVLM(SimParams(seed=seed, skill=1.0, notice_area_px=10.0))
        return vlm.probabilities(VisualQuery(observation, relevance_prompt(question), YES_NO))["Yes"]

    def p_no(observation: Observation, seed: int) -> float:
        vlm = SimulatedVLM(SimParams(seed=seed, skill=1.0, notice_area_px=10.0))
        return vlm.probabilities(VisualQuery(observation, prompt, LETTERS))["B"]

    partial = drawers("open", "closed")
    whole = side_by_side([drawers("open", "closed"), drawers("closed", "open")])
    assert {label.id: label.state for label in whole.labels}[5] == "open"
    partial_relevance = np.mean([relevance(partial, seed) for seed in range(40)])
    whole_relevance = np.mean([relevance(whole, seed) for seed in range(40)])
    assert whole_relevance > partial_relevance + 0.15
    assert np.mean([p_no(whole, seed) for seed in range(40)]) > np.mean([p_no(partial, seed) for seed in range(40)])
