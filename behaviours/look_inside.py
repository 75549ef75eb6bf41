"""LookInside: the act of explore, query, check and act. Open the storage the question asks about.

A question such as "Is there any milk carton in the fridge in the kitchen?" cannot be answered by
looking: the evidence is behind a door. When the question asks what is *in* or *inside* a kind of
storage, and a piece of that kind with a handle on a door or drawer has been seen within
``reach_m`` of the robot (in the room the question names, when the frame says which room a piece
stands in; pieces seen in another room are left alone), this behaviour has the robot
(`agent.acsg.robot.Robot`) drive to a stand clear of what the opening sweeps (`skills.stand`),
along a path over the robot's map, open one of its doors or drawers, take frames while it stands
open (a door held open by its handle, looked at with the head camera, then pushed shut from the
same grasp; a drawer let go and looked into with the wrist camera, then closed), and fold the arm
away. The robot stays at that stand, and a frame taken inside becomes the blackboard's
observation (`_view_for_vlm`), so the `QueryVLM` after it sees what was revealed and the next move
starts from where the robot is. A part held back halfway is looked into all the same when it
stands open far enough to show something (`LookInsideConfig.min_look`), and shut again before the
robot moves on: a door left open blocks the way.

Each part is opened once per episode; a later step tries the next one. The arm takes seconds; the
behaviour stays RUNNING meanwhile (the robot works in a thread of its own and the tree keeps
ticking). It fails, saying why, when there is nothing to open (so the tree goes on exploring) or
nothing could be seen inside; a robot that moved and saw nothing leaves a fresh frame from where it
stands as the observation. Every attempt is recorded under the blackboard key ``acts`` and in the
episode's record: what was tried, how far it opened, whether the frames went to the VLM, whether
it was closed again, and at which stage and why it failed.
"""

from __future__ import annotations

import logging
import math
import re
import time
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import py_trees
from py_trees.common import Access, Status

from agent import blackboard as bb
from agent.acsg.robot import Robot, RobotConfig
from agent.bus.rpc import QueryFailed
from agent.observation import Observation
from agent.perception.geometry import GeometryError
from agent.perception.memory import STORAGE_CATEGORIES, Instance, InstanceMemory, MemoryConfig
from agent.planning.route import Routes, routes_from
from agent.runtime.world_link import WorldLink
from skills.plan import SkillPlanError
from skills.stand import StandConfig

log = logging.getLogger(__name__)

PARTS = ("door", "drawer")
#: What a view into storage shows besides what lies in it.
NOT_CONTENTS = frozenset({*STORAGE_CATEGORIES, *PARTS, "handle", "floor", "wall"})
#: Parts attach to the part or piece with voxels this near (`MemoryConfig.part_gap_m`): a little
#: more than the memory's default, since storage is often first seen from metres away, where a
#: handle's few voxels lie further off its door.
PART_GAP_M = 0.07
_STORAGE_WORDS = "|".join(re.escape(w) for w in sorted(STORAGE_CATEGORIES, key=len, reverse=True))


def storage_in_question(question: str) -> str | None:
    """The kind of storage the question asks what is in ("in the fridge", "inside the cabinet")."""
    found = re.search(rf"\b(?:in|inside) the ({_STORAGE_WORDS})\b", question.lower())
    return found.group(1) if found else None


def room_in_question(question: str) -> str | None:
    """The room the storage the question asks about stands in ("in the cabinet in the laundry room")."""
    found = re.search(rf"\b(?:in|inside) the (?:{_STORAGE_WORDS}) in the ([a-z ]+?)\s*\?*$", question.lower().strip())
    return found.group(1) if found else None


@dataclass(frozen=True)
class LookInsideConfig:
    """``reach_m``: how near (base to the piece's centre) storage must be seen to be opened (the
    instance memory keeps nothing seen further than 4 m away, `MemoryConfig.max_depth_m`);
    ``skill_timeout_s``: how long one arm skill may run; ``min_look``: how far a part must stand
    open (rad for doors, m for drawers) for a frame of it to be worth the VLM's look; ``stand``:
    where the base stands to open (`skills.stand`)."""

    reach_m: float = 4.0
    skill_timeout_s: float = 120.0
    min_look: dict[str, float] = field(default_factory=lambda: {"door": math.radians(15.0), "drawer": 0.05})
    stand: StandConfig = field(default_factory=StandConfig)

    def __post_init__(self) -> None:
        for name in ("reach_m", "skill_timeout_s"):
            if not getattr(self, name) > 0:
                raise ValueError(f"act.{name}: {getattr(self, name)} must be positive")
        if set(self.min_look) != set(PARTS) or not all(v > 0 for v in self.min_look.values()):
            raise ValueError(f"act.min_look: {self.min_look!r} must give a positive opening for each of {PARTS}")


