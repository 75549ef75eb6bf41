"""Where the base stands to pick a thing away, and where on the table the thing goes down.

A pick away (`skills.robot_picks.Picks.pick_away`) asks, side by side of the table, where the base
stands and which spots its arm reaches from there: a free spot on the surface the thing stands on
(`idle_spot`, towards the robot, out of what the doors and drawers sweep as they open and of the
lanes to their handles: `agent.acsg.keep_clear`; a thing out of storage or one that may cover
another, out of the lane from where it stood to the robot, along which what it hid is reached for
next), the base slid along a side of the table to where the arm reaches both the object and the
spot (`PLACE_REACH_M`), level with the object where it can: along the front, where the robot
started facing the table, and where that fails, along the other sides that the arm reaches the
object from, the nearest first (`skills.table_sides`), at a stand where the arm comes out of the
base clear of what stands there; where no place on it is free, on top of a thing put out of the
way before it (`stack_spot`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

import numpy as np

from agent.acsg.keep_clear import way_out
from agent.perception.instances import Instance
from agent.pose import Pose2D
from skills.arm.fold_plans import unfold_problem
from skills.arm.idle_space import HAND_RADIUS_M, idle_spot, reach_along, stack_spot
from skills.arm.skill_plan import SkillPlanError
from skills.robot_body import RobotBody
from skills.table_sides import FRONT, SIDE_NAMES, SIDES, TableSides

#: Idle spots offered to a pick away, nearest first, and how far apart they lie at least (m): where
#: the way to the nearest is blocked (a door standing open across it), the next may be clear.
PLACES, PLACES_APART_M = 3, 0.15
#: How far from the base's axis (m) a thing is picked and put down: a carry planned out near
#: `skills.robot_picks.ARM_REACH_M` fails at planning. The base slides along the table's edge to a
#: stand from which both lie within this.
PLACE_REACH_M = 0.8
#: How high (m) over the surface the lane from where a thing stood to the robot stands for
#: `idle_spot` (`way_out`): above its top, where the points of things count.
LANE_ABOVE_M = 0.03
#: How far apart (m) the stands along a side other than the front are tried
#: (`StandsAndSpots.clear_stand`).
STAND_STEP_M = 0.05


class StandsAndSpots:
    """Chooses, for the things ``body`` remembers, where the base stands to pick one away and where
    it is put down.

    Args:
        body: the robot's body.
        idle_toward_robot_m: how far from the object, towards the robot, the idle spot is sought first.
        things_away: the ids of the things this robot has put out of the way and not yet back, the
            latest last (a live view: `skills.robot_picks.Picks.away`'s keys); a thing may go down
            on top of one of them.
    """

    def __init__(self, body: RobotBody, idle_toward_robot_m: float, things_away: Iterable[int]) -> None:
        self.body = body
        self.idle_toward_robot_m = idle_toward_robot_m
        self.things_away = things_away

    def keep_clear_of(self, in_the_way: list[np.ndarray], top: np.ndarray, radius: float, table_top: float,
                      in_storage: bool, covers: bool, level: Pose2D) -> list[list[np.ndarray]]:
        """The point sets a spot to put a thing down on keeps clear of, in the order they are tried:
        ``in_the_way`` (every remembered thing but the surface, what the doors and drawers sweep and
        the lanes to their handles: `agent.acsg.keep_clear.kept_clear`, worked out once for every
        side); and a lane (`way_out`) from where the thing stood (``top``, its top grasp point) to
        the robot. Out of storage (``in_storage``), the lane to where the robot started, as wide as
        the thing (``radius``, its footprint's): put down in front of the cabinet it came from, a
        box hid the smaller box it had covered from the robot's cameras and stood in the way of the
        hand reaching in for it (recursive 1075 of tuning-wide). In the open, for a thing that may
        cover what stands under it (``covers``: `agent.acsg.decision.COVER_LABELS`, what the
        decision module lifts to look beneath), the lane to the stand level with it on the side it
        is picked from (``level``), from where the hand reaches for what it covered next, as wide as
        the hand across its axis at the least (`HAND_RADIUS_M`): a box lifted off a smaller one and
        put down right before it held back the hand leaning over it to the smaller one's near edge,
        which closed on nothing above its top (recursive 1154 and 1160), and put down beside a lane
        to where the robot started, the hand's palm caught its corner (1128). In the open, where no
        spot clear of that lane is free or the pick finds no plan to one, the same sets but the lane
        are tried after (a box 0.31 m wide 0.94 m out, its spots beside the lane, reached none:
        recursive 1064).

        Args:
            in_the_way: (N, 3) point sets kept clear from every side.
            top: the thing's top grasp point where it stands.
            radius: half the widest of its footprint (m).
            table_top: the height of the surface it stands on (m).
            in_storage: whether it stands under a board (`skills.arm.headroom.under_a_board`).
            covers: whether it may cover another thing.
            level: the stand level with it on the side it is picked from.

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

    def sides(self, table: TableSides, top: np.ndarray, front_only: bool = False
              ) -> list[tuple[int, tuple[float, float]]]:
        """The sides of ``table`` to pick the thing whose top grasp point is ``top`` from, each with
        the interval along its line from which the arm reaches it (`PLACE_REACH_M`): the front
        first, where the robot started, level with the thing where no stand along it is that near
        (the arm may still reach it there, a little further out: it lifted nests 0.94 m out,
        recursive 1064 of tuning-wide, and `skills.robot_picks.beyond_reach` says how far out a
        thing stands where it did not); then the other sides the arm reaches it from, the nearest
        first.

        With ``front_only`` (a thing in storage, or a door or drawer this robot opened standing
        open), the front alone: storage opens towards the front, and from the back a box in a
        cabinet stood 0.4 m out behind the cabinet's back; the robot driving round the table
        folded its arm into the handle of the door it had left open, and that door, come back to,
        was not shut again (recursive 1243 of tuning-wide).

        Args:
            table: the table's sides, as seen from where the robot started.
            top: the thing's top grasp point.
            front_only: the front alone.

        Returns:
            (side, (lo, hi)) for each side in the order tried, (lo, hi) along its line.
        """
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

    def stand_and_spots(self, obj: Instance, surface: Instance, table: TableSides, side: int,
                        grasp_along: tuple[float, float], top: np.ndarray, extent: np.ndarray,
                        keep_clear: list[np.ndarray], radius: float, may_stack: bool) -> tuple[Pose2D, np.ndarray]:
        """Where on ``side``'s line the base stands to pick ``obj`` (its arm reaching the object from
        anywhere in ``grasp_along``) and the spots to put it down that the arm reaches from there,
        nearest first (`_put_down_spots`): sought first towards the robot from the object (towards
        where it started, at the front; elsewhere towards the side's line), beyond the strip before
        the robot's start that its head camera does not see, as close to level with the object as
        the spot allows.

        Args:
            obj: the thing to put down.
            surface: what it stands on.
            table: the table's sides.
            side: the side to stand at (`skills.table_sides.SIDES`).
            grasp_along: (lo, hi) along the side's line, from which the arm reaches the thing.
            top: its top grasp point.
            extent: its box (dx, dy, dz).
            keep_clear: (N, 3) point sets a spot keeps clear of (`keep_clear_of`).
            radius: half the widest of its footprint (m).
            may_stack: whether it may go on top of a thing away where no place is free.

        Returns:
            The stand, and the spots (k, 3) (x, y, top z) that the arm reaches from it, nearest
            first.

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
            along = self.clear_stand(table, side, along, lo_along, hi_along)
        lo, hi = reach_along(table.local(side, spots[:, :2]), line, PLACE_REACH_M)
        return table.stand(side, along), spots[(lo <= along) & (along <= hi)]  # the others the same stand reaches

    def clear_stand(self, table: TableSides, side: int, level: float, lo: float, hi: float) -> float:
        """The place along ``side``'s line, within [``lo``, ``hi``], nearest ``level``, every
        `STAND_STEP_M`, where the arm comes out of the base clear of all that is remembered
        (`unfold_problem`). Not asked at the front, whose strip before the robot is kept clear for
        the arm; at the back the storage stands right before the base.

        Args:
            table: the table's sides.
            side: the side whose line the base stands on.
            level: the place along the line tried first (level with the thing).
            lo: the low end of the stretch of the line searched.
            hi: its high end.

        Returns:
            The place along the line.

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
        for thing_id in reversed(list(self.things_away)):
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
