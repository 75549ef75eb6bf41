"""Picking things away out of the way and back to where they stood, with the robot's body.

- pick away: a free spot on the surface it stands on (`idle_spot`, towards the robot, out of what
  the doors and drawers sweep as they open and of the lanes to their handles:
  `agent.acsg.keep_clear`; a thing out of storage or one that may cover another, out of the lane
  from where it stood to the robot, along which what it hid is reached for next), the base slid
  along a side of the table to where the arm reaches both the object and the spot
  (`PLACE_REACH_M`), level with the object where it can: along the front, where the robot started
  facing the table, and where that fails, along the other sides that the arm reaches the object
  from, the nearest first (`skills.table_sides`), at a stand where the arm comes out of the base
  clear of what stands there; where no place on it is free, on top of a thing put out of the way
  before it (`stack_spot`); where no side finds a plan, every side again, by the near edge of a
  top in the open too;
- pick back: from the stand it was picked from, from where it was put down to where it was, by the
  near edge of its top last.

The box a thing filled before it was picked away is kept while it is away (``vacated``): what is
found there lay inside it (the Matryoshka's smaller doll).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from agent.acsg.decision import COVER_LABELS
from agent.acsg.from_memory import Box
from agent.acsg.interfaces import SkillResult
from agent.acsg.keep_clear import kept_clear, way_out
from agent.perception.grasp_poses import drawer_floor, standing_extent, top_grasp_point
from agent.perception.hidden_bodies import closed_drawer_faces
from agent.perception.instances import Instance
from agent.pose import Pose2D
from skills.arm.grasps import ObjectGrasp
from skills.arm.fold_plans import unfold_problem
from skills.arm.headroom import under_a_board
from skills.arm.idle_space import HAND_RADIUS_M, idle_spot, reach_along, stack_spot
from skills.arm.skill_plan import SkillPlanError
from skills.base import SkillResult as ArmResult
from skills.robot_body import RobotBody, surface_top
from skills.robot_parts import DoorsAndDrawers
from skills.table_sides import FRONT, SIDE_NAMES, SIDES, TableSides

#: A thing whose top grasp point a look finds this near (m) where it was picked from is back:
#: the evaluation's tolerance for a thing put back.
BACK_M = 0.02
#: A thing whose top the memory has this far across (m) from where it was put down has moved since.
MOVED_M = 0.03
#: How far (m) beyond the box a thing filled what it covered may show in the memory (its voxels).
COVERED_M = 0.005
#: Idle spots offered to a pick away, nearest first, and how far apart they lie at least (m): where
#: the way to the nearest is blocked (a door standing open across it), the next may be clear.
PLACES, PLACES_APART_M = 3, 0.15
#: How far from the base's axis (m) the arm reaches a table's top from above at all.
ARM_REACH_M = 0.85
#: How far from the base's axis (m) a thing is picked and put down: a carry planned out near
#: `ARM_REACH_M` fails at planning. The base slides along the table's edge to a stand from which
#: both lie within this.
PLACE_REACH_M = 0.8
#: How high (m) over the surface the lane from where a thing stood to the robot stands for
#: `idle_spot` (`way_out`): above its top, where the points of things count.
LANE_ABOVE_M = 0.03
#: How far apart (m) the stands along a side other than the front are tried (`Picks._clear_stand`).
STAND_STEP_M = 0.05


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
        self.idle_toward_robot_m = idle_toward_robot_m
        self.parts = parts
        self.away: dict[int, Away] = {}
        self.vacated: dict[int, Box] = {}  # the box each thing away filled where it stood, down to its foot

    def pick_away(self, obj: Instance) -> SkillResult:
        """Put ``obj`` down on a free spot of the surface it stands on, in the arm's reach and, where
        there is one, beyond the strip before the robot that the arm works over, and, for a thing
        that may cover another or one out of storage, out of the lane from where it stood to the
        robot (in the open, where no such spot is free or no plan is found to one, in it:
        `_keep_clear_of`); where none is free, on top of a thing it put out of the way before
        (`_on_a_thing_away`). The base stands at the table's front, where the robot started; where
        no spot is free or no plan is found from there, at the other sides of the table that the
        arm reaches the thing from, the nearest first, unless the thing is in storage or a part
        this robot opened stands open (`_sides`). Where no plan is found from any side, a thing in
        the open is tried again from each, by the near edge of its top as well (``near_edge`` of
        `skills.arm.pick_plans.plan_pick`: a top beyond the hand's reach from above, between the
        cabinets at a table's back, recursive 1182 of tuning-wide); not before, since no other grasp
        holds a box less surely. A thing standing in a drawer the robot opened
        reaches down to the drawer's floor (`_drawer_floor`). Lifted out of a door or drawer
        standing open, the wrist camera looks in again at what it covered
        (`DoorsAndDrawers.look_again_into`).

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
        sides = self._sides(table, top, front_only)
        tries = [(side, along, False) for side, along in sides]
        if not in_storage:  # the near edge after every side: no other grasp holds a box less surely
            tries += [(side, along, True) for side, along in sides]
        for side, grasp_along, near_edge in tries:
            failed: tuple[SkillPlanError | ArmResult, tuple[float, float]] | None = None  # of the last spots sought
            level = table.stand(side, table.along(side, top))
            keep_clear_of = self._keep_clear_of(in_the_way, top, radius, table_top, in_storage,
                                                obj.label in COVER_LABELS, level)
            for tier, keep_clear in enumerate(keep_clear_of):
                try:
                    stand, spots = self._stand_and_spots(obj, surface, table, side, grasp_along, top, extent,
                                                         keep_clear, radius, may_stack=tier == len(keep_clear_of) - 1)
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
        assert first is not None  # `_sides` gives one side at least
        failure, stood = first
        if isinstance(failure, SkillPlanError):  # say so where no side brings the thing within reach
            raise SkillPlanError(f"{failure}{beyond_reach(top, stood)}") from None
        return SkillResult(False, failure.reason + (beyond_reach(top, stood) if failure.unplanned else ""))

    def _keep_clear_of(self, in_the_way: list[np.ndarray], top: np.ndarray, radius: float, table_top: float,
                       in_storage: bool, covers: bool, level: Pose2D) -> list[list[np.ndarray]]:
        """The point sets a spot to put a thing down on keeps clear of, in the order they are tried:
        ``in_the_way`` (every remembered thing but the surface, what the doors and drawers sweep
        and the lanes to their handles: `kept_clear`, worked out once for every side); and a lane
        (`way_out`) from where the thing stood (``top``, its top grasp point) to the robot. Out of
        storage (``in_storage``), the lane to where the robot started, as wide as the thing
        (``radius``, its footprint's): put down in front of the cabinet it came from, a box hid the
        smaller box it had covered from the robot's cameras and stood in the way of the hand
        reaching in for it (recursive 1075 of tuning-wide). In the
        open, for a thing that may cover what stands under it (``covers``: `COVER_LABELS`, what the
        decision module lifts to look beneath), the lane to the stand level with it on the side it
        is picked from (``level``), from where the hand reaches for what it covered next, as wide
        as the hand across its axis at the least (`HAND_RADIUS_M`): a box lifted off a smaller one
        and put down right before it held back the hand leaning over it to the smaller one's near
        edge, which closed on nothing above its top (recursive 1154 and 1160), and put down beside a
        lane to where the robot started, the hand's palm caught its corner (1128). In the open,
        where no spot clear of that lane is free or the pick finds no plan to one, the same sets but
        the lane are tried after (a box 0.31 m wide 0.94 m out, its spots beside the lane, reached
        none: recursive 1064).

        Returns:
            One or two lists of (N, 3) point sets.
        """
        home = self.body.home
        assert home is not None
        if in_storage:
            return [[*in_the_way, way_out(top, radius, home[:2], table_top + LANE_ABOVE_M)]]
        if not covers:
            return [in_the_way]
        lane = way_out(top, max(radius, HAND_RADIUS_M), np.array([level.x, level.y]), table_top + LANE_ABOVE_M)
        return [[*in_the_way, lane], in_the_way]

    def _sides(self, table: TableSides, top: np.ndarray, front_only: bool = False
               ) -> list[tuple[int, tuple[float, float]]]:
        """The sides of ``table`` to pick the thing whose top grasp point is ``top`` from, each with
        the interval along its line from which the arm reaches it (`PLACE_REACH_M`): the front
        first, where the robot started, level with the thing where no stand along it is that near
        (the arm may still reach it there, a little further out: it lifted nests 0.94 m out,
        recursive 1064 of tuning-wide, and `beyond_reach` says how far out a thing stands where it
        did not); then the other sides the arm reaches it from, the nearest first.

        With ``front_only`` (a thing in storage, or a door or drawer this robot opened standing
        open), the front alone: storage opens towards the front, and from the back a box in a
        cabinet stood 0.4 m out behind the cabinet's back; the robot driving round the table
        folded its arm into the handle of the door it had left open, and that door, come back to,
        was not shut again (recursive 1243 of tuning-wide)."""
        reaching = []
        for side in SIDES:
            (lo,), (hi,) = reach_along(table.local(side, top[:2]), table.line(side), PLACE_REACH_M)
            if lo <= hi:
                out = float(table.local(side, top[:2])[0, 1]) - table.line(side)
                reaching.append((side != FRONT, out, side, (float(lo), float(hi))))
        reaching.sort()
        if not reaching or reaching[0][2] != FRONT:
            level = table.along(FRONT, top)
            reaching.insert(0, (False, 0.0, FRONT, (level, level)))
        return [(side, interval) for _, _, side, interval in reaching[:1 if front_only else None]]

    def _stand_and_spots(self, obj: Instance, surface: Instance, table: TableSides, side: int,
                         grasp_along: tuple[float, float], top: np.ndarray, extent: np.ndarray,
                         keep_clear: list[np.ndarray], radius: float, may_stack: bool) -> tuple[Pose2D, np.ndarray]:
        """Where on ``side``'s line the base stands to pick ``obj`` (its arm reaching the object from
        anywhere in ``grasp_along``) and the spots to put it down that the arm reaches from there,
        nearest first (`_put_down_spots`): sought first towards the robot from the object (towards
        where it started, at the front; elsewhere towards the side's line), beyond the strip before
        the robot's start that its head camera does not see, as close to level with the object as
        the spot allows.

        Raises:
            SkillPlanError: no spot is free (the reason the surface gives).
        """
        body = self.body
        assert body.home is not None
        line, (grasp_lo, grasp_hi) = table.line(side), grasp_along
        toward_xy = body.home[:2] if side == FRONT else table.stand(side, table.along(side, top))[:2]
        toward = np.asarray(toward_xy) - top[:2]
        near = top[:2] + self.idle_toward_robot_m * toward / max(float(np.linalg.norm(toward)), 1e-6)

        def reachable(places: np.ndarray) -> np.ndarray:
            lo, hi = reach_along(table.local(side, places[:, :2]), line, PLACE_REACH_M)
            return np.maximum(lo, grasp_lo) <= np.minimum(hi, grasp_hi)

        def beyond_strip(places: np.ndarray) -> np.ndarray:
            ahead = table.local(FRONT, places[:, :2])[:, 1] - table.line(FRONT)
            return reachable(places) & (ahead >= body.head_sees_from)

        spots = self._put_down_spots(obj, surface, keep_clear, radius, near, extent, beyond_strip, reachable,
                                     may_stack)
        (place_lo,), (place_hi,) = reach_along(table.local(side, spots[:1, :2]), line, PLACE_REACH_M)
        lo_along, hi_along = max(grasp_lo, place_lo), min(grasp_hi, place_hi)
        along = float(np.clip(table.along(side, top), lo_along, hi_along))
        if side != FRONT:
            along = self._clear_stand(table, side, along, lo_along, hi_along)
        lo, hi = reach_along(table.local(side, spots[:, :2]), line, PLACE_REACH_M)
        return table.stand(side, along), spots[(lo <= along) & (along <= hi)]  # the others the same stand reaches

    def _clear_stand(self, table: TableSides, side: int, level: float, lo: float, hi: float) -> float:
        """The place along ``side``'s line, within [``lo``, ``hi``], nearest ``level``, every
        `STAND_STEP_M`, where the arm comes out of the base clear of all that is remembered
        (`unfold_problem`). Not asked at the front, whose strip before the robot is kept clear for
        the arm; at the back the storage stands right before the base.

        Raises:
            SkillPlanError: no such place.
        """
        planner, near = self.body.planner(), self.body.points_near(())
        for along in sorted(np.r_[level, np.arange(lo, hi + 1e-9, STAND_STEP_M)], key=lambda a: abs(a - level)):
            if unfold_problem(planner, table.stand(side, float(along)), near) is None:
                return float(along)
        raise SkillPlanError(f"no stand at the table's {SIDE_NAMES[side]} from which the arm comes out of the base "
                             "clear of what stands there")

    def _put_down_spots(self, obj: Instance, surface: Instance, keep_clear: list[np.ndarray], radius: float,
                        near: np.ndarray, extent: np.ndarray, beyond_strip: Callable[[np.ndarray], np.ndarray],
                        reachable: Callable[[np.ndarray], np.ndarray], may_stack: bool) -> np.ndarray:
        """Where ``obj`` (of ``extent``, ``radius`` across its footprint) may be put down, nearest
        ``near`` first: free places of ``surface`` clear of ``keep_clear`` beyond the strip the arm
        works over from the robot's stands (``beyond_strip``), else in it (``reachable``), else,
        ``may_stack``, on top of a thing put away before it (`_on_a_thing_away`).

        Returns:
            (k, 3): the spots (x, y, top z).

        Raises:
            SkillPlanError: no place is free (the reason the surface gives).
        """
        options = {"height": float(extent[2]), "count": PLACES, "apart_m": PLACES_APART_M}
        try:
            return idle_spot(surface.points(), keep_clear, radius, near, allowed=beyond_strip,
                             allowed_means="within the arm's reach beyond the strip before the robot", **options)
        except SkillPlanError:
            pass
        try:
            return idle_spot(surface.points(), keep_clear, radius, near, allowed=reachable,
                             allowed_means="within the arm's reach", **options)
        except SkillPlanError as no_room:
            spots = self._on_a_thing_away(obj, extent, reachable) if may_stack else None
            if spots is None:
                raise no_room from None
            return spots

    def _on_a_thing_away(self, obj: Instance, extent: np.ndarray, reachable: Callable[[np.ndarray], np.ndarray]
                         ) -> np.ndarray | None:
        """A spot on top of a thing this robot put out of the way before ``obj``, the latest first,
        whose top holds ``obj`` whole (`stack_spot`) where the arm reaches (``reachable``): a table
        with no free place left may still take the smaller box of a nest on the larger one lifted
        off it (recursive 1014 of tuning-wide). That thing is done with until it goes back, and it
        goes back after ``obj`` (the action stack puts back the last thing moved first).

        Returns:
            (1, 3): the spot (x, y, top z), or None where no such thing is.
        """
        memory = self.body.memory
        points = {inst.id: inst.points() for inst in memory.live() if inst.id != obj.id}
        for thing_id in reversed(list(self.away)):
            support = memory.get(thing_id)
            if support.id not in points:
                continue  # gone
            lo, hi = support.bounds
            if bool(np.all((obj.centroid[:2] >= lo[:2]) & (obj.centroid[:2] <= hi[:2]))):
                continue  # the object stands on it already: seen anew there, it is the one put there
            others = [seen for key, seen in points.items() if key != support.id]
            spot = stack_spot(points[support.id], others, extent)
            if spot is not None and bool(reachable(spot[None, :2])[0]):
                return spot[None, :]
        return None

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