@dataclass(frozen=True)
class _Outcome:
    views: list[Observation]  # frames taken while the part stood open, for the VLM
    last: Observation | None  # a frame from where the robot ended, when it moved
    record: dict[str, Any]


class LookInside(py_trees.behaviour.Behaviour):
    def __init__(self, link: WorldLink, config: LookInsideConfig = LookInsideConfig(),
                 name: str = "LookInside") -> None:
        super().__init__(name)
        self.link = link
        self.config = config
        self.blackboard = self.attach_blackboard_client(name=name)
        self.blackboard.register_key(bb.QUESTION, access=Access.READ)
        self.blackboard.register_key(bb.MAP, access=Access.READ)
        self.blackboard.register_key(bb.ANSWER_LOG, access=Access.READ)
        self.blackboard.register_key(bb.OBSERVATION, access=Access.WRITE)
        self.blackboard.register_key(bb.TRAJECTORY, access=Access.WRITE)
        self.blackboard.register_key(bb.ACTS, access=Access.WRITE)
        self.memory = InstanceMemory(MemoryConfig(part_gap_m=PART_GAP_M))
        self.rooms: dict[int, str] = {}  # storage piece (memory id) -> the room its label named
        self.tried: set[int] = set()
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="look-inside")
        self._future: Future[_Outcome] | None = None
        self._why_not = ""

    def initialise(self) -> None:
        self._future, self._why_not = None, ""
        question = self.blackboard.get(bb.QUESTION)
        kind = storage_in_question(question)
        if kind is None:
            self._why_not = "the question asks about no storage"
            return
        observation: Observation = self.blackboard.get(bb.OBSERVATION)
        self._integrate(observation)
        part = self._next_part(kind, room_in_question(question), observation.base_pose)
        if part is None:
            self._why_not = f"no unopened {kind} door or drawer seen within {self.config.reach_m:g} m"
            return
        self.tried.add(part.id)
        routes = None
        if self.blackboard.exists(bb.MAP):  # planned here, while the map holds still
            routes = routes_from(self.blackboard.get(bb.MAP), np.asarray(observation.base_pose[:2]))
        self._future = self._pool.submit(self._open_and_look, kind, part, routes)

    def update(self) -> Status:
        if self._future is None:
            self.feedback_message = self._why_not
            return Status.FAILURE
        if not self._future.done():
            self.feedback_message = "the arm is at work"
            return Status.RUNNING
        outcome = self._future.result()
        if outcome.views and self.blackboard.exists(bb.ANSWER_LOG):  # the step the VLM's look inside will be
            outcome.record["step"] = len(self.blackboard.get(bb.ANSWER_LOG)) + 1
        acts = list(self.blackboard.get(bb.ACTS)) if self.blackboard.exists(bb.ACTS) else []
        self.blackboard.set(bb.ACTS, [*acts, outcome.record])
        self.feedback_message = outcome.record["outcome"]
        newest = _view_for_vlm(outcome.views) if outcome.views else outcome.last
        if newest is not None:
            self.blackboard.set(bb.OBSERVATION, newest)
            if self.blackboard.exists(bb.TRAJECTORY):
                self.blackboard.get(bb.TRAJECTORY).append(tuple(float(v) for v in newest.base_pose))
        return Status.SUCCESS if outcome.views else Status.FAILURE

    def _integrate(self, observation: Observation) -> None:
        """The frame into the memory, and the room of every storage piece it labels."""
        update = self.memory.integrate(observation)
        rooms = {label.id: label.room for label in observation.labels if label.category in STORAGE_CATEGORIES}
        for key in (*update.created, *update.updated):
            inst = self.memory.get(key)
            if inst.hint in rooms:
                self.rooms[inst.id] = rooms[inst.hint]

    def _next_part(self, kind: str, room: str | None, base_pose: tuple[float, float, float]) -> Instance | None:
        """The nearest unopened part with a handle of the nearest piece of ``kind`` within reach,
        pieces labelled in ``room`` first and pieces labelled in another room never."""
        here = np.asarray(base_pose[:2], dtype=float)
        pieces = []
        for piece in self.memory.with_label(kind):
            seen_in = self.rooms.get(piece.id)
            distance = float(np.linalg.norm(piece.centroid[:2] - here))
            if distance <= self.config.reach_m and (room is None or seen_in in (None, room)):
                pieces.append((seen_in != room, distance, piece.id))
        for _, _, piece_id in sorted(pieces):
            for child in self.memory.get(piece_id).children:
                part = self.memory.get(child)
                handled = any(self.memory.get(c).label == "handle" for c in part.children)
                if part.label in PARTS and handled and part.id not in self.tried and not part.gone:
                    return part
        return None

    def _open_and_look(self, kind: str, part: Instance, routes: Routes | None) -> _Outcome:
        """In the worker thread: open, look, close, stow. Never raises: the record says why."""
        began = time.monotonic()
        unit = "opening_deg" if part.label == "door" else "opening_m"
        record: dict[str, Any] = {"storage": kind, "part": f"{part.label} {part.id}", "opened": False, unit: 0.0,
                                  "looked": False, "closed": None, "stage": None, "reason": ""}
        robot = Robot(self.link, RobotConfig(skill_timeout_s=self.config.skill_timeout_s, stand=self.config.stand,
                                             hold_open=True),
                      memory=self.memory, routes=routes)
        views: list[Observation] = []
        stage = "look"
        try:
            robot.observe()
            stage = "open"
            opened = robot.open_part(part)
            amount = robot.opening(part)
            record.update({"opened": opened.ok, unit: round(math.degrees(amount) if unit == "opening_deg" else amount, 3)})
            if not opened.ok:
                record.update(stage=stage, reason=opened.reason)
            if amount >= self.config.min_look[part.label]:
                views = list(robot.views)
            if amount > 0:
                stage = "close"
                closed = robot.close_part(part)
                record["closed"] = closed.ok
                if not closed.ok and not record["stage"]:
                    record.update(stage=stage, reason=closed.reason)
            stage = "stow"
            robot.stow()
        except (GeometryError, SkillPlanError, QueryFailed, ValueError) as error:
            if not record["stage"]:
                record.update(stage=stage, reason=str(error))
        except Exception as error:  # a bug in the arm's code fails this act, not the whole episode
            log.exception("looking inside the %s raised", kind)
            if not record["stage"]:
                record.update(stage=stage, reason=f"{type(error).__name__}: {error}")
        record["looked"] = bool(views)
        record["outcome"] = _outcome_text(kind, part.label, record)
        record["seconds"] = round(time.monotonic() - began, 1)
        return _Outcome(views, None if views or not _moved(robot) else _head_frame(robot), record)


