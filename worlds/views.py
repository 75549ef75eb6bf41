"""Views of a home for measuring a VLM: frames that show a question's target, and frames from
anywhere.

A VLM's answers are worth measuring where it should know (the thing asked about in clear view)
and where it cannot (nothing of the question in view). Which instances a question is about is
ground truth (`worlds.targets.question_target`), which no VLM may see: here it only picks the
views and says, with each, how much of the frame the target fills and whether anything of the
question is in view. The frames themselves are the head camera's, rendered as the robot would see
them from a free spot of the floor. Every choice comes from the generator passed in.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from worlds.camera import Frame
from worlds.freespace import clearance
from worlds.home import HomeSpec
from worlds.robot import ROBOT_RADIUS
from worlds.scenario import Scenario
from worlds.sim import World
from worlds.targets import Target
from worlds.things import Label
from worlds.vocabulary import FURNITURE, OBJECTS

Pose = tuple[float, float, float]

#: The robot stands at least this far from any obstacle in a view.
_STAND_CLEARANCE = ROBOT_RADIUS + 0.05
#: Distances (m) from the target's centre a view of it is taken from.
_NEAR_M, _FAR_M = 0.6, 3.0


@dataclass(frozen=True)
class View:
    """A head frame from ``base_pose``; ``target_share``: the share of its pixels the question's
    target things fill (with their doors, drawers and handles), 0 unless every one of them is in
    the frame, and 0 for a room (a "No" to "Is there a … in the kitchen?": no thing shows the
    answer); ``relevant``: whether any instance of the kind the question asks about is in view."""

    frame: Frame
    base_pose: Pose
    target_share: float
    relevant: bool


def relevant(label: Label, scenario: Scenario) -> bool:
    """Whether an instance is of the kind the question asks about: the storage piece it names,
    else the thing or appliance, with the colour it names (any thing of that colour when it names
    no kind).

    Args:
        label: the instance's label.
        scenario: the scenario.

    Returns:
        Whether it is relevant.
    """
    t = scenario.target
    kind = t["container"] or t["category"] or t["appliance"]
    if label["category"] not in OBJECTS and label["category"] not in FURNITURE:
        return False
    return kind in (None, label["category"]) and t["colour"] in (None, label["colour"])


def aimed_views(world: World, scenario: Scenario, target: Target, count: int, rng: np.random.Generator,
                tries: int = 24) -> list[View]:
    """Up to ``count`` views from where the answer shows, ``tries`` spots at most: facing the
    centre of the target things from free spots `_NEAR_M`–`_FAR_M` from it, every thing in the
    frame (for a room, its floor).

    Args:
        world: the world, reset to the home.
        scenario: the scenario.
        target: its target.
        count: the views wanted.
        rng: the spots' generator.
        tries: spots tried at most.

    Returns:
        The views.
    """
    assert world.home is not None
    cx, cy = np.mean([thing["xy"] for thing in target.things], axis=0)
    views: list[View] = []
    for _ in range(tries):
        if len(views) >= count:
            break
        distance, bearing = rng.uniform(_NEAR_M, _FAR_M), rng.uniform(-math.pi, math.pi)
        x, y = cx + distance * math.cos(bearing), cy + distance * math.sin(bearing)
        if not _free(world.home, x, y):
            continue
        view = _view(world, scenario, (x, y, math.atan2(cy - y, cx - x) + rng.normal(0.0, 0.1)), target)
        if view.whole:
            views.append(view.view)
    return views


def random_views(world: World, scenario: Scenario, target: Target, count: int,
                 rng: np.random.Generator, tries: int = 200) -> list[View]:
    """``count`` views from free spots drawn anywhere in the home, facing anywhere.

    Args:
        world: the world, reset to the home.
        scenario: the scenario.
        target: its target.
        count: the views wanted.
        rng: the spots' generator.
        tries: spots tried at most.

    Returns:
        The views.
    """
    assert world.home is not None
    x0, y0, x1, y1 = world.home.bounds
    views: list[View] = []
    for _ in range(tries):
        if len(views) >= count:
            break
        x, y = rng.uniform(x0, x1), rng.uniform(y0, y1)
        if _free(world.home, x, y):
            views.append(_view(world, scenario, (x, y, rng.uniform(-math.pi, math.pi)), target).view)
    return views


def _free(home: HomeSpec, x: float, y: float) -> bool:
    return home.room_at(x, y) is not None and clearance(home, x, y) >= _STAND_CLEARANCE


@dataclass(frozen=True)
class _Rendered:
    view: View
    whole: bool  # every target thing in the frame


def _view(world: World, scenario: Scenario, pose: Pose, target: Target) -> _Rendered:
    world.place(pose)
    frame = world.observe()
    ids, counts = np.unique(frame.seg, return_counts=True)
    pixels = dict(zip(ids.tolist(), counts.tolist()))
    whole = all(thing["id"] in pixels for thing in target.things)
    share = sum(pixels.get(i, 0) for i in target.ids) / frame.seg.size if whole and target.kind != "room" else 0.0
    relevant_in_view = any(relevant(label, scenario) for label in frame.labels)
    return _Rendered(View(frame, world.base_pose, share, relevant_in_view), whole)
