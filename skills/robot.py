"""The robot as Algorithm 1 sees it: a `Perception` and a `SkillExecutor` over the world link.

Perception is the head camera, looking from where the robot started or, where the table's near
edge is out of its view from there, from a little further back (``lookout``: the whole table in
view), and the wrist camera looking into whatever a skill has just opened; both frames are fused in one
`InstanceMemory`, whose instances become the explorer's detections (`memory_detections`). The
memory's ids are the ACSG's: the simulator's segmentation ids are never used to act.

Each primitive's ports are bound from what the memory holds, the skill is made by its registered
name through the `SkillRegistry` (so an installed package may replace none of them silently: a
name declared twice is an error) and runs as a py_trees behaviour (`skills.running.run_to_end`)
while this object waits. `Robot` composes three parts:

- `skills.robot_body.RobotBody`: running a skill by name, head and wrist frames, driving the
  base, the tables and counters remembered; every skill run is kept in its ``skill_times``;
- `skills.robot_parts.DoorsAndDrawers`: opening and closing doors and drawers, what stands
  open and what was shut again;
- `skills.robot_picks.Picks`: picking things away out of the way and back.

The first `Robot.observe` sets where the robot started (``home``); opening a part or picking a
thing before it raises. What a skill moved, the memory is told (`InstanceMemory.move`): a drawer
pulled out, a door swung, a cup put down elsewhere keep their identity, so the graph gains what
was revealed and nothing else.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from agent.acsg.from_memory import memory_detections
from agent.acsg.interfaces import Detection, SkillCall, SkillResult
from agent.mapping.camera import nearest_seen_ahead
from agent.observation import Observation
from agent.perception.directions import GeometryError
from agent.perception.instances import Instance
from agent.perception.memory import InstanceMemory
from agent.planning.route import Routes
from agent.pose import Pose2D
from skills.arm.skill_plan import SkillPlanError
from skills.arm.stand import StandConfig
from skills.registry import SkillRegistry
from skills.robot_body import LOOK, STOW, RobotBody, surface_top
from skills.robot_parts import DoorsAndDrawers
from skills.robot_picks import Picks
from worlds.bus.link import WorldLink
from worlds.bus.rpc import QueryFailed

log = logging.getLogger(__name__)

#: The table-edge scan (`Robot.scan_table_edge`): the wrist camera's height over the top, how far
#: apart its views are across the table, how far to either side of the base they go (m), and how
#: near the first row the head camera sees the top must come for the table's edge to count as
#: out of view (`Robot.see_table_edge`).
EDGE_STANDOFF_M, EDGE_STEP_M, EDGE_REACH_M, EDGE_SEEN_M = 0.4, 0.6, 0.7, 0.05
#: How far (m) from the robot's body the head camera's first row comes from the lookout.
LOOK_MARGIN_M = 0.05


@dataclass(frozen=True)
class RobotConfig:
    """``look_inside``: the kinds of part (door, drawer) to look into with the wrist camera once
    open; the head camera sees into the rest from the start pose. A drawer's tray is best seen from
    just above it; the way to a view behind an open door passes the door itself, which the arm
    would push shut again. ``idle_toward_robot_m``: how far from the object, towards the robot,
    the idle spot is sought first. ``stand``: where the base stands to open a part; None keeps
    the distance it has, slid along the front (at a table, where it already stands within reach),
    a `StandConfig` drives it to a stand clear of the opening (`skills.arm.stand`). ``hold_open``: the
    parts not looked into with the wrist camera are opened holding the handle, looked at with the
    head camera so, and pushed shut from the same grasp: let go, a door may swing on past where
    it was pulled, and a second grasp, aimed from a look at how far it stands open, may miss.
    ``see_table_edge``: at the first look, the robot makes sure the head camera sees the near edge
    of the table it stands at, backing away from it to look (`Robot.see_table_edge`)."""

    skill_timeout_s: float = 120.0
    see_table_edge: bool = True
    look_inside: tuple[str, ...] = ("drawer",)
    stand: StandConfig | None = None
    hold_open: bool = False
    idle_toward_robot_m: float = 0.2


@dataclass
class Robot:
    """`Perception` and `SkillExecutor` of the robot behind ``link``; see the module docstring.
    ``routes``: the paths over the robot's map from where it stands when it first looks; without
    them the base drives straight. ``body``, ``parts`` and ``picks`` are its three parts."""

    link: WorldLink
    config: RobotConfig = field(default_factory=RobotConfig)
    memory: InstanceMemory = field(default_factory=InstanceMemory)
    routes: Routes | None = None
    skills: SkillRegistry = field(default_factory=SkillRegistry)

    def __post_init__(self) -> None:
        config = self.config
        self.body = RobotBody(self.link, self.memory, self.skills, config.skill_timeout_s)
        self.parts = DoorsAndDrawers(self.body, self.routes, config.look_inside, config.stand, config.hold_open)
        self.picks = Picks(self.body, config.idle_toward_robot_m, self.parts)

    @property
    def home(self) -> Pose2D | None:
        """Where the robot first looked (set by the first `observe`), or None before it."""
        return self.body.home

    @property
    def pose(self) -> Pose2D | None:
        """Where the base is, as the world last said, or None before the first frame."""
        return self.body.pose

    @property
    def skill_times(self) -> list[dict[str, Any]]:
        """Per skill run, in order: its name, outcome, planning and execution time, wall time."""
        return self.body.skill_times

    # ---- Perception ---------------------------------------------------------------------------
    def observe(self) -> list[Detection]:
        """One head frame into the memory, from where the robot looks (`look_from_lookout`). The
        first call looks from where the robot stands and makes that its ``home``; with
        ``see_table_edge``, it then makes sure the table's near edge is seen (`see_table_edge`).

        Returns:
            The memory's detections.

        Raises:
            QueryFailed: the world sent no frame.
        """
        body = self.body
        if body.home is None:
            head = body.look("head")
            body.home = body.lookout = body.pose
            if self.config.see_table_edge:
                self.see_table_edge(head)
        else:
            self.look_from_lookout()
        return memory_detections(self.memory, body.eye, vacated=self.picks.vacated)

    def look_from_lookout(self) -> Observation:
        """Back to ``home``, straight back to the ``lookout`` when it lies behind it, one head frame
        into the memory, and straight forward to ``home`` again: every skill starts from ``home``
        or a stand along the table from it, and the way forward retraces the way back, with the arm
        as it was, past what stood there as it stood. A drive that fails leaves the robot to look
        from where it stands.

        Returns:
            The head frame.

        Raises:
            QueryFailed: the world sent no frame.
        """
        body = self.body
        assert body.home is not None and body.lookout is not None
        try:
            self.parts.drive(body.home)
            self.parts.drive(body.lookout)
        except SkillPlanError as error:  # look from where it stands rather than not at all
            log.info("observe: looking from where the robot stands: %s", error)
        head = body.look("head")
        if body.lookout != body.home:
            self._back_home()
        return head

    def _back_home(self) -> None:
        """Straight forward from the lookout to ``home``; a drive that fails is left for the next
        skill's own drive to its stand."""
        assert self.body.home is not None
        try:
            self.parts.drive(self.body.home)
        except SkillPlanError as error:
            log.info("the base did not get back before the table: %s", error)

    def see_table_edge(self, head: Observation) -> None:
        """Bring the strip of the table just before the robot into the head camera's view: its
        lowest ray meets a table top about half a metre out, and a cup standing nearer than that,
        or a box that a lifted shell leaves there, is never seen. Where the top seen runs into that
        strip, the base backs away from the table until the whole strip up to the robot's body is in
        view (to `LOOK_MARGIN_M` from it), looks, and comes back; every later head frame is taken
        from there (``lookout``, `look_from_lookout`). Where it cannot back away, the wrist camera
        looks along the strip instead (`scan_table_edge`).

        Args:
            head: the head frame just taken from where the robot stands.
        """
        body = self.body
        assert body.pose is not None
        surface = body.nearest_surface(body.pose)
        if surface is None:
            return
        base, ahead = np.asarray(body.pose[:2]), _ahead(body.pose)
        top = surface_top(surface)
        points = surface.points()
        flat = points[points[:, 2] >= top - 0.015, :2] - base
        first_row = nearest_seen_ahead(head.intrinsics, head.camera_to_world, top, base, ahead)
        body.head_sees_from = first_row
        if float(np.min(flat @ ahead)) > first_row + EDGE_SEEN_M:
            return  # the table's edge is in view
        # How far the top runs on into the strip is not seen: all of it up to the robot's body.
        back = first_row - body.planner().body_radius + LOOK_MARGIN_M
        lookout = Pose2D(*(base - back * ahead), body.pose[2])
        try:
            self.parts.drive(lookout)
        except SkillPlanError as error:
            log.info("the base cannot back away to see the table's edge (%s): the wrist camera looks", error)
            self.scan_table_edge(top, flat, first_row)
            return
        body.lookout = lookout
        body.look("head")
        self._back_home()

    def scan_table_edge(self, top: float, flat: np.ndarray, first_row: float) -> None:
        """Wrist-camera looks, straight down, into the strip of the table before the robot that the
        head frame does not show, for a robot that cannot back away from the table to see it: the
        looks go across the table's width as far as the arm reaches (`EDGE_REACH_M`), midway
        between the robot's body and the first row seen; a view that cannot be reached is skipped,
        and the arm is folded away afterwards.

        Args:
            top: the table's top (world z).
            flat: (N, 2) the top's points seen, relative to the base.
            first_row: how far ahead of the base the head camera's first row meets the top.
        """
        body = self.body
        assert body.pose is not None
        base, yaw = np.asarray(body.pose[:2]), body.pose[2]
        ahead, side = _ahead(body.pose), np.array([-math.sin(yaw), math.cos(yaw)])
        across = flat @ side
        out = (body.planner().body_radius + first_row) / 2
        lo, hi = max(float(across.min()), -EDGE_REACH_M), min(float(across.max()), EDGE_REACH_M)
        count = max(1, math.ceil((hi - lo) / EDGE_STEP_M))
        width = (hi - lo) / count
        looked = False
        for offset in np.linspace(lo + width / 2, hi - width / 2, count):
            point = np.array([*(base + out * ahead + offset * side), top])
            if body.run(LOOK, look_point=point, standoff_m=EDGE_STANDOFF_M, pitch_deg=90.0, surface_z=top).ok:
                body.look("wrist")
                looked = True
        if looked:
            body.run(STOW, surface_z=top)

    # ---- SkillExecutor ------------------------------------------------------------------------
    def execute(self, call: SkillCall) -> SkillResult:
        """Run one exploration primitive on the remembered instance ``call.instance``.

        Args:
            call: the primitive (open or close a door or drawer, pick away or back) and its target.

        Returns:
            Whether it went as planned, and why not: a primitive that could not be planned or run
            fails with the reason rather than raising.
        """
        handlers = {"open_door": self._open, "open_drawer": self._open, "close_door": self._close,
                    "close_drawer": self._close, "pick_away": self._pick_away, "pick_back": self._pick_back}
        handler = handlers.get(call.primitive)
        if handler is None:
            return SkillResult(False, f"{call.primitive}: not an exploration primitive ({', '.join(handlers)})")
        try:
            instance = self.memory.get(int(call.instance))  # type: ignore[arg-type]
        except (KeyError, TypeError, ValueError):
            return SkillResult(False, f"{call.primitive}: {call.target} is no instance the robot remembers")
        try:
            return handler(call, instance)
        except (GeometryError, SkillPlanError, QueryFailed, KeyError) as error:
            return SkillResult(False, f"{call.primitive} {instance.label} {instance.id}: {error}")

    def _open(self, call: SkillCall, part: Instance) -> SkillResult:
        return self.parts.open_part(part, self.parts.handle(call, part))

    def _close(self, call: SkillCall, part: Instance) -> SkillResult:
        return self.parts.close_part(part)

    def _pick_away(self, call: SkillCall, obj: Instance) -> SkillResult:
        return self.picks.pick_away(obj)

    def _pick_back(self, call: SkillCall, obj: Instance) -> SkillResult:
        return self.picks.pick_back(obj)

    def stow(self) -> None:
        """Fold the arm into the base, as it must be for the base to drive on freely.

        Raises:
            SkillPlanError: the arm could not be folded.
        """
        result = self.body.run(STOW)
        if not result.ok:
            raise SkillPlanError(result.reason)


def _ahead(pose: Pose2D) -> np.ndarray:
    """The unit vector the base faces."""
    return np.array([math.cos(pose[2]), math.sin(pose[2])])