def _view_for_vlm(views: list[Observation]) -> Observation:
    """The frame the VLM is shown: the last close view into the part (the wrist camera's, into a
    drawer) when something lies in view there besides the storage itself, else the first, the head
    camera's view of the storage standing open (which shows whether anything is there at all)."""
    for view in reversed(views[1:]):
        if any(label.category not in NOT_CONTENTS for label in view.labels):
            return view
    return views[0]


def _moved(robot: Robot) -> bool:
    """Whether the base stands elsewhere than where the robot first looked."""
    if robot.home is None or robot.pose is None:
        return False
    return bool(np.max(np.abs(np.subtract(robot.pose, robot.home))) > 0.01)


def _head_frame(robot: Robot) -> Observation | None:
    """A head frame from where the robot stands, or None when the world does not answer."""
    try:
        return Observation.from_message(robot.link.call("observe", {"camera": "head"}))
    except (QueryFailed, ValueError):
        return None


def _outcome_text(kind: str, label: str, record: dict[str, Any]) -> str:
    """One line for the feedback message and the record."""
    if record["looked"]:
        text = f"opened the {kind}'s {label}, looked inside"
        if record["stage"] == "open":
            text += f" (it opened only part of the way: {record['reason']})"
    else:
        text = f"could not open the {kind}'s {label}: {record['reason']}"
    if record["closed"] is False:
        text += "; could not close it" + (f": {record['reason']}" if record["stage"] == "close" else "")
    elif record["stage"] == "stow":
        text += f"; {record['reason']}"
    return text
