"""Cases for measuring a VLM (`agent.vlm.measure`), rendered from generated homes.

For each home seed, a few questions drawn as scenarios (hidden-evidence questions aside: their
answer shows only once the robot opens something), and for each question up to ``views`` frames
from where the answer shows (`worlds.views.aimed_views`: the target of `worlds.targets` in view
from 0.6–3 m, or the room a "No" is about) and as many from anywhere in the home
(`worlds.views.random_views`). Each frame becomes what the agent would receive, with the
question's right letter, the share of the frame its target fills, whether anything of the
question is in view, and, for measuring how the simulator judges rooms, the true room kind of
every floor in view. Every choice is seeded by the home seed, so the same seeds give the same
cases.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from agent.mapping.camera import Intrinsics
from agent.observation import InstanceLabel, Observation
from agent.vlm.measure import Case
from worlds.home import generate_home
from worlds.robot import CameraConfig
from worlds.scenario import make_scenario
from worlds.sim import World
from worlds.targets import question_target
from worlds.views import View, aimed_views, random_views

#: Scenario seeds of a home's questions are ``QUESTION_SEEDS * home seed + k``: apart from the
#: home's own scenario (seed = home seed) and from every other home's.
QUESTION_SEEDS = 1000


def home_cases(seeds: Iterable[int], questions: int = 3, views: int = 3,
               camera: CameraConfig = CameraConfig()) -> list[Case]:
    """The cases of every home seed (module docstring), rendered with ``camera``.

    Args:
        seeds: the home seeds.
        questions: the questions per home.
        views: the views per question.
        camera: the camera.

    Returns:
        The cases.
    """
    world = World(camera)
    intrinsics = Intrinsics(camera.width, camera.height, *camera.intrinsics())
    cases = []
    try:
        for seed in seeds:
            home = generate_home(seed)
            world.build(home)
            rooms = {room.instance_id: room.kind for room in home.rooms}
            for k in range(questions):
                scenario = make_scenario(home, QUESTION_SEEDS * seed + k, hidden=False)
                rng = np.random.default_rng([seed, k])
                target = question_target(home, scenario.target)
                aimed = aimed_views(world, scenario, target, views, rng)
                for view in (*aimed, *random_views(world, scenario, target, len(aimed), rng)):
                    cases.append(Case(_observation(view, intrinsics), scenario.question, scenario.choices,
                                      scenario.answer, view.target_share, view.relevant,
                                      {i: rooms[i] for i in np.unique(view.frame.seg).tolist() if i in rooms}))
    finally:
        world.close()
    return cases


def _observation(view: View, intrinsics: Intrinsics) -> Observation:
    """The frame as the agent receives it from the world (`Observation.from_message`)."""
    frame = view.frame
    labels = tuple(InstanceLabel.from_meta(label) for label in frame.labels)
    return Observation(frame.rgb, frame.depth, frame.seg, labels, intrinsics, frame.camera_pose, view.base_pose)
