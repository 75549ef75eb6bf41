"""LookInside: the act of explore, query, check and act. Open the storage the question asks about.

A question such as "Is there any milk carton in the fridge in the kitchen?" cannot be answered by
looking: the evidence is behind a door. When the question asks what is *in* or *inside* a kind of
storage, and a piece of that kind with a handle on a door or drawer has been seen within
``reach_m`` of the robot, this behaviour has the robot (`agent.acsg.robot.Robot`) drive up to it,
open one of its doors or drawers, take frames while it stands open, close it again and drive back.
The newest frame taken inside becomes the blackboard's observation, so the `QueryVLM` after it sees
what was revealed. Each part is opened once per episode; a later step tries the next one.

The arm takes seconds; the behaviour stays RUNNING meanwhile (the robot works in a thread of its
own and the tree keeps ticking). It fails, saying why, when there is nothing to open (so the tree
goes on exploring) or the robot could not open anything; every attempt is recorded under the
blackboard key ``acts`` and in the episode's record.
"""

from __future__ import annotations

import logging
import re
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any

import numpy as np
import py_trees
from py_trees.common import Access, Status

from agent import blackboard as bb
from agent.acsg.robot import Robot, RobotConfig
from agent.bus.rpc import QueryFailed
from agent.observation import Observation
from agent.perception.geometry import GeometryError
from agent.perception.memory import STORAGE_CATEGORIES, Instance, InstanceMemory
from agent.runtime.world_link import WorldLink
from skills.plan import SkillPlanError

log = logging.getLogger(__name__)

PARTS = ("door", "drawer")


def storage_in_question(question: str) -> str | None:
    """The kind of storage the question asks what is in ("in the fridge", "inside the cabinet")."""
    words = sorted(STORAGE_CATEGORIES, key=len, reverse=True)  # "drawer chest" before "chest"
    found = re.search(r"\b(?:in|inside) the (" + "|".join(re.escape(w) for w in words) + r")\b", question.lower())
    return found.group(1) if found else None


@dataclass(frozen=True)
class LookInsideConfig:
    """``reach_m``: how near (base to the piece's centre) storage must be seen to be opened;
    ``stand_off_m``: how far from a handle the base stands to open it."""

    reach_m: float = 3.0
    stand_off_m: float = 0.85
    skill_timeout_s: float = 120.0

    def __post_init__(self) -> None:
        for name in ("reach_m", "stand_off_m", "skill_timeout_s"):
            if not getattr(self, name) > 0:
                raise ValueError(f"act.{name}: {getattr(self, name)} must be positive")


class LookInside(py_trees.behaviour.Behaviour):
    def __init__(self, link: WorldLink, config: LookInsideConfig = LookInsideConfig(),
                 name: str = "LookInside") -> None:
        super().__init__(name)
        self.link = link
        self.config = config
        self.blackboard = self.attach_blackboard_client(name=name)
        self.blackboard.register_key(bb.QUESTION, access=Access.READ)
        self.blackboard.register_key(bb.OBSERVATION, access=Access.WRITE)
        self.blackboard.register_key(bb.ACTS, access=Access.WRITE)
        self.memory = InstanceMemory()
        self.tried: set[int] = set()
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="look-inside")
        self._future: Future[tuple[list[Observation], dict[str, Any]]] | None = None
        self._why_not = ""

    def initialise(self) -> None:
        self._future, self._why_not = None, ""
        kind = storage_in_question(self.blackboard.get(bb.QUESTION))
        if kind is None:
            self._why_not = "the question asks about no storage"
            return
        observation: Observation = self.blackboard.get(bb.OBSERVATION)
        self.memory.integrate(observation)
        part = self._next_part(kind, observation.base_pose)
        if part is None:
            self._why_not = f"no unopened {kind} door or drawer seen within {self.config.reach_m:g} m"
            return
        self.tried.add(part.id)
        self._future = self._pool.submit(self._open_and_look, kind, part)

    def update(self) -> Status:
        if self._future is None:
            self.feedback_message = self._why_not
            return Status.FAILURE
        if not self._future.done():
            self.feedback_message = "the arm is at work"
            return Status.RUNNING
        views, record = self._future.result()
        acts = list(self.blackboard.get(bb.ACTS)) if self.blackboard.exists(bb.ACTS) else []
        self.blackboard.set(bb.ACTS, [*acts, record])
        self.feedback_message = record["outcome"]
        if not views:
            return Status.FAILURE
        self.blackboard.set(bb.OBSERVATION, views[-1])
        return Status.SUCCESS

    def _next_part(self, kind: str, base_pose: tuple[float, float, float]) -> Instance | None:
        here = np.asarray(base_pose[:2], dtype=float)
        pieces = sorted((float(np.linalg.norm(p.centroid[:2] - here)), p.id) for p in self.memory.with_label(kind))
        for distance, piece_id in pieces:
            if distance > self.config.reach_m:
                break
            for child in self.memory.get(piece_id).children:
                part = self.memory.get(child)
                handled = any(self.memory.get(c).label == "handle" for c in part.children)
                if part.label in PARTS and handled and part.id not in self.tried and not part.gone:
                    return part
        return None

    def _open_and_look(self, kind: str, part: Instance) -> tuple[list[Observation], dict[str, Any]]:
        """In the worker thread: open, look, close, come back. Never raises: the record says why."""
        record: dict[str, Any] = {"storage": kind, "part": f"{part.label} {part.id}"}
        robot = Robot(self.link, RobotConfig(skill_timeout_s=self.config.skill_timeout_s,
                                             stand_off_m=self.config.stand_off_m), memory=self.memory)
        try:
            robot.observe()  # where it stands now is where it comes back to
            opened = robot.open_part(part)
            views = list(robot.views)
            if not opened.ok:
                record["outcome"] = f"could not open the {kind}'s {part.label}: {opened.reason}"
                return [], record
            closed = robot.close_part(part)
            record["closed"] = closed.ok
            robot.return_home()
            record["outcome"] = (f"opened the {kind}'s {part.label}, looked inside"
                                 + ("" if closed.ok else f"; could not close it: {closed.reason}"))
            return views, record
        except (GeometryError, SkillPlanError, QueryFailed, ValueError) as error:
            record["outcome"] = f"could not open the {kind}'s {part.label}: {error}"
            return [], record
        except Exception as error:  # a bug in the arm's code fails this act, not the whole episode
            log.exception("looking inside the %s raised", kind)
            record["outcome"] = f"could not open the {kind}'s {part.label}: {type(error).__name__}: {error}"
            return [], record
