"""LookInside: the act of explore, query, check and act. Open the storage the question asks about.

A question such as "Is there any milk carton in the fridge in the kitchen?" cannot be answered by
looking: the evidence is behind a door. When the question asks what is *in* or *inside* a kind of
storage, and a piece of that kind with a handle on a door or drawer has been seen within
``reach_m`` of the robot (in the room the question names, when the frames showed which room a
piece stands in: the furniture around it, `agent.perception.rooms`, else the room whose floor was
seen around it, `agent.planning.room_goal.room_of_piece`; pieces seen in another room are left
alone), this behaviour has the robot
(`skills.robot.Robot`) drive to a stand clear of what the opening sweeps (`skills.arm.stand`),
along a path over the robot's map, open one of its doors or drawers, take frames while it stands
open (a door held open by its handle, looked at with the head camera, then pushed shut from the
same grasp; a drawer let go and looked into with the wrist camera, then closed), and fold the arm
away; then the piece's next door or drawer, up to ``max_parts``. A part held back halfway is
looked into all the same when it stands open far enough to show something
(`LookInsideConfig.min_look`), and shut again before the robot moves on: a door left open blocks
the way (and one that cannot be shut ends the act).

Every compartment is shown to the VLM at once: the best view into each part opened
(`_view_for_vlm`), side by side (`agent.vlm.mosaic`), goes on the blackboard as ``inside_view`` for
the `QueryVLM` after this behaviour. Shown one compartment at a time, the VLM took the empty one
behind the first door for "nothing in the cabinet". When a door or drawer of the piece could not
be looked behind, the head frame of the piece as it stood (from the first stand reached) leads the
row, so the VLM sees that part still shut and does not take the rest for the whole piece open and
empty. The robot stays at its last stand, and a head
frame from there becomes the observation, so the next move starts from where the robot is.

Each part is opened once per episode. The arm takes seconds; the behaviour stays RUNNING meanwhile
(the robot works in a thread of its own and the tree keeps ticking). It fails, saying why, when
there is nothing to open (so the tree goes on exploring) or nothing could be seen inside; a robot
that moved and saw nothing leaves a fresh frame from where it stands as the observation. Every
attempt on a part is recorded under the blackboard key ``acts`` (`behaviours.episode_state.ActRecord`)
and in the episode's record: what was tried, where the piece stands (``piece_xy``), how far it opened, whether the frames went to
the VLM, whether it was closed again, and at which stage and why it failed.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import py_trees
from py_trees.common import Access, Status

from behaviours import blackboard as bb
from behaviours.episode_state import ActRecord, LookInsideState
from skills.robot import Robot, RobotConfig
from worlds.bus.rpc import QueryFailed
from agent.eqa.storage_question import room_in_question, storage_in_question
from agent.observation import Observation
from agent.perception.directions import GeometryError
from agent.perception.instances import STORAGE_CATEGORIES, Instance
from agent.perception.rooms import floor_points_by_kind, read_rooms
from agent.planning.room_goal import RoomFloors, room_of_piece
from agent.planning.route import Routes, routes_from
from worlds.bus.link import WorldLink
from agent.pose import Pose2D
from agent.vlm.mosaic import side_by_side
from behaviours.approach_storage import ApproachConfig
from skills.arm.skill_plan import SkillPlanError
from skills.arm.stand import StandConfig
from worlds.vocabulary import room_kind

log = logging.getLogger(__name__)

PARTS = ("door", "drawer")
#: What a view into storage shows besides what lies in it.
NOT_CONTENTS = frozenset({*STORAGE_CATEGORIES, *PARTS, "handle", "floor", "wall"})
#: Pieces of one kind with centres this near, in the same room, are one piece the memory holds in
#: fragments: "the cabinet in the bathroom" says there is one, and carcasses of one piece seen from
#: two sides lie well within this.
SIBLING_M = 1.0


@dataclass(frozen=True)
class LookInsideConfig:
    """``reach_m``: how near (base to the piece's centre) storage must be seen to be opened (the
    instance memory keeps nothing seen further than 4 m away, `MemoryConfig.max_depth_m`);
    ``skill_timeout_s``: how long one arm skill may run; ``min_look``: how far a part must stand
    open (rad for doors, m for drawers) for a frame of it to be worth the VLM's look; ``stand``:
    where the base stands to open (`skills.arm.stand`); ``max_parts``: doors and drawers of one piece
    opened in one act at most (a kitchen counter may have six); ``approach``: how the robot goes
    to look at storage seen farther off (`behaviours.approach_storage`)."""

    reach_m: float = 4.0
    skill_timeout_s: float = 120.0
    min_look: dict[str, float] = field(default_factory=lambda: {"door": math.radians(15.0), "drawer": 0.05})
    stand: StandConfig = field(default_factory=StandConfig)
    max_parts: int = 4
    approach: ApproachConfig = field(default_factory=ApproachConfig)

    def __post_init__(self) -> None:
        for name in ("reach_m", "skill_timeout_s"):
            if not getattr(self, name) > 0:
                raise ValueError(f"act.{name}: {getattr(self, name)} must be positive")
        if self.max_parts < 1:
            raise ValueError(f"act.max_parts: {self.max_parts} must be at least 1")
        if set(self.min_look) != set(PARTS) or not all(v > 0 for v in self.min_look.values()):
            raise ValueError(f"act.min_look: {self.min_look!r} must give a positive opening for each of {PARTS}")


@dataclass(frozen=True)
class _Outcome:
    views: list[Observation]  # for each part looked into, the frame of it for the VLM
    last: Observation | None  # a head frame from where the robot ended, when it moved
    records: list[ActRecord]  # one per part tried


class LookInside(py_trees.behaviour.Behaviour):
    """Opens the storage the question asks about and leaves the views inside for the VLM (see the
    module docstring). What it has seen and opened over the episode is the blackboard's
    ``look_inside_state``; the arm works in a thread of the executor made in `setup`.

    Args:
        link: the world link.
        config: how to open storage and look inside.
        name: the node's name.
    """

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
        self.blackboard.register_key(bb.INSIDE_VIEW, access=Access.WRITE)
        self.blackboard.register_key(bb.TRAJECTORY, access=Access.WRITE)
        self.blackboard.register_key(bb.ACTS, access=Access.WRITE)
        self.blackboard.register_key(bb.MAP_FIELDS, access=Access.WRITE)
        self.blackboard.register_key(bb.LOOK_INSIDE_STATE, access=Access.WRITE)
        self._pool: ThreadPoolExecutor | None = None
        self._future: Future[_Outcome] | None = None
        self._stop = threading.Event()  # the running act's: set, it opens no further part
        self._why_not = ""
        self._wake: Callable[[], None] | None = None

    def setup(self, **kwargs: Any) -> None:
        """Make the executor the arm works in; take the tree's ``wake``, if it hands one.

        Args:
            **kwargs: py_trees' setup arguments; ``wake`` is called once the act is done.
        """
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="look-inside")
        self._wake = kwargs.get("wake")

    def initialise(self) -> None:
        self._future, self._why_not = None, ""
        state: LookInsideState = self.blackboard.get(bb.LOOK_INSIDE_STATE)
        question = self.blackboard.get(bb.QUESTION)
        kind = storage_in_question(question)
        if kind is None:
            self._why_not = "the question asks about no storage"
            return
        observation: Observation = self.blackboard.get(bb.OBSERVATION)
        self._integrate(state, observation)
        part = self._next_part(state, kind, room_in_question(question), observation.base_pose)
        if part is None:
            self._why_not = f"no unopened {kind} door or drawer seen within {self.config.reach_m:g} m"
            return
        routes = None
        if self.blackboard.exists(bb.MAP):  # planned here, while the map holds still
            routes = routes_from(self.blackboard.get(bb.MAP), np.asarray(observation.base_pose[:2]),
                                 fields=self.blackboard.get(bb.MAP_FIELDS))
        self._stop = threading.Event()
        assert self._pool is not None, "LookInside.setup() makes the executor the arm works in"
        self._future = self._pool.submit(self._open_and_look, state, kind, part, routes, self._stop)
        if self._wake is not None:
            wake = self._wake
            self._future.add_done_callback(lambda _: wake())

    def update(self) -> Status:
        if self._future is None:
            self.feedback_message = self._why_not
            return Status.FAILURE
        if not self._future.done():
            self.feedback_message = "the arm is at work"
            return Status.RUNNING
        outcome = self._future.result()
        if outcome.views and self.blackboard.exists(bb.ANSWER_LOG):  # the step the VLM's look inside will be
            step = len(self.blackboard.get(bb.ANSWER_LOG)) + 1
            for record in outcome.records:
                if record.looked:
                    record.step = step
        acts = list(self.blackboard.get(bb.ACTS)) if self.blackboard.exists(bb.ACTS) else []
        self.blackboard.set(bb.ACTS, [*acts, *outcome.records])
        self.feedback_message = "; ".join(record.outcome for record in outcome.records)
        if outcome.views:
            self.blackboard.set(bb.INSIDE_VIEW, side_by_side(outcome.views))
        if outcome.last is not None:
            self.blackboard.set(bb.OBSERVATION, outcome.last)
            if self.blackboard.exists(bb.TRAJECTORY):
                self.blackboard.get(bb.TRAJECTORY).append(outcome.last.base_pose)
        return Status.SUCCESS if outcome.views else Status.FAILURE

    def terminate(self, new_status: Status) -> None:
        """Interrupted while the arm is at work: the act finishes the part in hand (shut again and
        the arm folded, as it must be for the base to drive) and opens no further one."""
        if new_status == Status.INVALID:
            self._stop.set()

    def shutdown(self) -> None:
        """At the end of the episode: wait for the part in hand, at most one skill's time, so that no
        arm command goes out after the episode has closed its link."""
        self._stop.set()
        if self._future is not None and not self._future.done():
            try:  # _open_and_look never raises: its records say what went wrong
                self._future.result(timeout=self.config.skill_timeout_s)
            except TimeoutError:
                log.warning("the arm was still at work %g s after the episode ended", self.config.skill_timeout_s)
        if self._pool is not None:
            self._pool.shutdown(wait=False, cancel_futures=True)

    def _integrate(self, state: LookInsideState, observation: Observation) -> None:
        """The frame into the memory, and the room kind of every storage piece it shows standing
        in a room that something in view names."""
        update = state.memory.integrate(observation)
        reading = read_rooms(observation)
        if state.floors is None and self.blackboard.exists(bb.MAP):
            state.floors = RoomFloors(self.blackboard.get(bb.MAP).spec)
        if state.floors is not None:
            for kind, points in floor_points_by_kind(observation, reading, self.config.approach.sightings.max_depth_m).items():
                state.floors.add(kind, points)
        rooms = {label.id: room for label in observation.labels if label.category in STORAGE_CATEGORIES
                 and (room := reading.room_of(label.id)) is not None}
        for key in (*update.created, *update.updated):
            inst = state.memory.get(key)
            if inst.hint in rooms:
                state.rooms[inst.id] = rooms[inst.hint]

    def _next_part(self, state: LookInsideState, kind: str, room: str | None, base_pose: Pose2D) -> Instance | None:
        """The first unopened part with a handle (`_untried_part`) of the nearest piece of ``kind``
        within reach, pieces seen in a room of ``room``'s kind first and pieces seen in a room of
        another kind never."""
        room = None if room is None else room_kind(room)
        here = np.asarray(base_pose[:2], dtype=float)
        pieces = []
        for piece in state.memory.with_label(kind):
            seen_in = self._room_of(state, piece)
            distance = float(np.linalg.norm(piece.centroid[:2] - here))
            if distance <= self.config.reach_m and (room is None or seen_in in (None, room)):
                pieces.append((seen_in != room, distance, piece.id))
        for _, _, piece_id in sorted(pieces):
            part = self._untried_part(state, piece_id)
            if part is not None:
                return part
        return None

    def _room_of(self, state: LookInsideState, piece: Instance) -> str | None:
        """The room kind ``piece`` stands in as far as the frames tell (`room_of_piece`)."""
        told = state.rooms.get(piece.id)
        if state.floors is None:
            return told
        return room_of_piece(told, state.floors, piece.centroid[:2], self.config.approach.room_floor_m)

    def _untried_part(self, state: LookInsideState, piece_id: int) -> Instance | None:
        """A door or drawer with a handle seen on it, not tried yet and not gone, of the piece or of
        a piece of its kind that the memory keeps apart from it within `SIBLING_M` and not seen in
        another room (one piece seen in fragments: a wardrobe's two doors on two carcasses)."""
        memory = state.memory
        piece = memory.get(piece_id)
        room = self._room_of(state, piece)
        pieces = [piece, *(other for other in memory.with_label(piece.label) if other.id != piece.id
                           and float(np.linalg.norm(other.centroid[:2] - piece.centroid[:2])) <= SIBLING_M
                           and self._room_of(state, other) in (None, room))]
        for child in (child for holder in pieces for child in holder.children):
            part = memory.get(child)
            handled = any(memory.get(c).label == "handle" for c in part.children)
            if part.label in PARTS and handled and part.id not in state.tried and not part.gone:
                return part
        return None

    def _open_and_look(self, state: LookInsideState, kind: str, first: Instance, routes: Routes | None,
                       stop: threading.Event) -> _Outcome:
        """In the worker thread: each door and drawer of ``first``'s piece in turn (``first`` first,
        then those seen since, up to ``max_parts``): open, look, close, stow. It stops at a part it
        could not shut or stow after, and once ``stop`` is set. Never raises: the records say why."""
        robot = Robot(self.link, RobotConfig(skill_timeout_s=self.config.skill_timeout_s, stand=self.config.stand,
                                             hold_open=True, see_table_edge=False),  # storage stands on the floor
                      memory=state.memory, routes=routes)
        robot.body.skill_listeners.append(state.arm)
        piece = first.parent if first.parent is not None else first.id
        records: list[ActRecord] = []
        views: list[Observation] = []
        before: Observation | None = None  # the piece as it stood, from the first stand reached
        part: Instance | None = first
        while part is not None:
            state.tried.add(part.id)
            part_views, record = self._open_one(state, robot, kind, part, piece, look_first=not records)
            records.append(record)
            before = before or robot.parts.before
            if part_views:
                views.append(_view_for_vlm(part_views))
            if (record.closed is False or record.stage in ("look", "stow") or len(records) >= self.config.max_parts
                    or stop.is_set()):
                break
            part = self._untried_part(state, piece)
        planner = robot.body.context.planner
        if planner is not None:  # names the joints of the runs kept for a recording
            state.arm.joint_names = tuple(planner.joint_names)
        missed = any(not record.looked for record in records) or self._untried_part(state, piece) is not None
        if views and missed and before is not None:
            # Some door or drawer was not looked behind: the piece as it stood shows it shut, so
            # that what the VLM sees is not taken for the whole piece open and empty.
            views.insert(0, before)
        return _Outcome(views, _head_frame(robot) if _moved(robot) else None, records)

    def _open_one(self, state: LookInsideState, robot: Robot, kind: str, part: Instance, piece: int,
                  look_first: bool) -> tuple[list[Observation], ActRecord]:
        """Open one part, look, close, stow (first a look from where the robot stands, for the
        first part of an act): the frames to show the VLM and the act's record."""
        began = time.monotonic()
        unit = "opening_deg" if part.label == "door" else "opening_m"
        centre = state.memory.get(piece).centroid[:2]
        record = ActRecord(kind, f"{part.label} {part.id}", [round(float(v), 2) for v in centre], unit)
        views: list[Observation] = []
        stage = "look"
        try:
            if look_first:
                robot.observe()
            stage = "open"
            opened = robot.parts.open_part(part)
            amount = robot.parts.opening(part)
            record.opened = opened.ok
            record.opening = round(math.degrees(amount) if unit == "opening_deg" else amount, 3)
            if not opened.ok:
                record.stage, record.reason = stage, opened.reason
            if amount >= self.config.min_look[part.label]:
                views = list(robot.parts.views)
            if amount > 0:
                stage = "close"
                closed = robot.parts.close_part(part)
                record.closed = closed.ok
                if not closed.ok:
                    record.fail(stage, closed.reason)
            stage = "stow"
            robot.stow()
        except (GeometryError, SkillPlanError, QueryFailed, ValueError) as error:
            record.fail(stage, str(error))
        except Exception as error:  # a bug in the arm's code fails this act, not the whole episode
            log.exception("looking inside the %s raised", kind)
            record.fail(stage, f"{type(error).__name__}: {error}")
        record.looked = bool(views)
        record.outcome = _outcome_text(kind, part.label, record)
        record.seconds = round(time.monotonic() - began, 1)
        return views, record


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


def _outcome_text(kind: str, label: str, record: ActRecord) -> str:
    """One line for the feedback message and the record."""
    if record.looked:
        text = f"opened the {kind}'s {label}, looked inside"
        if record.stage == "open":
            text += f" (it opened only part of the way: {record.reason})"
    else:
        text = f"could not open the {kind}'s {label}: {record.reason}"
    if record.closed is False:
        text += "; could not close it" + (f": {record.reason}" if record.stage == "close" else "")
    elif record.stage == "stow":
        text += f"; {record.reason}"
    return text
