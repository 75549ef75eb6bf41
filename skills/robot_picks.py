"""Picking things away out of the way and back to where they stood, with the robot's body.

- pick away: to a free spot on the table, from a stand along one of its sides, both chosen by
  `skills.stands_and_spots.StandsAndSpots`, a side at a time; where no side finds a plan, every
  side again, by the near edge of a top in the open too;
- pick back: from the stand it was picked from, from where it was put down to where it was, by the
  near edge of its top last.

The box a thing filled before it was picked away is kept while it is away (``vacated``): what is
found there lay inside it (the Matryoshka's smaller doll).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from agent.acsg.decision import COVER_LABELS
from agent.acsg.from_memory import Box
from agent.acsg.interfaces import SkillResult
from agent.acsg.keep_clear import kept_clear
from agent.perception.grasp_poses import drawer_floor, standing_extent, top_grasp_point
from agent.perception.hidden_bodies import closed_drawer_faces
from agent.perception.instances import Instance
from agent.pose import Pose2D
from skills.arm.grasps import ObjectGrasp
from skills.arm.headroom import under_a_board
from skills.arm.skill_plan import SkillPlanError
from skills.base import SkillResult as ArmResult
from skills.robot_body import RobotBody, surface_top
from skills.robot_parts import DoorsAndDrawers
from skills.stands_and_spots import StandsAndSpots

#: A thing whose top grasp point a look finds this near (m) where it was picked from is back:
#: the evaluation's tolerance for a thing put back.
BACK_M = 0.02
#: A thing whose top the memory has this far across (m) from where it was put down has moved since.
MOVED_M = 0.03
#: How far (m) beyond the box a thing filled what it covered may show in the memory (its voxels).
COVERED_M = 0.005
#: How far from the base's axis (m) the arm reaches a table's top from above at all.
ARM_REACH_M = 0.85


@dataclass(frozen=True)
class Away:
    """A thing this robot picked away: its top grasp point where it stood (``grasp_point``), where
    that point was put down (``placed_point``) and its box in the memory there once put down
    (``placed_bounds``), its ``extent``, where the base stood at the table's side to pick it
    (``stand``), and how the hand held it (``grasp``, None where the plan did not say)."""

    grasp_point: np.ndarray
    placed_point: np.ndarray
    placed_bounds: tuple[np.ndarray, np.ndarray]
    extent: np.ndarray
    stand: Pose2D
    grasp: ObjectGrasp | None = None


class Picks:
    """Picks things of what ``body`` remembers away and back, and keeps what is away.

    Args:
        body: the robot's body.
        idle_toward_robot_m: how far from the object, towards the robot, the idle spot is sought first.
        parts: the doors and drawers the robot opens: the base drives knowing what it left open
            (`skills.robot_parts.DoorsAndDrawers.drive`), and things are put down out of the way of
            those it will still reach for.
    """

    def __init__(self, body: RobotBody, idle_toward_robot_m: float, parts: DoorsAndDrawers) -> None:
        self.body = body
        self.parts = parts
        self.away: dict[int, Away] = {}
        self.stands_and_spots = StandsAndSpots(body, idle_toward_robot_m, self.away.keys())
        self.vacated: dict[int, Box] = {}  # the box each thing away filled where it stood, down to its foot

    def pick_away(self, obj: Instance) -> SkillResult:
        """Put ``obj`` down on a free spot of the surface it stands on, in the arm's reach and,
        where there is one, beyond the strip before the robot that the arm works over, and, for a
        thing that may cover another or one out of storage, out of the lane from where it stood to
        the robot (in the open, where no such spot is free or no plan is found to one, in it); where
        none is free, on top of a thing it put out of the way before (`StandsAndSpots`). The base
        stands at the table's front, where the robot started; where no spot is free or no plan is
        found from there, at the other sides of the table that the arm reaches the thing from, the
        nearest first, unless the thing is in storage or a part this robot opened stands open
        (`StandsAndSpots.sides`). Where no plan is found from any side, a thing in the open is tried
        again from each, by the near edge of its top as well (``near_edge`` of
        `skills.arm.pick_plans.plan_pick`: a top beyond the hand's reach from above, between the
        cabinets at a table's back, recursive 1182 of tuning-wide); not before, since no other grasp
        holds a box less surely. A thing standing in a drawer the robot opened reaches down to the
        drawer's floor (`_drawer_floor`). Lifted out of a door or drawer standing open, the wrist
        camera looks in again at what it covered (`DoorsAndDrawers.look_again_into`).

        Args:
            obj: the thing to move out of the way.

        Returns:
            Whether it was put down there, and why not: why the run that moved the arm failed,
            else why the first side tried failed.

        Raises:
            SkillPlanError: the robot has not looked yet (no `RobotBody.home`), there is no surface
                under it or no table before the robot, or no free spot, or the base did not get to
                its stand; the last two say how far out the thing stands where no side brings it
                within the arm's reach (the nests in storage at a table's back: no spot within reach
                of both is free).
        """
        body = self.body
        if body.home is None:
            raise SkillPlanError("the robot has not looked yet")
        points = obj.points()
        top, box = top_grasp_point(points), obj.bounds
        surface, table = body.stood_on(obj), body.table_sides()
        if surface is None or table is None:
            raise SkillPlanError("no table or counter in memory to put the object down on")
        keep_off, table_top = self._near(obj), surface_top(surface)
        floor, seen = self._drawer_floor(points) or (table_top, False)
        extent = standing_extent(points, np.vstack([keep_off, surface.points()]), floor_z=max(table_top, floor),
                                 stands_on_z=floor if seen else None)
        box = (np.r_[box[0][:2], min(box[0][2], box[1][2] - extent[2])], box[1])  # down to what it stands on
        radius = float(max(extent[:2])) / 2
        in_storage = under_a_board(top, extent, keep_off)
        front_only = in_storage or bool(self.parts.standing_open())
        others = [inst.points() for inst in body.memory.live() if inst.id != surface.id]
        in_the_way = [*others, *kept_clear(body.memory, body.eye, body.home[:2], self.parts.done_with(),
                                           self.parts.open_parts())]
        first: tuple[SkillPlanError | ArmResult, tuple[float, float]] | None = None  # and where it stood
        sides = self.stands_and_spots.sides(table, top, front_only)
        tries = [(side, along, False) for side, along in sides]
        if not in_storage:  # the near edge after every side: no other grasp holds a box less surely
            tries += [(side, along, True) for side, along in sides]
        for side, grasp_along, near_edge in tries:
            failed: tuple[SkillPlanError | ArmResult, tuple[float, float]] | None = None  # of the last spots sought
            level = table.stand(side, table.along(side, top))
            keep_clear_of = self.stands_and_spots.keep_clear_of(in_the_way, top, radius, table_top, in_storage,
                                                                obj.label in COVER_LABELS, level)
            for tier, keep_clear in enumerate(keep_clear_of):
                try:
                    stand, spots = self.stands_and_spots.stand_and_spots(
                        obj, surface, table, side, grasp_along, top, extent, keep_clear, radius,
                        may_stack=tier == len(keep_clear_of) - 1)
                    self.parts.drive(stand)
                except SkillPlanError as error:
                    failed = (error, (level.x, level.y))
                    continue
                places = spots + np.array([0.0, 0.0, extent[2]])  # its top, as it stands
                result = body.run("pick_away", object_point=top, object_extent=extent, place_point=places,
                                  surface_z=table_top, label=f"{obj.label} {obj.id}", keep_off=keep_off,
                                  near_edge=near_edge)
                if result.ok:
                    place = np.asarray(result.info.get("place_point", places[0]), dtype=float)
                    body.memory.move(obj.id, _translation(place - top), carried=True)
                    self.away[obj.id] = Away(top, place, obj.bounds, extent, stand, result.info.get("grasp_way"))
                    self.vacated[obj.id] = box
                    self.parts.look_again_into(box)
                    return SkillResult(True)
                failed = (result, (stand.x, stand.y))
                if not result.unplanned:
                    break
            assert failed is not None  # one list of sets at least
            if isinstance(failed[0], ArmResult) and not failed[0].unplanned:
                first = failed  # the arm moved: the scene is no longer as the other sides would plan from
                break
            first = first or failed
        assert first is not None  # `StandsAndSpots.sides` gives one side at least
        failure, stood = first
        if isinstance(failure, SkillPlanError):  # say so where no side brings the thing within reach
            raise SkillPlanError(f"{failure}{beyond_reach(top, stood)}") from None
        return SkillResult(False, failure.reason + (beyond_reach(top, stood) if failure.unplanned else ""))

    def pick_back(self, obj: Instance) -> SkillResult:
        """Put ``obj``, picked away by this robot, back where it stood; when that fails after the arm
        moved, once more from a fresh look at where the thing now is (`_find_again`), unless the
        look finds it back already.

        Args:
            obj: the thing picked away.

        Returns:
            Whether it is back, and why not.

        Raises:
            SkillPlanError: the base did not get to the stand it was picked from.
        """
        body = self.body
        away = body.remembered(self.away, obj)
        if away is None:
            return SkillResult(False, f"{obj.label} {obj.id} was not picked away by this robot")
        assert body.home is not None  # set by the look before the pick away
        self.parts.drive(away.stand)
        result = self._put_back(obj, away)
        if not result.ok and result.steps_done:
            found = self._find_again(obj, away)
            if found is not None and float(np.linalg.norm(found - away.grasp_point)) <= BACK_M:
                return self._back(obj)  # it was let go of where it belongs
            if found is not None:
                result = self._put_back(obj, away)
        return self._back(obj) if result.ok else SkillResult(False, result.reason)

    def _put_back(self, obj: Instance, away: Away) -> ArmResult:
        """One run of the pick-back skill from where ``obj`` is now; the memory is told where it
        went when it went there.

        Where the memory has the thing within `MOVED_M` across of where it was put down, it still
        stands there, and the hand goes to that very point (at the height seen): held where it was
        held when it was put down, it goes back as it came. Seen anew from the side it stands at
        there, a box's top moved 1.7 cm in the memory, and put back by that top, the box came down
        onto the wall of the smaller one it had covered. How far it moved is how far both its
        sides moved (`_moved`): a box seen whole once put down, 3 cm wider than where it stood
        half hidden, was put back by its new middle, 3 cm beside where it stood (recursive 1117 of
        tuning-wide)."""
        body = self.body
        points = obj.points()
        now = top_grasp_point(points) if len(points) else away.placed_point
        moved = _moved(away.placed_bounds, obj.bounds) if len(points) else np.zeros(2)
        if float(np.linalg.norm(moved)) <= MOVED_M:
            moved = np.zeros(2)
        now = np.array([*(away.placed_point[:2] + moved), now[2]])
        result = body.run("pick_back", object_point=now, object_extent=away.extent, place_point=away.grasp_point,
                          surface_z=body.surface_z(away.grasp_point),  # under its place, below its top
                          label=f"{obj.label} {obj.id}", grasp_first=away.grasp, near_edge=True,
                          keep_off=self._near(obj, covering=body.remembered(self.vacated, obj)))
        if result.ok:
            body.memory.move(obj.id, _translation(away.grasp_point - now), carried=True)
        return result

    def _find_again(self, obj: Instance, away: Away) -> np.ndarray | None:
        """Where ``obj`` is after a pick back failed on the way: a head look from the stand; when the
        memory no longer has it where it was, the thing of its label first seen in that look
        nearest its place is it (the hand let go of it on the way), and the memory is told so.

        Returns:
            Its top grasp point now, or None when the look does not show it.
        """
        body = self.body
        body.look("head")
        memory = body.memory
        if not obj.gone and len(obj.points()):
            return top_grasp_point(obj.points())
        new = [inst for inst in memory.with_label(obj.label) if inst.first_seen == memory.frame]
        if not new:
            return None
        nearest = min(new, key=lambda inst: float(np.linalg.norm(inst.centroid - away.grasp_point)))
        kept = memory.merge(obj.id, nearest.id)
        return top_grasp_point(kept.points())

    def _back(self, obj: Instance) -> SkillResult:
        """``obj`` stands where it was picked from: forget it was away."""
        del self.away[obj.id]
        self.body.remembered(self.vacated, obj)
        self.vacated.pop(obj.id, None)
        return SkillResult(True)

    def _drawer_floor(self, points: np.ndarray) -> tuple[float, bool] | None:
        """How low the thing of ``points`` reaches in a drawer this robot opened that it stands in
        (`agent.perception.grasp_poses.drawer_floor`); None where it stands in none."""
        memory = self.body.memory
        floors = (drawer_floor(points, memory.get(part_id).points())
                  for part_id, (geometry, _) in self.parts.open_parts().items() if geometry.kind == "drawer")
        return next((floor for floor in floors if floor is not None), None)

    def _near(self, obj: Instance, covering: Box | None = None) -> np.ndarray:
        """The points of everything remembered but ``obj`` and the tables and counters: what the hand
        picking it and putting it down is to keep off (a bottle beside the one picked, the handle
        beside the place it goes back to).

        ``covering``: the box ``obj`` filled where it goes back. What stands inside it stood under
        it before (the clock a box was lifted off, the smaller box in the larger) and the thing is
        put back over it, so it is not kept off: kept off, the box coming down over the clock
        ruled out every route checked clear, and the one taken unchecked swept the box across a
        chest's handles and pulled both its drawers open (recursive 1016 of tuning-wide). The box
        reaches down to what the thing stood on: a box in a drawer is remembered by its top only,
        and what it covered, seen once it was lifted, stood under that top (recursive 1261)."""
        seen = self.body.points_near({obj.id}, () if covering is None else (covering,), COVERED_M)
        return np.vstack([seen, *self._closed_drawers()])

    def _closed_drawers(self) -> list[np.ndarray]:
        """What the drawers not standing open fill behind their fronts (`closed_drawer_faces`),
        for each drawer whose chest the memory holds."""
        memory = self.body.memory
        standing_open = {memory.get(part_id).id for part_id, opened in self.parts.opened.items() if opened.amount > 0}
        faces = []
        for drawer in memory.with_label("drawer"):
            if drawer.id in standing_open or drawer.parent is None or len(front := drawer.points()) < 3:
                continue
            faces.append(closed_drawer_faces(front, memory.get(drawer.parent).points(), self.body.eye))
        return faces


def beyond_reach(point: np.ndarray, stand_xy: tuple[float, float], reach_m: float = ARM_REACH_M) -> str:
    """What to add to the reason a pick could not be planned when its object stands further from
    the base's axis than the arm reaches over a table: the nests of boxes in storage at a table's
    back edge stand 0.85–1.2 m out, and "no route" alone sent the search to the routes.

    Args:
        point: the object's grasp point (world; its x, y count).
        stand_xy: where the base's axis stands (world x, y).
        reach_m: how far the arm reaches over a table from the base's axis.

    Returns:
        " (… m from the base's axis, beyond the arm's reach over a table, … m)", or "" within it.
    """
    out = math.dist((float(point[0]), float(point[1])), stand_xy)
    if out <= reach_m:
        return ""
    return f" ({out:.2f} m from the base's axis, beyond the arm's reach over a table, {reach_m:.2f} m)"


def _moved(before: tuple[np.ndarray, np.ndarray], now: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """How far (x, y) a thing's box in the memory moved from ``before`` to ``now`` (each (lo, hi)):
    along each axis, as far as both its sides moved the same way; a side that alone moved is the
    memory seeing more or less of the thing, not the thing moving."""
    lo, hi = (np.asarray(now[k][:2], dtype=float) - np.asarray(before[k][:2], dtype=float) for k in (0, 1))
    return np.where(np.sign(lo) == np.sign(hi), np.sign(lo) * np.minimum(np.abs(lo), np.abs(hi)), 0.0)


def _translation(offset: np.ndarray) -> np.ndarray:
    motion = np.eye(4)
    motion[:3, 3] = offset
    return motion
