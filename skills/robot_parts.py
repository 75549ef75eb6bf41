"""Opening and closing doors and drawers with the robot's body, and what it keeps about each one
it opened.

- open: the part's geometry from its handle (`handle_geometry`), the base slid to the part's
  `stand_pose` (at a table, where it already stands within reach) or, with a `StandConfig`, driven
  to a stand clear of what the opening sweeps (`skills.arm.stand.choose_stand`: storage standing
  in a room), along ``routes`` over the robot's map when it has them; a second look from there to
  refine the geometry (and, with a `StandConfig`, a second stand when the refined geometry cannot
  be opened from the first), the skill; then the wrist camera into the opening and the arm stowed
  again; or, with ``hold_open``, a door kept in hand, pulled open, and a head-camera look while it
  is held; an open that fails with the part left ajar pushes it shut again (`AJAR`);
- close: the geometry and opening remembered from the open, from the same stand, grasping the
  handle anew, or pushing it shut from the grasp it is held by; a close that fails while the part
  still stands open is tried once more, from a fresh look at how far it stands open (a door let go
  may swing on, or be held back by something, and a grasp aimed where it was misses).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from agent.acsg.interfaces import SkillCall, SkillResult
from agent.perception.directions import GeometryError
from agent.perception.frames import detect, frame_labels
from agent.perception.instances import Instance
from agent.perception.opening import opening_seen
from agent.perception.part_geometry import PartGeometry, handle_geometry
from agent.perception.part_motion import part_motion
from agent.perception.voxels import centres
from agent.observation import Observation
from agent.planning.route import Routes
from agent.pose import Pose2D
from skills.arm.skill_plan import SkillPlanError
from skills.arm.stand import NoStandError, StandConfig, choose_stand, stand_pose
from skills.base import SkillResult as ArmResult
from skills.robot_body import LOOK, STOW, RobotBody

log = logging.getLogger(__name__)

#: The part seen nearest to where a skill says it left it, within this, is that part: a part held
#: back (by the end of its travel, by something in its way) lags the hand by up to ~15 cm.
SEEN_PART_M = 0.25
#: ... and its points, carried by the opening found, lie within this (median) of the view: a
#: neighbouring drawer's handle, seen where the opened one's hides behind the arm, fits no opening.
SEEN_FIT_M = 0.03
#: A part a failed open left standing open by more than this (m, rad) is pushed shut again.
AJAR = {"drawer": 0.005, "door": math.radians(2.0)}
#: How far short (m) of the stand a part was opened from the base coming back to close it may stop
#: on a touch: one drive step (`worlds.drive.MAX_STEP`, 5 cm) and a centimetre. A door swung open
#: against the base rests where the base stood.
COME_BACK_SHORT_M = 0.06
#: How far (m) beyond the box of the piece a part belongs to, and of the part, their points and what
#: stands in them may show in the memory: two voxels.
PIECE_MARGIN_M = 0.02


@dataclass(frozen=True)
class Opened:
    """A door or drawer this robot opened: its ``geometry`` as seen closed, how far it stands open
    (``amount``, m or rad), the ``stand`` it was opened from, where the wrist camera looks into it
    (``look_point``), and whether the hand still holds its handle (``held``)."""

    geometry: PartGeometry
    amount: float
    stand: Pose2D
    look_point: np.ndarray
    held: bool = False


class DoorsAndDrawers:
    """Opens and closes the doors and drawers of what ``body`` remembers, and keeps what it opened.

    Args:
        body: the robot's body.
        routes: the paths over the robot's map from where it first looks; None drives straight.
        look_inside: the kinds of part (door, drawer) to look into with the wrist camera once open.
        stand: where the base stands to open a part; None keeps the distance it has, slid along
            the front, a `StandConfig` drives it to a stand clear of the opening.
        hold_open: the parts not looked into with the wrist camera are opened holding the handle,
            looked at with the head camera so, and pushed shut from the same grasp.
    """

    def __init__(self, body: RobotBody, routes: Routes | None, look_inside: tuple[str, ...],
                 stand: StandConfig | None, hold_open: bool) -> None:
        self.body = body
        self.routes = routes
        self.look_inside = look_inside
        self.stand = stand
        self.hold_open = hold_open
        self.opened: dict[int, Opened] = {}
        self.shut: set[int] = set()  # parts this robot opened and shut again: done with, in this exploration
        self.views: list[Observation] = []  # frames taken inside the last part opened
        self.before: Observation | None = None  # the head frame from the stand, before it was opened

    def may_fold(self) -> bool:
        """Whether the arm may fold in when the base touches something on a drive (see `RobotBody.drive`).

        Returns:
            False while a door this robot opened still stands open.
        """
        return not any(opened.geometry.kind == "door" for opened in self.opened.values())

    def done_with(self) -> set[int]:
        """The doors and drawers this robot opened and shut again, by their memory ids now: each
        action is run once, so nothing will reach for their handles or swing them again.

        Returns:
            The parts' ids.
        """
        memory = self.body.memory
        return {memory.get(part_id).id for part_id in self.shut} - set(self.opened)

    def open_parts(self) -> dict[int, tuple[PartGeometry, float]]:
        """The doors and drawers this robot opened and has not shut again, by their memory ids now:
        each one's geometry as seen closed and how far it stands open.

        Returns:
            Memory id -> (geometry, opening).
        """
        memory = self.body.memory
        return {memory.get(part_id).id: (opened.geometry, opened.amount) for part_id, opened in self.opened.items()}

    def standing_open(self) -> list[np.ndarray]:
        """Where the doors and drawers this robot opened and has not shut again stand now: their
        points in the memory, which each skill that moved them carried along.

        Returns:
            One (N, 3) point set per part (with its handle) standing open.
        """
        memory = self.body.memory
        found = []
        for part_id, opened in self.opened.items():
            if opened.amount <= 0:
                continue
            part = memory.get(part_id)
            children = [memory.get(c).points() for c in part.children]
            found.append(np.vstack([part.points(), *children]))
        return found

    def drive(self, pose: Pose2D, routes: Routes | None = None, coming_back: bool = False) -> None:
        """Drive the base to ``pose`` knowing what this robot left open (see `RobotBody.drive`).

        Args:
            pose: where the base is to stand.
            routes: paths over the robot's map, or None to drive straight.
            coming_back: the base comes back to the stand of a part it opened, to close it (the
                arm may be folded on the way: `RobotBody.drive`'s ``fold_first``; it may stop
                `COME_BACK_SHORT_M` short of the stand on a touch).

        Raises:
            SkillPlanError: the base did not get there.
        """
        self.body.drive(pose, routes, may_fold=self.may_fold(), standing_open=self.standing_open(),
                        fold_first=coming_back, short_of_m=COME_BACK_SHORT_M if coming_back else 0.0)

    def open_part(self, part: Instance, handle: int | None = None) -> SkillResult:
        """Stand before the door or drawer ``part``, open it by ``handle``, look inside; the frames
        taken while it stood open are in `views`. With ``hold_open`` the hand may still hold the
        handle afterwards, until `close_part`.

        Args:
            part: the door or drawer.
            handle: the memory id of the handle to open it by (default: its first seen handle).

        Returns:
            Whether it was opened, and why not.

        Raises:
            SkillPlanError: the robot has not looked yet (no `RobotBody.home`), or no stand or
                drive got it before the part.
            GeometryError: the part has no handle seen, or its geometry cannot be read.
        """
        body = self.body
        if body.home is None:
            raise SkillPlanError("the robot has not looked yet")
        if handle is None:
            handle = self.handle(None, part)
        self.views, self.before = [], None
        geometry = handle_geometry(body.memory, handle, body.eye, kind=part.label)
        stand, amount = self._stand_for(geometry, self.routes)
        self.drive(stand, self.routes)
        self.before = body.look("head")
        geometry = handle_geometry(body.memory, handle, body.eye, kind=part.label)
        closed_centre = part.centroid
        hold = self.hold_open and geometry.kind not in self.look_inside
        result = self._open_from_here(part, geometry, amount, hold)
        if result.achieved is None and self.stand is not None:
            # Seen from near, the handle is not quite where it seemed from afar: stand again for it.
            try:
                restand, amount = self._stand_for(geometry, None)
            except SkillPlanError as error:
                return SkillResult(False, f"{result.reason}; and then {error}")
            if math.dist(restand[:2], stand[:2]) > 0.02 or abs(restand[2] - stand[2]) > 0.02:
                stand = restand
                self.drive(stand)
                body.look("head")
                geometry = handle_geometry(body.memory, handle, body.eye, kind=part.label)
                result = self._open_from_here(part, geometry, amount, hold)
        if result.achieved is None:
            return SkillResult(False, result.reason)
        if result.ok and hold:  # the hand on the handle says how far the part stands open
            body.memory.move(part.id, part_motion(geometry, result.achieved))
            self.views.append(body.look("head"))
            self.opened[part.id] = Opened(geometry, result.achieved, stand, closed_centre, held=True)
            return SkillResult(True)
        amount = self._seen_opening(geometry, part, handle, result.achieved)
        if not result.ok:
            self.opened[part.id] = Opened(geometry, amount, stand, closed_centre)
            return SkillResult(False, self._shut_after_failed_open(part, result.reason))
        look = self._look_point(geometry, part, amount, closed_centre)
        self.opened[part.id] = Opened(geometry, amount, stand, look)
        if geometry.kind in self.look_inside:
            self._look_into(look)
        return SkillResult(True)

    def _shut_after_failed_open(self, part: Instance, reason: str) -> str:
        """Push shut a part that an open which failed left ajar (a drawer held back 2 cm out, a
        door stopped part of the way by what stands in its swing): the exploration undoes only
        what succeeded, and the scene is to be left as it was found.

        Returns:
            ``reason``, with how the part was left when it stands open.
        """
        opened = self.opened[part.id]
        if opened.amount <= AJAR[opened.geometry.kind]:
            del self.opened[part.id]
            return reason
        shut = self.close_part(part)
        return f"{reason}; pushed shut again" if shut.ok else f"{reason}; left open: {shut.reason}"

    def _stand_for(self, geometry: PartGeometry, routes: Routes | None) -> tuple[Pose2D, float | None]:
        """Where to stand to open ``geometry`` and how far to open it (None: the skill's default)."""
        body = self.body
        assert body.home is not None
        if self.stand is None:
            return stand_pose(geometry, body.home), None
        q = np.asarray(body.link.call("arm_state", {}).meta["positions"], dtype=float)
        surface_z = body.surface_z(geometry.handle_point)
        try:
            stand = choose_stand(body.planner(), q, geometry, reachable=None if routes is None else routes.reaches,
                                 surface_z=surface_z, config=self.stand)
        except NoStandError as error:
            if routes is None or not error.refused["unreachable"]:
                raise
            # None of the good places is known to be reachable (the floor by the storage unseen,
            # say): try those the map does not know to be blocked, to be driven to straight.
            try:
                stand = choose_stand(body.planner(), q, geometry, surface_z=surface_z, config=self.stand,
                                     reachable=lambda xy: routes.unblocked(xy) and not routes.reaches(xy))
            except NoStandError as again:
                raise SkillPlanError(f"{error}; nor off the map's known floor ({again.why})") from None
        log.info("stand for the %s at (%.2f, %.2f): %s, opening %.2f, clear by %.2f m", geometry.kind,
                 *geometry.handle_point[:2], np.round(stand.pose, 2).tolist(), stand.amount, stand.clearance_m)
        return stand.pose, stand.amount

    def _open_from_here(self, part: Instance, geometry: PartGeometry, amount: float | None,
                        hold: bool) -> ArmResult:
        return self.body.run(f"open_{geometry.kind}", geometry=geometry, amount=amount,
                             surface_z=self.body.surface_z(geometry.handle_point), label=f"{part.label} {part.id}",
                             hold=hold, **self.keep_off(part))

    def keep_off(self, part: Instance) -> dict[str, np.ndarray]:
        """What the arm keeps off while it opens or closes a door or drawer, as the part skills'
        ports take it (world points, (N, 3) each):

        - ``keep_off``, what stands near: everything remembered but the piece the part belongs to
          with all that piece's parts and handles, and what stands inside that piece or inside the
          part's box raised to the piece's top (the things in an open drawer). A box standing
          before a low drawer is kept off: the forearm came down on one while the hand pulled the
          drawer, and let go of the handle 4.4 cm out (recursive 1022 of tuning-wide);
        - ``part_points``, the part and every handle of its piece where the memory holds them now
          (an open part's carried along by the skill that opened it), for the free move to its
          handle: on its way to a door's handle a finger caught the handle of the drawer beside it
          (drawer-door 1007 of tuning-wide).

        Args:
            part: the door or drawer.

        Returns:
            The two point sets by port name.
        """
        memory = self.body.memory
        parent = memory.instances.get(part.parent) if part.parent is not None else None
        piece = parent if parent is not None and not parent.gone else part
        family, todo = set(), [piece.id, part.id]
        while todo:
            inst = memory.get(todo.pop())
            if inst.id not in family:
                family.add(inst.id)
                todo.extend(inst.children)
        boxes = [box for box in (piece.bounds, part.bounds) if np.all(np.isfinite(box[0]))]
        if len(boxes) == 2:
            lo, hi = boxes[1]
            boxes[1] = (lo, np.r_[hi[:2], max(hi[2], boxes[0][1][2])])
        handles = [memory.get(i).points() for i in family if memory.get(i).label == "handle"]
        return {"keep_off": self.body.points_near(family, boxes, PIECE_MARGIN_M),
                "part_points": np.vstack([part.points(), *handles])}

    def _seen_opening(self, geometry: PartGeometry, part: Instance, handle: int, reported: float,
                      moved: float = 0.0) -> float:
        """How far the part stands open by a head-camera look: `opening_seen` of the handle's
        remembered points among the handles seen near where the skill says it left it (else of the
        part's own points among the parts seen there), searching up to a quarter beyond the skill's
        figure; that figure when neither is seen. ``moved``: how far open the memory holds the part now (its
        points are carried back to closed first). The memory is told the part moved to the opening
        found, then given the frame."""
        memory = self.body.memory
        observation = self.body.frame("head")
        cfg = memory.config
        detections = detect(observation.depth, observation.segmentation, frame_labels(observation.labels),
                            observation.intrinsics, observation.camera_to_world, cfg.voxel_m, cfg.min_pixels,
                            cfg.max_depth_m)
        back = np.linalg.inv(part_motion(geometry, moved))
        amount = reported
        for inst in (memory.get(handle), part):
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
            memory.move(part.id, part_motion(geometry, amount) @ back)
        memory.integrate(observation)
        self.views.append(observation)
        return amount

    def close_part(self, part: Instance) -> SkillResult:
        """Close a door or drawer this robot opened, from where it stood to open it; once more, from
        a fresh look at how far it stands open, when that fails with the part still open.

        Args:
            part: the door or drawer.

        Returns:
            Whether it is shut, and why not.
        """
        result = self._close_once(part)
        opened = self.body.remembered(self.opened, part)
        if result.ok or opened is None or opened.amount <= 0:
            return result
        handles = [c for c in part.children if self.body.memory.get(c).label == "handle"]
        if handles:
            seen = self._seen_opening(opened.geometry, part, handles[0], opened.amount, moved=opened.amount)
            self.opened[part.id] = Opened(opened.geometry, seen, opened.stand, opened.look_point)
        return self._close_once(part)

    def _close_once(self, part: Instance) -> SkillResult:
        body = self.body
        opened = body.remembered(self.opened, part)
        if opened is None:
            return SkillResult(False, f"{part.label} {part.id} was not opened by this robot")
        if opened.amount <= 0:
            del self.opened[part.id]
            return SkillResult(True)
        if not opened.held:
            self.drive(opened.stand, coming_back=True)
        result = body.run(f"close_{opened.geometry.kind}", geometry=opened.geometry, amount=opened.amount,
                          surface_z=body.surface_z(opened.geometry.handle_point), label=f"{part.label} {part.id}",
                          held=opened.held, **self.keep_off(part))
        # A drawer is pushed on past where it was seen shut until it meets its end stop, and the hand
        # may go on a little further than the part; the memory holds a shut part where it was seen shut.
        left = opened.amount if result.achieved is None else max(result.achieved, 0.0)
        motion = part_motion(opened.geometry, left) @ np.linalg.inv(part_motion(opened.geometry, opened.amount))
        body.memory.move(part.id, motion)
        if not result.ok:
            if result.held is not None:  # refused at planning with the hand still on the handle
                body.link.call("gripper", {"action": "open"})
            self.opened[part.id] = Opened(opened.geometry, left, opened.stand, opened.look_point)
            return SkillResult(False, result.reason)
        del self.opened[part.id]
        self.shut.add(part.id)
        return SkillResult(True)

    def opening(self, part: Instance) -> float:
        """How far this robot last saw ``part`` stand open.

        Args:
            part: the door or drawer.

        Returns:
            The opening (m or rad); 0 when it is not open by this robot's doing.
        """
        opened = self.body.remembered(self.opened, part)
        return 0.0 if opened is None else opened.amount

    def handle(self, call: SkillCall | None, part: Instance) -> int:
        """The handle to open ``part`` by: the one ``call`` names (``params["handle"]``, ``"o<id>"``),
        else the part's first seen handle.

        Args:
            call: the exploration primitive, or None.
            part: the door or drawer.

        Returns:
            The handle's memory id.

        Raises:
            GeometryError: the part has no handle the robot has seen.
        """
        memory = self.body.memory
        named = None if call is None else call.params.get("handle")
        if isinstance(named, str) and named.startswith("o") and named[1:].isdigit():
            return memory.get(int(named[1:])).id
        handles = [c for c in part.children if memory.get(c).label == "handle"]
        if not handles:
            raise GeometryError(f"{part.label} {part.id} has no handle the robot has seen")
        return handles[0]

    def _look_point(self, geometry: PartGeometry, part: Instance, amount: float, closed_centre: np.ndarray
                    ) -> np.ndarray:
        """Where the wrist camera looks after opening: into a drawer's tray, or behind a door."""
        piece = self.body.memory.get(part.parent) if part.parent is not None else part
        lo, hi = piece.bounds
        depth = float(abs(np.asarray(geometry.normal) @ (hi - lo)))
        depth = min(max(depth, 0.15), 0.4)
        if geometry.kind == "drawer":
            return geometry.handle_point + (amount - depth / 2) * geometry.normal - np.array([0.0, 0.0, 0.03])
        return closed_centre - (depth / 2) * geometry.normal

    def look_again_into(self, box: tuple[np.ndarray, np.ndarray]) -> bool:
        """Look once more with the wrist camera, as when it was opened, into the door or drawer
        standing open whose piece ``box`` stood inside (the box of a thing just lifted out of it).

        What a box in a drawer covered lies below the drawer's sides for the head camera: the thing
        under a nest's box there was never seen, and the graph lacked it (recursive 1261 of
        tuning-wide). A drawer's piece reaches out as far as the drawer stands open.

        Args:
            box: (lo, hi) corners of where the thing stood.

        Returns:
            Whether such a part stood open (and the wrist camera was sent to look).
        """
        memory = self.body.memory
        middle = (np.asarray(box[0], dtype=float) + np.asarray(box[1], dtype=float)) / 2
        for part_id, opened in self.opened.items():
            part = memory.get(part_id)
            piece = memory.instances.get(part.parent) if part.parent is not None else None
            if opened.amount <= 0 or opened.geometry.kind not in self.look_inside or piece is None or piece.gone:
                continue
            lo, hi = piece.bounds
            if opened.geometry.kind == "drawer":
                out = opened.amount * np.asarray(opened.geometry.normal, dtype=float)
                lo, hi = np.minimum(lo, lo + out), np.maximum(hi, hi + out)
            if np.all(middle >= lo - PIECE_MARGIN_M) and np.all(middle <= hi + PIECE_MARGIN_M):
                self._look_into(opened.look_point)
                return True
        return False

    def _look_into(self, point: np.ndarray) -> None:
        """The wrist camera at ``point``, its frame into the memory, the arm folded away again, keeping
        off all that is remembered (the part just opened among it). A view that cannot be reached
        is skipped: the head camera saw what it could."""
        surface_z = self.body.surface_z(point)
        looked = self.body.run(LOOK, look_point=point, surface_z=surface_z, keep_off=self.body.points_near(()))
        if looked.ok:
            self.views.append(self.body.look("wrist"))
        self.body.run(STOW, surface_z=surface_z)
