"""The simulated VLM, shown frames built by hand, and the validation of observe replies."""

from __future__ import annotations

from collections import Counter
from dataclasses import replace
from typing import Any

import numpy as np
import pytest

from worlds.bus.codec import Message, decode, encode
from agent.eqa.prompts import YES_NO, answer_prompt, relevance_prompt
from agent.mapping.camera import Intrinsics
from agent.observation import InstanceLabel, Observation, ObservationError
from agent.vlm.protocol import VisualQuery
from agent.vlm.sim import SimParams, SimulatedVLM
from worlds.bus.questions import LETTERS, PAD_CHOICE

H, W = 48, 64
INTRINSICS = Intrinsics(W, H, 32.0, 32.0, 32.0, 24.0)
QUESTION = "What colour is the mug in the kitchen?"
CHOICES = ["red", "blue", "green", "yellow"]
FLOOR = InstanceLabel(1, "floor", "grey")
MUG = InstanceLabel(7, "mug", "red")
#: What tells a room in these frames: a piece standing on the floor at the right edge.
ROOM_CUES = {"kitchen": "stove", "office": "desk", "bedroom": "bed"}


def frame(index: int, mug: tuple[int, int, int] | None = None, mug_depth: float = 1.0,
          room: str | None = "kitchen") -> Observation:
    """A frame: floor (id 1) on the lower half, a piece of furniture (id 3) standing on it at the
    right that says which ``room`` this is (none for None), optionally a square mug (id 7) at
    (row, col, side).

    ``index`` shifts every depth a little, which changes the frame's hash and so the model's draws.
    """
    shift = index * 1e-3
    depth = np.full((H, W), 2.0 + shift, dtype=np.float32)
    seg = np.full((H, W), -1, dtype=np.int32)
    seg[H // 2 :, :] = 1
    labels = [FLOOR]
    if room is not None:
        seg[H // 2 - 12 : H // 2 + 4, W - 14 : W - 2] = 3  # its foot on the floor, at the floor's depth
        labels.append(InstanceLabel(3, ROOM_CUES[room], "white"))
    if mug is not None:
        row, col, side = mug
        seg[row : row + side, col : col + side] = 7
        depth[row : row + side, col : col + side] = mug_depth + shift
        labels.append(MUG)
    return Observation(np.zeros((H, W, 3), dtype=np.uint8), depth, seg, tuple(labels), INTRINSICS,
                       np.eye(4), (0.0, 0.0, 0.0))


NEAR_BIG = (10, 10, 30)  # 900 px at 1 m
FAR_TINY = (5, 30, 3)  # 9 px, placed at 6 m


def answer(vlm: SimulatedVLM, observation: Observation, choices: list[str] = CHOICES,
           question: str = QUESTION) -> dict[str, float]:
    return vlm.probabilities(VisualQuery(observation, answer_prompt(question, choices), LETTERS))


def relevance(vlm: SimulatedVLM, observation: Observation, question: str = QUESTION) -> float:
    probs = vlm.probabilities(VisualQuery(observation, relevance_prompt(question), YES_NO))
    assert set(probs) == {"Yes", "No"}
    assert sum(probs.values()) == pytest.approx(1.0)
    return probs["Yes"]


def argmax(probs: dict[str, float]) -> str:
    return max(probs, key=probs.__getitem__)


def favourite_letter(vlm: SimulatedVLM) -> str:
    """The choice the model favours when it sees nothing relevant (the majority over empty frames)."""
    return Counter(argmax(answer(vlm, frame(i))) for i in range(20)).most_common(1)[0][0]


def test_big_near_mug_gives_its_colour() -> None:
    vlm = SimulatedVLM()
    probs = [answer(vlm, frame(i, NEAR_BIG))["A"] for i in range(40)]
    assert np.mean(probs) > 0.7
    assert np.mean(np.array(probs) > 0.7) > 0.6


def test_evidence_wins_wherever_the_choice_stands() -> None:
    """Red is picked from its content, not its position: moving it to each letter moves the answer."""
    vlm = SimulatedVLM()
    for position in range(4):
        choices = [c for c in CHOICES if c != "red"]
        choices.insert(position, "red")
        wins = Counter(argmax(answer(vlm, frame(i, NEAR_BIG), choices)) for i in range(30))
        assert wins.most_common(1)[0][0] == LETTERS[position]


def test_without_evidence_the_biased_favourite_wins_confidently() -> None:
    vlm = SimulatedVLM()
    answers = [answer(vlm, frame(i)) for i in range(20)]
    winners = Counter(argmax(p) for p in answers)
    favourite, count = winners.most_common(1)[0]
    assert count >= 18, winners
    assert np.mean([p[favourite] for p in answers]) > 0.6
    # the same favourite whatever the view, as long as it shows nothing relevant
    other_room = Counter(argmax(answer(vlm, frame(i, room="office"))) for i in range(20))
    assert other_room.most_common(1)[0][0] == favourite


def test_same_inputs_same_probabilities_and_seed_changes_them() -> None:
    observation = frame(3, NEAR_BIG)
    first = answer(SimulatedVLM(), observation)
    assert answer(SimulatedVLM(), observation) == first
    assert answer(SimulatedVLM(SimParams(seed=0)), frame(3, NEAR_BIG)) == first
    assert answer(SimulatedVLM(SimParams(seed=1)), observation) != first
    assert relevance(SimulatedVLM(), observation) == relevance(SimulatedVLM(), observation)
    assert relevance(SimulatedVLM(SimParams(seed=5)), observation) != relevance(SimulatedVLM(), observation)


def test_a_different_frame_changes_the_draws() -> None:
    vlm = SimulatedVLM()
    assert answer(vlm, frame(1)) != answer(vlm, frame(2))


def test_far_tiny_mug_is_noticed_less_often_than_near_big() -> None:
    vlm = SimulatedVLM()
    favourite = LETTERS.index(favourite_letter(vlm))
    choices = [c for c in CHOICES if c != "red"]
    red_at = (favourite + 1) % 4  # so red only wins when the mug is noticed
    choices.insert(red_at, "red")

    def noticed(mug: tuple[int, int, int], depth: float) -> int:
        return sum(answer(vlm, frame(i, mug, depth), choices)[LETTERS[red_at]] > 0.5 for i in range(60))

    near, far = noticed(NEAR_BIG, 1.0), noticed(FAR_TINY, 6.0)
    assert near >= 40
    assert far <= 10
    assert near > far + 25


def test_relevance_is_higher_with_evidence() -> None:
    vlm = SimulatedVLM()
    with_mug = np.mean([relevance(vlm, frame(i, NEAR_BIG)) for i in range(50)])
    without = np.mean([relevance(vlm, frame(i)) for i in range(50)])
    assert with_mug > without + 0.4
    assert with_mug > 0.75
    # Seeing the kitchen without a red mug makes "No" a likely guess: more relevant than a view of
    # the office, which says nothing about the kitchen.
    exists = "Is there a red mug in the kitchen?"
    kitchen = np.mean([relevance(vlm, frame(i), exists) for i in range(50)])
    office = np.mean([relevance(vlm, frame(i, room="office"), exists) for i in range(50)])
    assert kitchen > office + 0.15


@pytest.mark.parametrize("mug", [None, NEAR_BIG, FAR_TINY])
def test_probabilities_sum_to_one(mug: tuple[int, int, int] | None) -> None:
    vlm = SimulatedVLM()
    for i in range(10):
        observation = frame(i, mug, 3.0)
        for choices in (CHOICES, ["red", "blue", PAD_CHOICE, PAD_CHOICE]):
            probs = answer(vlm, observation, choices)
            assert set(probs) == set(LETTERS)
            assert sum(probs.values()) == pytest.approx(1.0)
            assert all(0.0 <= p <= 1.0 for p in probs.values())
        assert 0.0 <= relevance(vlm, observation) <= 1.0


def test_padded_choices_get_tiny_probability() -> None:
    vlm = SimulatedVLM()
    for i in range(20):
        for mug in (None, NEAR_BIG):
            probs = answer(vlm, frame(i, mug), ["blue", "green", PAD_CHOICE, PAD_CHOICE])
            assert probs["C"] < 0.01 and probs["D"] < 0.01


def test_unparseable_prompt_gives_uniform() -> None:
    probs = SimulatedVLM().probabilities(VisualQuery(frame(0, NEAR_BIG), "Describe the image.", ("x", "y", "z")))
    assert probs == pytest.approx({"x": 1 / 3, "y": 1 / 3, "z": 1 / 3})


def test_existence_question_says_yes_for_a_seen_object() -> None:
    vlm = SimulatedVLM()
    question = "Is there a red mug in the kitchen?"
    seen = np.mean([answer(vlm, frame(i, NEAR_BIG), ["yes", "no"], question)["A"] for i in range(30)])
    assert seen > 0.7


LOCATION = "Which room is the red mug in?"
ROOMS = ["bathroom", "bedroom", "kitchen", "office"]


def on_the_floor(index: int, room: str | None) -> Observation:
    """The red mug standing on the floor, beside the furniture that tells ``room`` (if any)."""
    observation = frame(index, room=room)
    seg = observation.segmentation.copy()
    seg[H // 2 - 10 : H // 2 + 4, 16:30] = 7  # its foot on the floor, at the floor's depth
    return replace(observation, segmentation=seg, labels=(*observation.labels, MUG))


def test_the_room_a_thing_is_in_is_read_off_the_furniture_beside_it() -> None:
    vlm = SimulatedVLM(SimParams(room_error=0.0))
    for room in ("bedroom", "kitchen", "office"):
        answers = Counter(ROOMS[LETTERS.index(argmax(answer(vlm, on_the_floor(i, room), ROOMS, LOCATION)))]
                          for i in range(30))
        assert answers[room] >= 28, (room, answers)
        assert np.mean([relevance(vlm, on_the_floor(i, room), LOCATION) for i in range(30)]) > 0.75


def test_a_thing_alone_in_view_tells_no_room_and_the_model_only_guesses() -> None:
    """No label names a room: a red mug with nothing around it gets the common-sense guess (a
    kitchen), with a guess's confidence."""
    vlm = SimulatedVLM()
    alone = [frame(i, NEAR_BIG, room=None) for i in range(40)]
    answers = Counter(ROOMS[LETTERS.index(argmax(answer(vlm, f, ROOMS, LOCATION)))] for f in alone)
    assert answers["kitchen"] >= 36, answers
    told = np.mean([relevance(vlm, on_the_floor(i, "bedroom"), LOCATION) for i in range(40)])
    assert np.mean([relevance(vlm, f, LOCATION) for f in alone]) < told - 0.2


def test_rooms_are_misjudged_at_the_documented_rate() -> None:
    for error in (0.0, 0.3):
        vlm = SimulatedVLM(SimParams(room_error=error, skill=1.0, notice_area_px=10.0, notice_near_m=5.0))  # sees the mug
        wrong = np.mean([argmax(answer(vlm, on_the_floor(i, "bedroom"), ROOMS, LOCATION)) != "B" for i in range(300)])
        assert abs(wrong - error) < 0.07, (error, wrong)


def test_a_thing_seen_in_another_room_than_the_named_one_counts_only_as_a_guess() -> None:
    """The red mug stands in an office; asked about the mug in the kitchen, the model still names
    its colour, without the confidence of a mug seen where the question says."""
    vlm = SimulatedVLM(SimParams(room_error=0.0))
    office = [on_the_floor(i, "office") for i in range(40)]
    kitchen = [on_the_floor(i, "kitchen") for i in range(40)]
    assert sum(argmax(answer(vlm, f)) == "A" for f in office) >= 36
    assert np.mean([relevance(vlm, f) for f in kitchen]) > np.mean([relevance(vlm, f) for f in office]) + 0.2


@pytest.mark.parametrize("field, value", [("skill", 2.0), ("skill", -0.1), ("misread", 1.5), ("room_error", 1.1)])
def test_sim_params_out_of_range(field: str, value: float) -> None:
    with pytest.raises(ValueError, match=rf"vlm\.sim\.{field}"):
        SimParams(**{field: value})


def test_sim_params_negative_scales() -> None:
    with pytest.raises(ValueError, match=r"vlm\.sim\.notice_area_px"):
        SimParams(notice_area_px=-1.0)


# --- Observation.from_message ------------------------------------------------------------------


def reply(**changes: Any) -> Message:
    """A valid observe reply sent through the codec, with some fields replaced."""
    seg = np.full((H, W), -1, dtype=np.int32)
    seg[H // 2 :, :] = 1
    seg[5:15, 5:15] = 7
    meta: dict[str, Any] = {
        "camera": {"width": W, "height": H, "fx": 32.0, "fy": 32.0, "cx": 32.0, "cy": 24.0},
        "camera_pose": np.eye(4).tolist(),
        "base_pose": [1.0, 2.0, 0.5],
        "labels": [{"id": 1, "category": "floor", "colour": "grey"}, {"id": 7, "category": "mug", "colour": "red"}],
        "render_ms": 4.5,
    }
    arrays = {"rgb": np.zeros((H, W, 3), np.uint8), "depth": np.ones((H, W), np.float32), "seg": seg}
    for key, value in changes.items():
        if key in arrays:
            arrays[key] = value
        else:
            meta[key] = value
    return decode(encode(meta, arrays))


def test_from_message_accepts_a_consistent_reply() -> None:
    observation = Observation.from_message(reply())
    assert observation.intrinsics == INTRINSICS
    assert observation.base_pose == (1.0, 2.0, 0.5)
    assert observation.labels == (FLOOR, MUG)
    assert observation.render_ms == 4.5
    assert observation.rgb.shape == (H, W, 3) and observation.depth.dtype == np.float32


def test_from_message_rejects_rgb_shape_mismatch() -> None:
    with pytest.raises(ObservationError, match=r"rgb is uint8\[24, 64, 3\], the camera says uint8\[48, 64, 3\]"):
        Observation.from_message(reply(rgb=np.zeros((24, W, 3), np.uint8)))


def test_from_message_rejects_wrong_dtype() -> None:
    with pytest.raises(ObservationError, match=r"depth is float64"):
        Observation.from_message(reply(depth=np.ones((H, W), np.float64)))


def test_from_message_rejects_labels_not_in_frame() -> None:
    labels = [{"id": 1, "category": "floor", "colour": "grey"}, {"id": 7, "category": "mug", "colour": "red"},
              {"id": 9, "category": "book", "colour": "blue"}]
    with pytest.raises(ObservationError, match=r"labels name instances \[9\] not in the frame"):
        Observation.from_message(reply(labels=labels))


def test_from_message_rejects_instances_without_labels() -> None:
    labels = [{"id": 1, "category": "floor", "colour": "grey"}]
    with pytest.raises(ObservationError, match=r"miss \[7\]"):
        Observation.from_message(reply(labels=labels))


def test_from_message_rejects_missing_fields_and_bad_pose() -> None:
    message = reply()
    del message.arrays["seg"]
    with pytest.raises(ObservationError, match=r"missing or malformed field"):
        Observation.from_message(message)
    message = reply()
    del message.meta["camera"]
    with pytest.raises(ObservationError, match=r"missing or malformed field"):
        Observation.from_message(message)
    skewed = np.eye(4)
    skewed[0, 0] = 2.0
    with pytest.raises(ObservationError, match=r"camera_pose must be a 4x4 rigid transform"):
        Observation.from_message(reply(camera_pose=skewed.tolist()))
    with pytest.raises(ObservationError, match=r"base_pose"):
        Observation.from_message(reply(base_pose=[1.0, 2.0]))
