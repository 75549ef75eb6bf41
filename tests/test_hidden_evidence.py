"""Evidence inside closed storage: the VLM simulator gets none until the robot opens the door."""

from __future__ import annotations

import math

import numpy as np
import pytest

from agent.eqa.prompts import answer_prompt
from agent.mapping.camera import Intrinsics
from agent.observation import InstanceLabel, Observation
from agent.vlm.protocol import VisualQuery
from agent.vlm.sim import SimParams, SimulatedVLM
from worlds.facts import HomeFacts
from worlds.home import generate_home
from worlds.robot import CameraConfig
from worlds.scenario import make_scenario
from worlds.sim import World
from worlds.bus.questions import LETTERS


def _yes_case():
    """A home whose hidden question is 'Is there any X in the Y in the Z?' with answer Yes, behind a door."""
    for seed in range(200):
        home = generate_home(seed)
        scenario = make_scenario(home, seed, kinds=("existence",), hidden=True)
        if scenario.answer_text != "Yes":
            continue
        facts = HomeFacts(home)
        [storage] = [f for f in home.furniture if f.room == scenario.target["room"] and f.category == scenario.target["container"]]
        inside = [o for o in home.objects if facts.storage_of(o) == storage and o.category == scenario.target["category"]
                  and o.relation == "inside" and o.parent == storage.instance_id]
        if inside and storage.storage.part(storage.storage.slot(inside[0].slot).access).kind == "door":
            return home, scenario, storage, inside[0]
    pytest.skip("no seed below 200 hides the answer behind a door")


def _observation(frame, camera: CameraConfig, base_pose) -> Observation:
    intrinsics = Intrinsics(camera.width, camera.height, *camera.intrinsics())
    labels = tuple(InstanceLabel.from_meta(label) for label in frame.labels)
    return Observation(frame.rgb, frame.depth, frame.seg, labels, intrinsics, frame.camera_pose, base_pose)


@pytest.fixture(scope="module")
def views():
    home, scenario, storage, item = _yes_case()
    camera = CameraConfig()
    world = World(camera)
    world.start(home, scenario)
    x, y, _ = storage.center
    heading = storage.facing + math.pi  # look back at the front
    stand = (x + 1.6 * math.cos(storage.facing), y + 1.6 * math.sin(storage.facing), heading)
    world.place(stand)
    closed = _observation(world.observe(), camera, stand)
    access = storage.storage.slot(item.slot).access
    world.set_part_state(storage.instance_id, access, storage.storage.part(access).upper)
    opened = _observation(world.observe(), camera, stand)
    door = world.stage.built.storage[storage.instance_id].placement.part_ids()[access]
    world.close()
    return scenario, item, closed, opened, door


def _p_yes(observation: Observation, scenario, vlm_seed: int) -> float:
    vlm = SimulatedVLM(SimParams(seed=vlm_seed, skill=1.0, notice_area_px=20.0))
    probs = vlm.probabilities(VisualQuery(observation, answer_prompt(scenario.question, list(scenario.choices)), LETTERS))
    return probs[LETTERS[scenario.choices.index("Yes")]]


def test_the_hidden_object_is_not_in_the_closed_frame_and_is_in_the_open_one(views) -> None:
    _, item, closed, opened, _ = views
    assert item.instance_id not in {label.id for label in closed.labels}
    seen = [label for label in opened.labels if label.id == item.instance_id]
    assert seen and seen[0].inside is not None


def test_the_vlm_has_no_evidence_until_the_door_is_opened(views) -> None:
    scenario, _, closed, opened, _ = views
    closed_answers = [_p_yes(closed, scenario, k) > 0.5 for k in range(20)]
    opened_yes = [_p_yes(opened, scenario, k) for k in range(20)]
    # Closed: no evidence, so every seed answers the question's fixed favourite, right or wrong.
    assert len(set(closed_answers)) == 1
    assert np.mean(opened_yes) > 0.8


def test_a_door_of_the_storage_shows_whether_it_stands_open(views) -> None:
    _, _, closed, opened, door = views
    assert {label.id: label.state for label in closed.labels}.get(door) == "closed"
    assert {label.id: label.state for label in opened.labels}[door] == "open"
