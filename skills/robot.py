"""The robot as Algorithm 1 sees it: a `Perception` and a `SkillExecutor` over the world link.

Perception is the head camera, seen from where the robot started (the whole table in view), and
the wrist camera looking into whatever a skill has just opened; both frames are fused in one
`InstanceMemory`, whose instances become the explorer's detections (`memory_detections`). The
memory's ids are the ACSG's: the simulator's segmentation ids are never used to act.

Each primitive's ports are bound from what the memory holds, the skill is made by its registered
name through the `SkillRegistry` (so an installed package may replace none of them silently: a
name declared twice is an error) and runs as a py_trees behaviour (`skills.running.run_to_end`)
while this object waits. `Robot` composes three parts:

- `skills.robot_body.RobotBody`: running a skill by name, head and wrist frames, driving the
  base, the tables and counters remembered; every skill run is kept in its ``skill_times``;
- `skills.robot_parts.DoorsAndDrawers`: opening and closing doors and drawers, and what stands
  open;
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
#: near the first row the head camera sees the top must come for the scan to be needed.
EDGE_STANDOFF_M, EDGE_STEP_M, EDGE_REACH_M, EDGE_SEEN_M = 0.4, 0.6, 0.7, 0.05


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
    ``scan_table_edge``: at the first look, the wrist camera also looks along the near edge of the
    table the robot stands at (`Robot.scan_table_edge`), below the head camera's view."""

    skill_timeout_s: float = 120.0
    scan_table_edge: bool = True
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
        self.picks = Picks(self.body, config.idle_toward_robot_m, self.parts.drive)

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
        """Back to the start pose, one head frame into the memory. The first call looks from where
        the robot stands, makes that its ``home`` and, with ``scan_table_edge``, looks along the
        table's near edge with the wrist camera.

        Returns:
            The memory's detections.

        Raises:
            QueryFailed: the world sent no frame.
        """
        body = self.body
        first = body.home is None
        if not first:
            try:
                self.return_home()
            except SkillPlanError as error:  # look from where it stands rather than not at all
                log.info("observe: looking from where the robot stands: %s", error)
        head = body.frame("head")
        if first:
            body.home = body.pose
        body.memory.integrate(head)
        if first and self.config.scan_table_edge:
            self.scan_table_edge(head)
        return memory_detections(self.memory, body.eye, vacated=self.picks.vacated)

    def scan_table_edge(self, head: Observation) -> None:
        """Wrist-camera looks, straight down, into the strip of the table before the robot that the
        head frame does not show: its lowest ray meets a table top about half a metre out, and a
        cup standing nearer than that is never seen, nor explored. Only where the table's top seen
        runs into that strip; the looks go across its width as far as the arm reaches
        (`EDGE_REACH_M`), midway between the robot's body and the first row seen; a view that
        cannot be reached is skipped, and the arm is folded away afterwards.

        Args:
            head: the head frame just taken from where the robot stands.
        """
        body = self.body
        assert body.pose is not None
        base, yaw = np.asarray(body.pose[:2]), body.pose[2]
        ahead, side = np.array([math.cos(yaw), math.sin(yaw)]), np.array([-math.sin(yaw), math.cos(yaw)])
        surfaces = body.surfaces()
        if not surfaces:
            return
        surface = min(surfaces, key=lambda inst: float(np.min(np.linalg.norm(inst.points()[:, :2] - base, axis=1))))
        top = surface_top(surface)
        points = surface.points()
        flat = points[points[:, 2] >= top - 0.015, :2] - base
        forward, across = flat @ ahead, flat @ side
        first_row = nearest_seen_ahead(head.intrinsics, head.camera_to_world, top, base, ahead)
        body.head_sees_from = first_row
        if float(forward.min()) > first_row + EDGE_SEEN_M:
            return  # the table's edge is in view
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

    def return_home(self) -> None:
        """Drive back to where the robot first looked (nothing before the first `observe`).

        Raises:
            SkillPlanError: the base did not get there.
        """
        if self.body.home is not None:
            self.parts.drive(self.body.home)

    def stow(self) -> None:
        """Fold the arm into the base, as it must be for the base to drive on freely.

        Raises:
            SkillPlanError: the arm could not be folded.
        """
        result = self.body.run(STOW)
        if not result.ok:
            raise SkillPlanError(result.reason)
