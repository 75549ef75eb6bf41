"""The robot as Algorithm 1 sees it: a `Perception` and a `SkillExecutor` over the world link.

Perception is the head camera, seen from where the robot started (the whole table in view), and
the wrist camera looking into whatever a skill has just opened; both frames are fused in one
`InstanceMemory`, whose instances become the explorer's detections (`memory_detections`). The
memory's ids are the ACSG's: the simulator's segmentation ids are never used to act.

Each primitive's ports are bound from what the memory holds, the skill is made by its registered
name through the `SkillRegistry` (so an installed package may replace none of them silently: a
name declared twice is an error) and runs as a py_trees behaviour (`skills.running.run_to_end`)
while this object waits:

- open a door or drawer: the part's geometry from its handle (`handle_geometry`), the base slid to
  the part's `stand_pose` (at a table, where it already stands within reach) or, with a
  `StandConfig`, driven to a stand clear of what the opening sweeps (`skills.arm.stand.choose_stand`:
  storage standing in a room), along ``routes`` over the robot's map when it has them; a second
  look from there to refine the geometry (and, with a `StandConfig`, a second stand when the
  refined geometry cannot be opened from the first), the skill; then the wrist camera into the
  opening and the arm stowed again; or, with ``hold_open``, a door kept in hand, pulled open, and
  a head-camera look while it is held;
- close it: the geometry and opening remembered from the open, from the same stand, grasping the
  handle anew, or pushing it shut from the grasp it is held by; a close that fails while the part
  still stands open is tried once more, from a fresh look at how far it stands open (a door let go
  may swing on, or be held back by something, and a grasp aimed where it was misses);
- pick away: a free spot on the surface it stands on (`idle_spot`, towards the robot, out of what
  the doors and drawers sweep as they open and of the lanes to their handles:
  `agent.acsg.keep_clear`), the base slid along the table's edge (the robot faces the table along
  +y, as the tabletop scenes start it) to where the arm reaches both the object and the spot
  (`PLACE_REACH_M`), level with the object where it can; pick back: from where it was put down to
  where it was.

What a skill moved, the memory is told (`InstanceMemory.move`): a drawer pulled out, a door swung,
a cup put down elsewhere keep their identity, so the graph gains what was revealed and nothing
else. The box a thing filled before it was picked away is kept while it is away: what is found
there lay inside it (the Matryoshka's smaller doll). Every skill run is kept in
`skill_times`: its name, outcome and timings.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from agent.acsg.from_memory import Box, memory_detections
from agent.acsg.interfaces import Detection, SkillCall, SkillResult
from agent.acsg.keep_clear import kept_clear
from worlds.bus.rpc import QueryFailed
from agent.mapping.camera import nearest_seen_ahead
from agent.observation import Observation
from agent.perception.directions import GeometryError
from agent.perception.frames import detect, frame_labels
from agent.perception.grasp_poses import top_grasp_point
from agent.perception.instances import Instance
from agent.perception.memory import InstanceMemory
from agent.perception.opening import opening_seen
from agent.perception.part_geometry import PartGeometry, handle_geometry
from agent.perception.part_motion import part_motion
from agent.perception.voxels import centres
from agent.planning.route import Routes
from worlds.bus.link import WorldLink
from skills.base import SkillResult as ArmResult
from skills.context import SkillContext
from skills.registry import SkillRegistry
from skills.replies import arm_state
from skills.running import run_to_end
from skills.arm.idle_space import idle_spot, reach_along
from skills.arm.planner import ArmPlanner
from skills.arm.skill_plan import SkillPlanError
from skills.arm.stand import NoStandError, StandConfig, choose_stand, stand_pose

log = logging.getLogger(__name__)

SURFACE_LABELS = ("table", "counter")
#: The skills the robot runs besides the exploration primitives, by their registered names.
LOOK, STOW = "move_camera", "stow"
#: The part seen nearest to where a skill says it left it, within this, is that part: a part held
#: back (by the end of its travel, by something in its way) lags the hand by up to ~15 cm.
SEEN_PART_M = 0.25
#: ... and its points, carried by the opening found, lie within this (median) of the view: a
#: neighbouring drawer's handle, seen where the opened one's hides behind the arm, fits no opening.
SEEN_FIT_M = 0.03
#: The table-edge scan (`Robot.scan_table_edge`): the wrist camera's height over the top, how far
#: apart its views are across the table, how far to either side of the base they go (m), and how
#: near the first row the head camera sees the top must come for the scan to be needed.
EDGE_STANDOFF_M, EDGE_STEP_M, EDGE_REACH_M, EDGE_SEEN_M = 0.4, 0.6, 0.7, 0.05
#: How far from the base's axis (m) a thing is picked and put down: the arm reaches a table's top
#: from above up to ~0.85 m out, and a carry planned further fails at planning. The base slides
#: along the table's edge to a stand from which both lie within this.
PLACE_REACH_M = 0.8
#: A hand folding in from where it is may swing this far (m) out and down on the way.
FOLD_REACH_M = 0.3


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


@dataclass(frozen=True)
class _Opened:
    geometry: PartGeometry  # as seen closed
    amount: float  # how far it stands open
    stand: tuple[float, float, float]
    look_point: np.ndarray
    held: bool = False  # the hand still holds its handle


@dataclass(frozen=True)
class _Away:
    grasp_point: np.ndarray  # its top grasp point where it stood
    placed_point: np.ndarray  # where that point was put down
    extent: np.ndarray
    stand_x: float


@dataclass
class Robot:
    """`Perception` and `SkillExecutor` of the robot behind ``link``; see the module docstring.
    ``routes``: the paths over the robot's map from where it stands when it first looks; without
    them the base drives straight."""

    link: WorldLink
    config: RobotConfig = field(default_factory=RobotConfig)
    memory: InstanceMemory = field(default_factory=InstanceMemory)
    routes: Routes | None = None
    skills: SkillRegistry = field(default_factory=SkillRegistry)

    def __post_init__(self) -> None:
        self.home: tuple[float, float, float] | None = None
        self.pose: tuple[float, float, float] | None = None  # where the base is, as the world last said
        self.context = SkillContext(self.link)
        self.opened: dict[int, _Opened] = {}
        self.away: dict[int, _Away] = {}
        self.vacated: dict[int, Box] = {}
        self.skill_times: list[dict[str, Any]] = []  # per skill run: name, ok, planning, execution, wall time
        self.notes: list[str] = []
        self.views: list[Observation] = []  # frames taken inside the last part opened
        self.before: Observation | None = None  # the head frame from the stand, before it was opened
        self._eye = np.zeros(3)
        self._head_sees_from = 0.0  # how far ahead of the start pose the head camera sees the table's top

    # ---- Perception ---------------------------------------------------------------------------
    def observe(self) -> list[Detection]:
        """Back to the start pose, one head frame into the memory; the memory's detections."""
        first = self.home is None
        if not first:
            try:
                self.return_home()
            except SkillPlanError as error:  # look from where it stands rather than not at all
                self.notes.append(f"observe: {error}")
        head = self._look("head")
        if first and self.config.scan_table_edge:
            self.scan_table_edge(head)
        return memory_detections(self.memory, self._eye, vacated=self.vacated)

    def scan_table_edge(self, head: Observation) -> None:
        """Wrist-camera looks, straight down, into the strip of the table before the robot that the
        head frame ``head`` does not show: its lowest ray meets a table top about half a metre out,
        and a cup standing nearer than that is never seen, nor explored. Only where the table's top
        seen runs into that strip; the looks go across its width as far as the arm reaches
        (`EDGE_REACH_M`), midway between the robot's body and the first row seen; a view that
        cannot be reached is skipped, and the arm is folded away afterwards."""
        assert self.pose is not None
        base, yaw = np.asarray(self.pose[:2]), self.pose[2]
        ahead, side = np.array([math.cos(yaw), math.sin(yaw)]), np.array([-math.sin(yaw), math.cos(yaw)])
        surfaces = self._surfaces()
        if not surfaces:
            return
        surface = min(surfaces, key=lambda inst: float(np.min(np.linalg.norm(inst.points()[:, :2] - base, axis=1))))
        top = _top(surface)
        points = surface.points()
        flat = points[points[:, 2] >= top - 0.015, :2] - base
        forward, across = flat @ ahead, flat @ side
        first_row = nearest_seen_ahead(head.intrinsics, head.camera_to_world, top, base, ahead)
        self._head_sees_from = first_row
        if float(forward.min()) > first_row + EDGE_SEEN_M:
            return  # the table's edge is in view
        out = (self.planner().body_radius + first_row) / 2
        lo, hi = max(float(across.min()), -EDGE_REACH_M), min(float(across.max()), EDGE_REACH_M)
        count = max(1, math.ceil((hi - lo) / EDGE_STEP_M))
        width = (hi - lo) / count
        looked = False
        for offset in np.linspace(lo + width / 2, hi - width / 2, count):
            point = np.array([*(base + out * ahead + offset * side), top])
            if self._skill(LOOK, look_point=point, standoff_m=EDGE_STANDOFF_M, pitch_deg=90.0, surface_z=top).ok:
                self._look("wrist")
                looked = True
        if looked:
            self._skill(STOW, surface_z=top)

    # ---- SkillExecutor ------------------------------------------------------------------------
    def execute(self, call: SkillCall) -> SkillResult:
        """Run one exploration primitive on the remembered instance ``call.instance``."""
        handlers = {"open_door": self._open_call, "open_drawer": self._open_call, "close_door": self._close_call,
                    "close_drawer": self._close_call, "pick_away": self._pick_away, "pick_back": self._pick_back}
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

    # ---- doors and drawers --------------------------------------------------------------------
    def _open_call(self, call: SkillCall, part: Instance) -> SkillResult:
        return self.open_part(part, self._handle(call, part))

    def _close_call(self, call: SkillCall, part: Instance) -> SkillResult:
        return self.close_part(part)

    def open_part(self, part: Instance, handle: int | None = None) -> SkillResult:
        """Stand before the door or drawer ``part``, open it by ``handle`` (its first seen handle by
        default), look inside; the frames taken while it stood open are in `views`. With
        ``hold_open`` (see `RobotConfig`) the hand may still hold the handle afterwards, until
        `close_part`."""
        if self.home is None:
            raise SkillPlanError("the robot has not looked yet")
        if handle is None:
            handle = self._handle(None, part)
        self.views, self.before = [], None
        geometry = handle_geometry(self.memory, handle, self._eye, kind=part.label)
        stand, amount = self._stand_for(geometry, self.routes)
        self._drive(stand, self.routes)
        self.before = self._look("head")
        geometry = handle_geometry(self.memory, handle, self._eye, kind=part.label)
        closed_centre = part.centroid
        hold = self.config.hold_open and geometry.kind not in self.config.look_inside
        result = self._open_from_here(part, geometry, amount, hold)
        if result.achieved is None and self.config.stand is not None:
            # Seen from near, the handle is not quite where it seemed from afar: stand again for it.
            try:
                restand, amount = self._stand_for(geometry, None)
            except SkillPlanError as error:
                return SkillResult(False, f"{result.reason}; and then {error}")
            if math.dist(restand[:2], stand[:2]) > 0.02 or abs(restand[2] - stand[2]) > 0.02:
                stand = restand
                self._drive(stand)
                self._look("head")
                geometry = handle_geometry(self.memory, handle, self._eye, kind=part.label)
                result = self._open_from_here(part, geometry, amount, hold)
        if result.achieved is None:
            return SkillResult(False, result.reason)
        if result.ok and hold:  # the hand on the handle says how far the part stands open
            self.memory.move(part.id, part_motion(geometry, result.achieved))
            self.views.append(self._look("head"))
            self.opened[part.id] = _Opened(geometry, result.achieved, stand, closed_centre, held=True)
            return SkillResult(True)
        amount = self._seen_opening(geometry, part, handle, result.achieved)
        if not result.ok:
            self.opened[part.id] = _Opened(geometry, amount, stand, closed_centre)
            return SkillResult(False, result.reason)
        look = self._look_point(geometry, part, amount, closed_centre)
        self.opened[part.id] = _Opened(geometry, amount, stand, look)
        if geometry.kind in self.config.look_inside:
            self._look_into(look)
        return SkillResult(True)

    def _stand_for(self, geometry: PartGeometry,
                   routes: Routes | None) -> tuple[tuple[float, float, float], float | None]:
        """Where to stand to open ``geometry`` and how far to open it (None: the skill's default)."""
        assert self.home is not None
        if self.config.stand is None:
            return stand_pose(geometry, self.home), None
        q = np.asarray(self.link.call("arm_state", {}).meta["positions"], dtype=float)
        surface_z = self._surface_z(geometry.handle_point)
        try:
            stand = choose_stand(self.planner(), q, geometry, reachable=None if routes is None else routes.reaches,
                                 surface_z=surface_z, config=self.config.stand)
        except NoStandError as error:
            if routes is None or not error.refused["unreachable"]:
                raise
            # None of the good places is known to be reachable (the floor by the storage unseen,
            # say): try those the map does not know to be blocked, to be driven to straight.
            try:
                stand = choose_stand(self.planner(), q, geometry, surface_z=surface_z, config=self.config.stand,
                                     reachable=lambda xy: routes.unblocked(xy) and not routes.reaches(xy))
            except NoStandError as again:
                raise SkillPlanError(f"{error}; nor off the map's known floor ({again.why})") from None
        log.info("stand for the %s at (%.2f, %.2f): %s, opening %.2f, clear by %.2f m", geometry.kind,
                 *geometry.handle_point[:2], np.round(stand.pose, 2).tolist(), stand.amount, stand.clearance_m)
        return stand.pose, stand.amount

    def _open_from_here(self, part: Instance, geometry: PartGeometry, amount: float | None,
                        hold: bool) -> ArmResult:
        return self._skill(f"open_{geometry.kind}", geometry=geometry, amount=amount,
                           surface_z=self._surface_z(geometry.handle_point), label=f"{part.label} {part.id}", hold=hold)

    def planner(self) -> ArmPlanner:
        """The arm's planner, from the robot's description (asked for once, shared with the skills)."""
        if self.context.planner is None:
            self.context.planner = ArmPlanner.from_description(self.link.describe().wait().meta)
        return self.context.planner

    def _seen_opening(self, geometry: PartGeometry, part: Instance, handle: int, reported: float,
                      moved: float = 0.0) -> float:
        """How far the part stands open by a head-camera look: `opening_seen` of the handle's
        remembered points among the handles seen near where the skill says it left it (else of the
        part's own points among the parts seen there), searching up to a quarter beyond the skill's
        figure; that figure when neither is seen. ``moved``: how far open the memory holds the part now (its
        points are carried back to closed first). The memory is told the part moved to the opening
        found, then given the frame."""
        observation = self._frame("head")
        cfg = self.memory.config
        detections = detect(observation.depth, observation.segmentation, frame_labels(observation.labels),
                            observation.intrinsics, observation.camera_to_world, cfg.voxel_m, cfg.min_pixels,
                            cfg.max_depth_m)
        back = np.linalg.inv(part_motion(geometry, moved))
        amount = reported
        for inst in (self.memory.get(handle), part):
            closed = inst.points()
            if len(closed) < 3:
                continue
            closed = closed @ back[:3, :3].T + back[:3, 3]
            views = [centres(d.keys, cfg.voxel_m) for d in detections if d.label == inst.label]
            seen = opening_seen(geometry, closed, views, reported, SEEN_PART_M, SEEN_FIT_M)
            if seen is not None:
                amount = seen
                break
        if abs(amount - moved) > 0:
            self.memory.move(part.id, part_motion(geometry, amount) @ back)
        self.memory.integrate(observation)
        self.views.append(observation)
        return amount

    def close_part(self, part: Instance) -> SkillResult:
        """Close a door or drawer this robot opened, from where it stood to open it; once more, from
        a fresh look at how far it stands open, when that fails with the part still open."""
        result = self._close_once(part)
        opened = self._remembered(self.opened, part)
        if result.ok or opened is None or opened.amount <= 0:
            return result
        handles = [c for c in part.children if self.memory.get(c).label == "handle"]
        if handles:
            seen = self._seen_opening(opened.geometry, part, handles[0], opened.amount, moved=opened.amount)
            self.opened[part.id] = _Opened(opened.geometry, seen, opened.stand, opened.look_point)
        return self._close_once(part)

    def _close_once(self, part: Instance) -> SkillResult:
        opened = self._remembered(self.opened, part)
        if opened is None:
            return SkillResult(False, f"{part.label} {part.id} was not opened by this robot")
        if opened.amount <= 0:
            del self.opened[part.id]
            return SkillResult(True)
        if not opened.held:
            self._drive(opened.stand)
        result = self._skill(f"close_{opened.geometry.kind}", geometry=opened.geometry, amount=opened.amount,
                             surface_z=self._surface_z(opened.geometry.handle_point), label=f"{part.label} {part.id}",
                             held=opened.held)
        left = opened.amount if result.achieved is None else result.achieved
        motion = part_motion(opened.geometry, left) @ np.linalg.inv(part_motion(opened.geometry, opened.amount))
        self.memory.move(part.id, motion)
        if not result.ok:
            if result.held is not None:  # refused at planning with the hand still on the handle
                self.link.call("gripper", {"action": "open"})
            self.opened[part.id] = _Opened(opened.geometry, left, opened.stand, opened.look_point)
            return SkillResult(False, result.reason)
        del self.opened[part.id]
        return SkillResult(True)

    def opening(self, part: Instance) -> float:
        """How far this robot last saw ``part`` stand open (m or rad; 0 when it is not open by its doing)."""
        opened = self._remembered(self.opened, part)
        return 0.0 if opened is None else opened.amount

    def stow(self) -> None:
        """Fold the arm into the base, as it must be for the base to drive on freely."""
        result = self._skill(STOW)
        if not result.ok:
            raise SkillPlanError(result.reason)

    def _handle(self, call: SkillCall | None, part: Instance) -> int:
        named = None if call is None else call.params.get("handle")
        if isinstance(named, str) and named.startswith("o") and named[1:].isdigit():
            return self.memory.get(int(named[1:])).id
        handles = [c for c in part.children if self.memory.get(c).label == "handle"]
        if not handles:
            raise GeometryError(f"{part.label} {part.id} has no handle the robot has seen")
        return handles[0]

    def _look_point(self, geometry: PartGeometry, part: Instance, amount: float, closed_centre: np.ndarray
                    ) -> np.ndarray:
        """Where the wrist camera looks after opening: into a drawer's tray, or behind a door."""
        piece = self.memory.get(part.parent) if part.parent is not None else part
        lo, hi = piece.bounds
        depth = float(abs(np.asarray(geometry.normal) @ (hi - lo)))
        depth = min(max(depth, 0.15), 0.4)
        if geometry.kind == "drawer":
            return geometry.handle_point + (amount - depth / 2) * geometry.normal - np.array([0.0, 0.0, 0.03])
        return closed_centre - (depth / 2) * geometry.normal

    def _look_into(self, point: np.ndarray) -> None:
        """The wrist camera at ``point``, its frame into the memory, the arm folded away again. A
        view that cannot be reached is skipped: the head camera saw what it could."""
        surface_z = self._surface_z(point)
        looked = self._skill(LOOK, look_point=point, surface_z=surface_z)
        if looked.ok:
            self.views.append(self._look("wrist"))
        self._skill(STOW, surface_z=surface_z)

    # ---- picks ----------------------------------------------------------------------------------
    def _pick_away(self, call: SkillCall, obj: Instance) -> SkillResult:
        if self.home is None:
            raise SkillPlanError("the robot has not looked yet")
        points = obj.points()
        top, extent, box = top_grasp_point(points), np.ptp(points, axis=0), obj.bounds
        surface = self._surface(np.array([top[0], top[1], box[0][2] + 0.01]))  # under its bottom
        if surface is None:
            raise SkillPlanError("no table or counter in memory to put the object down on")
        others = [inst.points() for inst in self.memory.live() if inst.id != surface.id]
        toward = np.asarray(self.home[:2]) - top[:2]
        near = top[:2] + self.config.idle_toward_robot_m * toward / max(float(np.linalg.norm(toward)), 1e-6)
        edge_y = self.home[1]
        (grasp_lo,), (grasp_hi,) = reach_along(top[:2], edge_y, PLACE_REACH_M)
        if grasp_lo > grasp_hi:  # further out than that: from level with it, straight ahead, if at all
            grasp_lo = grasp_hi = float(top[0])

        def reachable(places: np.ndarray) -> np.ndarray:
            lo, hi = reach_along(places, edge_y, PLACE_REACH_M)
            return np.maximum(lo, grasp_lo) <= np.minimum(hi, grasp_hi)

        def in_view(places: np.ndarray) -> np.ndarray:
            return reachable(places) & (places[:, 1] - edge_y >= self._head_sees_from)

        obstacles, radius = [*others, *kept_clear(self.memory, self._eye, self.home[:2])], float(max(extent[:2])) / 2
        try:  # where the head camera sees it, so the memory follows it; else before the robot
            spot = idle_spot(surface.points(), obstacles, radius, near, allowed=in_view,
                             allowed_means="within the arm's reach and the head camera's view")
        except SkillPlanError:
            spot = idle_spot(surface.points(), obstacles, radius, near, allowed=reachable,
                             allowed_means="within the arm's reach")
        (place_lo,), (place_hi,) = reach_along(spot[:2], edge_y, PLACE_REACH_M)
        stand_x = float(np.clip(top[0], max(grasp_lo, place_lo), min(grasp_hi, place_hi)))
        self._drive((stand_x, edge_y, self.home[2]))
        place = np.array([spot[0], spot[1], spot[2] + top[2] - box[0][2]])
        result = self._skill(call.primitive, object_point=top, object_extent=extent, place_point=place,
                             surface_z=float(spot[2]), label=f"{obj.label} {obj.id}")
        if not result.ok:
            return SkillResult(False, result.reason)
        self.memory.move(obj.id, _translation(place - top))
        self.away[obj.id] = _Away(top, place, extent, stand_x)
        self.vacated[obj.id] = box
        return SkillResult(True)

    def _pick_back(self, call: SkillCall, obj: Instance) -> SkillResult:
        away = self._remembered(self.away, obj)
        if away is None:
            return SkillResult(False, f"{obj.label} {obj.id} was not picked away by this robot")
        assert self.home is not None  # set by the look before the pick away
        self._drive((away.stand_x, self.home[1], self.home[2]))
        points = obj.points()
        now = top_grasp_point(points) if len(points) else away.placed_point
        result = self._skill(call.primitive, object_point=now, object_extent=away.extent, place_point=away.grasp_point,
                             surface_z=self._surface_z(away.grasp_point - np.array([0.0, 0.0, away.extent[2] - 0.01])),
                             label=f"{obj.label} {obj.id}")
        if not result.ok:
            return SkillResult(False, result.reason)
        self.memory.move(obj.id, _translation(away.grasp_point - now))
        del self.away[obj.id]
        self._remembered(self.vacated, obj)
        self.vacated.pop(obj.id, None)
        return SkillResult(True)

    def _remembered(self, records: dict[int, Any], inst: Instance) -> Any:
        """What ``records`` holds for ``inst``, under its id or an id the memory has since merged into
        it (the drawer seen open is the drawer that was closed); re-keyed to its id."""
        for key in list(records):
            if key != inst.id and self.memory.get(key).id == inst.id:
                records[inst.id] = records.pop(key)
        return records.get(inst.id)

    def return_home(self) -> None:
        """Drive back to where the robot first looked."""
        if self.home is not None:
            self._drive(self.home)

    # ---- the body -------------------------------------------------------------------------------
    def _skill(self, name: str, **bindings: Any) -> ArmResult:
        """Make the skill registered as ``name`` with ``bindings`` for its ports and run it to its
        end; on a failure after the arm moved, fold it away."""
        began = time.perf_counter()
        skill = self.skills.create(name, self.context, bindings)
        result = run_to_end(skill, timeout_s=self.config.skill_timeout_s)
        self.skill_times.append({"skill": name, "ok": result.ok, "planning_ms": round(result.planning_ms, 2),
                                 "execution_s": round(result.execution_s, 3),
                                 "wall_s": round(time.perf_counter() - began, 3),
                                 **({} if result.ok else {"reason": result.reason})})
        if not result.ok and name != STOW and (result.steps_done or result.execution_s > 0):
            self._skill(STOW, surface_z=bindings.get("surface_z"))  # out of the way
        return result

    def _look(self, camera: str) -> Observation:
        observation = self._frame(camera)
        self.memory.integrate(observation)
        return observation

    def _frame(self, camera: str) -> Observation:
        observation = Observation.from_message(self.link.call("observe", {"camera": camera}))
        self.pose = tuple(float(v) for v in observation.base_pose)  # type: ignore[assignment]
        if camera == "head":
            self._eye = observation.camera_to_world[:3, 3].copy()
            if self.home is None:
                self.home = self.pose
        return observation

    def _drive(self, pose: tuple[float, float, float], routes: Routes | None = None) -> None:
        """Drive to ``pose``: along ``routes`` when they lead there from where the base is, else straight.
        The arm is left where the last skill left it (backed off ahead of the base), which the
        world checks on the way; when it touches something, it is folded in and the base drives
        on from where it stopped, unless a door this robot opened still stands open: a door swings
        out towards the robot, and the folding arm would sweep through it (the drive fails then,
        as it would have). Folding it first every time would do the same."""
        reply = self._move_base(pose, routes)
        if not reply.get("reached") and not any(opened.geometry.kind == "door" for opened in self.opened.values()):
            arm = arm_state(self.link.call("arm_state", {}).meta)
            if not arm["stowed"]:
                self._skill(STOW, surface_z=self._surface_z(arm["tcp_pose"][:3, 3], FOLD_REACH_M))
                reply = self._move_base(pose, routes)
        if not reply.get("reached"):
            touched = (reply.get("contact") or {}).get("category", "something")
            raise SkillPlanError(f"the base could not reach ({pose[0]:.2f}, {pose[1]:.2f}, "
                                 f"{math.degrees(pose[2]):.0f}°): it touched {touched}")

    def _move_base(self, pose: tuple[float, float, float], routes: Routes | None) -> dict[str, Any]:
        """One move_base command towards ``pose`` (see `_drive`); the world's reply."""
        path = [[pose[0], pose[1]]]
        here = self.pose
        if routes is not None and here is not None and math.dist(here[:2], routes.start_xy) < 0.05 \
                and routes.reaches(np.array(pose[:2])):
            path = np.round(routes.to(np.array(pose[:2]))[1:], 3).tolist()
        reply: dict[str, Any] = self.link.call("move_base", {"path": path, "yaw": pose[2]}).meta
        if isinstance(reply.get("base_pose"), list):
            self.pose = tuple(float(v) for v in reply["base_pose"])  # type: ignore[assignment]
        return reply

    def _surfaces(self) -> list[Instance]:
        """Every remembered table and counter."""
        return [inst for label in SURFACE_LABELS for inst in self.memory.with_label(label)]

    def _surface(self, under: np.ndarray, reach_m: float = 0.0) -> Instance | None:
        """The highest table or counter below the point ``under`` (its top lower) whose footprint
        comes within ``reach_m`` of it: by default the one under it, what the hand must keep above
        there; with `FOLD_REACH_M`, what a hand folding in from there may swing down onto, though it
        is not over it now. None on the floor (a cabinet standing in a room)."""
        found = []
        for inst in self._surfaces():
            lo, hi = inst.bounds
            gap = np.maximum(np.maximum(lo[:2] - under[:2], under[:2] - hi[:2]), 0.0)
            top = _top(inst)
            if float(np.linalg.norm(gap)) <= reach_m and top < under[2]:
                found.append((top, inst))
        return max(found, key=lambda pair: pair[0], default=(None, None))[1]

    def _surface_z(self, under: np.ndarray, reach_m: float = 0.0) -> float | None:
        surface = self._surface(under, reach_m)
        return None if surface is None else _top(surface)


def _top(surface: Instance) -> float:
    return float(np.percentile(surface.points()[:, 2], 99))


def _translation(offset: np.ndarray) -> np.ndarray:
    motion = np.eye(4)
    motion[:3, 3] = offset
    return motion
