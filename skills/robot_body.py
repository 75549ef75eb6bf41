"""The robot's body over the world link: running skills, taking frames, driving the base, and the
tables and counters it remembers.

What the scene-graph executor (`skills.robot.Robot`) and its handling of doors, drawers and picks
share: the `SkillContext` the skills run in, the `SkillRegistry` that makes them by name, where the
base stands as the world last said (``pose``), where the robot first looked (``home``, set by
`skills.robot.Robot.observe`), the head camera's position (``eye``), every skill run's name,
outcome and timings (``skill_times``), and whoever wants each run's result as it ends
(``skill_listeners``: a recording of the arm's joints).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Collection, Sequence
from typing import Any, TypeVar

import numpy as np

from agent.acsg.from_memory import SUPPORT_GAP_M, Box
from agent.observation import Observation
from agent.perception.grasp_poses import top_grasp_point
from agent.perception.instances import Instance
from agent.perception.memory import InstanceMemory
from agent.planning.route import Routes
from agent.pose import Pose2D
from skills.arm.drive_clear import clear_path, fold_place
from skills.arm.grasps import hand_corners
from skills.arm.planner import ArmPlanner
from skills.arm.skill_plan import SkillPlanError
from skills.base import SkillResult as ArmResult
from skills.context import SkillContext
from skills.registry import SkillRegistry
from skills.replies import arm_state
from skills.running import run_to_end
from skills.table_sides import TableSides
from worlds.bus.link import WorldLink

SURFACE_LABELS = ("table", "counter")
#: The skills the robot runs besides the exploration primitives, by their registered names.
LOOK, STOW = "move_camera", "stow"
#: A hand folding in from where it is may swing this far (m) out and down on the way.
FOLD_REACH_M = 0.3

Record = TypeVar("Record")


class RobotBody:
    """The robot behind ``link`` as the skills see it: one skill run at a time, head and wrist
    frames fused into ``memory``, and base moves.

    Args:
        link: the world link.
        memory: the instance memory every frame is fused into.
        skills: the registry the skills are made from by name.
        skill_timeout_s: how long one skill may run.
    """

    def __init__(self, link: WorldLink, memory: InstanceMemory, skills: SkillRegistry,
                 skill_timeout_s: float) -> None:
        self.link = link
        self.memory = memory
        self.skills = skills
        self.skill_timeout_s = skill_timeout_s
        self.context = SkillContext(link)
        self.home: Pose2D | None = None  # where the robot first looked (`skills.robot.Robot.observe`)
        self.lookout: Pose2D | None = None  # where it takes its head frames from (`skills.robot.Robot.see_table_edge`)
        self.pose: Pose2D | None = None  # where the base is, as the world last said
        self.eye = np.zeros(3)  # the head camera's position at its last frame
        self.head_sees_from = 0.0  # how far ahead of ``home`` its head camera sees a table's top (the strip nearer
        # is where the arm works from the stands, where things are put down last)
        self.skill_times: list[dict[str, Any]] = []  # per skill run: name, ok, planning, execution, wall time
        self.skill_listeners: list[Callable[[str, ArmResult], None]] = []  # told each run's name and result

    def run(self, name: str, **bindings: Any) -> ArmResult:
        """Make the skill registered as ``name`` with ``bindings`` for its ports and run it to its
        end; on a failure after the arm moved, fold it away. The run is kept in `skill_times`, and
        its result given to each of `skill_listeners`.

        Args:
            name: the skill's registered name.
            **bindings: port name -> value.

        Returns:
            The skill's result.

        Raises:
            skills.registry.SkillError: no skill is registered as ``name``, or it cannot be loaded.
            skills.ports.PortError: a port bound wrongly.
        """
        began = time.perf_counter()
        skill = self.skills.create(name, self.context, bindings)
        result = run_to_end(skill, timeout_s=self.skill_timeout_s)
        self.skill_times.append({"skill": name, "ok": result.ok, "planning_ms": round(result.planning_ms, 2),
                                 "execution_s": round(result.execution_s, 3),
                                 "wall_s": round(time.perf_counter() - began, 3),
                                 **({} if result.ok else {"reason": result.reason})})
        for listener in self.skill_listeners:
            listener(name, result)
        if not result.ok and name != STOW and (result.steps_done or result.execution_s > 0):
            self.run(STOW, surface_z=bindings.get("surface_z"))  # out of the way
        return result

    def look(self, camera: str) -> Observation:
        """One frame of ``camera``, fused into the memory.

        Args:
            camera: ``"head"`` or ``"wrist"``.

        Returns:
            The frame.

        Raises:
            QueryFailed: the world sent no frame.
        """
        observation = self.frame(camera)
        self.memory.integrate(observation)
        return observation

    def frame(self, camera: str) -> Observation:
        """One frame of ``camera``, not yet fused into the memory; it updates `pose` (and, for the
        head camera, `eye`).

        Args:
            camera: ``"head"`` or ``"wrist"``.

        Returns:
            The frame.

        Raises:
            QueryFailed: the world sent no frame.
        """
        observation = Observation.from_message(self.link.call("observe", {"camera": camera}))
        self.pose = Pose2D.of(observation.base_pose)
        if camera == "head":
            self.eye = observation.camera_to_world[:3, 3].copy()
        return observation

    def planner(self) -> ArmPlanner:
        """The arm's planner, from the robot's description (asked for once, shared with the skills).

        Returns:
            The planner.
        """
        if self.context.planner is None:
            self.context.planner = ArmPlanner.from_description(self.link.describe().wait().meta)
        return self.context.planner

    def drive(self, pose: Pose2D, routes: Routes | None = None, *, may_fold: bool = True,
              standing_open: Sequence[np.ndarray] = (), fold_first: bool = False, short_of_m: float = 0.0) -> None:
        """Drive to ``pose``: along ``routes`` when they lead there from where the base is, else
        round the table the robot works at where the straight way would cross it (from one of its
        sides to another: `_way_round_the_table`), else straight.
        The arm is left where the last skill left it (backed off ahead of the base), which the
        world checks on the way; a straight drive whose hand would cross a part this robot left
        standing open (``standing_open``) backs away from it first (`skills.arm.drive_clear`). When
        the arm touches something, it is folded in and the base drives on from where it stopped,
        unless ``may_fold`` is false: a door this robot opened still stands open, it swings out
        towards the robot, and the folding arm would sweep through it (the drive fails then, as it
        would have). Folding it first every time would do the same; but with ``fold_first`` (the
        robot coming back to the stand of a door it opened), where the arm, as it is, would touch a
        part standing open once the base is at ``pose``, it is folded in where the drive has backed
        away from the part, if that fold keeps clear of it (`skills.arm.drive_clear.fold_place`).
        Only then: folded on its way elsewhere, the arm later came out of the stowed pose to the
        handle of the door it had left open by no way clear of that door (drawer-door 1094 of
        tuning-wide).

        A drive stopped by a touch ``short_of_m`` or less before ``pose``, facing its way, has got
        there: a door swung open against the base rests where the base stood, and the robot
        coming back to that stand to shut it meets it there (occlusion 1249 of tuning-wide).

        Args:
            pose: where the base is to stand.
            routes: paths over the robot's map, or None to drive straight.
            may_fold: whether the arm may be folded in when it touches something on the way.
            standing_open: point sets of the doors and drawers this robot opened that still stand open.
            fold_first: fold the arm in on the way where it would stand in a part left open.
            short_of_m: how far short of ``pose`` (m) a drive stopped by a touch may end.

        Raises:
            SkillPlanError: the base did not get there.
        """
        reply = self._move_base(pose, routes, standing_open, fold_first)
        if not reply.get("reached") and self._stands_near(pose, short_of_m):
            return
        if not reply.get("reached") and may_fold:
            arm = arm_state(self.link.call("arm_state", {}).meta)
            if not arm["stowed"]:
                self.run(STOW, surface_z=self.surface_z(arm["tcp_pose"][:3, 3], FOLD_REACH_M))
                reply = self._move_base(pose, routes)
        if not reply.get("reached"):
            touched = (reply.get("contact") or {}).get("category", "something")
            raise SkillPlanError(f"the base could not reach ({pose[0]:.2f}, {pose[1]:.2f}, "
                                 f"{math.degrees(pose[2]):.0f}°): it touched {touched}")

    def _stands_near(self, pose: Pose2D, within_m: float) -> bool:
        """Whether the base stands within ``within_m`` of ``pose`` and faces its way (to 1°)."""
        here = self.pose
        if here is None or within_m <= 0:
            return False
        turned = math.remainder(here[2] - pose[2], math.tau)
        return math.dist(here[:2], pose[:2]) <= within_m and abs(turned) <= math.radians(1.0)

    def _move_base(self, pose: Pose2D, routes: Routes | None,
                   standing_open: Sequence[np.ndarray] = (), fold_first: bool = False) -> dict[str, Any]:
        """One move_base command towards ``pose`` (see `drive`); the world's reply."""
        path = [[pose[0], pose[1]]]
        here = self.pose
        if routes is not None and here is not None and math.dist(here[:2], routes.start_xy) < 0.05 \
                and routes.reaches(np.array(pose[:2])):
            path = np.round(routes.to(np.array(pose[:2]))[1:], 3).tolist()
        elif here is not None and len(way := self._way_round_the_table(here, pose)) > 1:
            path = way
        elif here is not None and any(len(points) for points in standing_open):
            arm = arm_state(self.link.call("arm_state", {}).meta)
            if not arm["stowed"]:
                path = [list(xy) for xy in clear_path(here, pose, hand_corners(arm["tcp_pose"]), standing_open)]
                if fold_first:
                    folded = self._fold_on_the_way(pose, path, arm, standing_open)
                    if folded is not None and not folded.get("reached"):
                        return folded
                    path = path if folded is None else path[2:]
        return self._drive_along(path, pose[2])

    def _way_round_the_table(self, here: Pose2D, pose: Pose2D) -> list[list[float]]:
        """The way from ``here`` to ``pose`` round the table the robot works at (`TableSides.way`).
        Where that way is not straight and the arm is out, the base first backs `FOLD_REACH_M`
        straight away from the table and folds the arm in there: the base keeps its heading along
        the way and turns at its end, so an arm held out ahead would sweep the table's corner, and
        an arm folded in where it was, at the table's back, swept a finger into the box it had
        just put down beside the stand (recursive 1268 of tuning-wide).

        Returns:
            The waypoints (x, y) from where the base then stands; one, the goal, where the straight
            way passes or no table is known.

        Raises:
            SkillPlanError: the arm could not be folded in.
        """
        table = self.table_sides()
        if table is None:
            return [[pose[0], pose[1]]]
        way = table.way(np.asarray(here[:2]), np.asarray(pose[:2]))
        if len(way) > 1 and not arm_state(self.link.call("arm_state", {}).meta)["stowed"]:
            ahead = np.array([math.cos(here[2]), math.sin(here[2])])
            self._drive_along([list(np.asarray(here[:2]) - FOLD_REACH_M * ahead)], here[2])
            arm = arm_state(self.link.call("arm_state", {}).meta)
            folded = self.run(STOW, surface_z=self.surface_z(arm["tcp_pose"][:3, 3], FOLD_REACH_M))
            if not folded.ok:
                raise SkillPlanError(f"the arm could not be folded in to drive round the table: {folded.reason}")
            assert self.pose is not None  # the drive's reply said where the base stands
            way = table.way(np.asarray(self.pose[:2]), np.asarray(pose[:2]))
        return [list(xy) for xy in way]

    def table_sides(self) -> TableSides | None:
        """The sides of the table the robot started before: the remembered table or counter
        nearest ``home``, its top's points (within 1.5 cm of its top) as its footprint.

        Returns:
            The sides, or None before the first look, where no such surface is remembered, or where
            ``home`` stands on its footprint.
        """
        if self.home is None:
            return None
        surface = self.nearest_surface(self.home)
        if surface is None:
            return None
        points = surface.points()
        try:
            return TableSides.around(points[points[:, 2] >= surface_top(surface) - 0.015, :2], self.home)
        except ValueError:
            return None

    def nearest_surface(self, pose: Pose2D) -> Instance | None:
        """The remembered table or counter nearest the base standing at ``pose``.

        Args:
            pose: where the base stands (its x, y count).

        Returns:
            The surface, or None where none is remembered.
        """
        surfaces = self.surfaces()
        if not surfaces:
            return None
        base = np.asarray(pose[:2])
        return min(surfaces, key=lambda inst: float(np.min(np.linalg.norm(inst.points()[:, :2] - base, axis=1))))

    def _fold_on_the_way(self, pose: Pose2D, path: list[list[float]], arm: dict[str, Any],
                         standing_open: Sequence[np.ndarray]) -> dict[str, Any] | None:
        """Drive to where the arm is to be folded on ``path`` (`skills.arm.drive_clear.fold_place`)
        and fold it there; the drive's reply, or None when it is not to be folded."""
        assert self.pose is not None
        heading = self.pose[2]
        surface_z = self.surface_z(arm["tcp_pose"][:3, 3], FOLD_REACH_M)
        fold_at = fold_place(self.planner(), arm["q"], path, pose, heading, standing_open, surface_z)
        if fold_at is None:
            return None
        reply = self._drive_along(fold_at, heading)
        if reply.get("reached"):
            self.run(STOW, surface_z=surface_z)
        return reply

    def _drive_along(self, path: list[list[float]], yaw: float) -> dict[str, Any]:
        """One move_base command along ``path`` (x, y waypoints), turning to ``yaw`` at the end; the reply."""
        reply: dict[str, Any] = self.link.call("move_base", {"path": path, "yaw": yaw}).meta
        if isinstance(reply.get("base_pose"), list):
            self.pose = Pose2D.of(reply["base_pose"])
        return reply

    def surfaces(self) -> list[Instance]:
        """Every remembered table and counter.

        Returns:
            The tables, then the counters, in the memory's order.
        """
        return [inst for label in SURFACE_LABELS for inst in self.memory.with_label(label)]

    def surface(self, under: np.ndarray, reach_m: float = 0.0) -> Instance | None:
        """The highest table or counter below the point ``under`` (its top lower) whose footprint
        comes within ``reach_m`` of it.

        Args:
            under: a point in the world frame.
            reach_m: by default 0, the one under it, what the hand must keep above there; with
                `FOLD_REACH_M`, what a hand folding in from there may swing down onto, though it
                is not over it now.

        Returns:
            The surface, or None on the floor (a cabinet standing in a room).
        """
        found = []
        for inst in self.surfaces():
            lo, hi = inst.bounds
            gap = np.maximum(np.maximum(lo[:2] - under[:2], under[:2] - hi[:2]), 0.0)
            top = surface_top(inst)
            if float(np.linalg.norm(gap)) <= reach_m and top < under[2]:
                found.append((top, inst))
        return max(found, key=lambda pair: pair[0], default=(None, None))[1]

    def stood_on(self, inst: Instance) -> Instance | None:
        """The table or counter a remembered thing stands on: the `surface` under the middle of its
        top, below its lowest voxel raised by how far that may sink into what it stands on
        (`SUPPORT_GAP_M` / 2). A bottle's lowest voxel lay 1.5 cm under a table's top, and it was
        put down on nothing: "no table or counter in memory" (occlusion 1156 of tuning-wide).

        Args:
            inst: the thing.

        Returns:
            The surface, or None where none is under it.
        """
        top, bottom = top_grasp_point(inst.points()), float(inst.bounds[0][2])
        return self.surface(np.array([top[0], top[1], bottom + SUPPORT_GAP_M / 2]))

    def surface_z(self, under: np.ndarray, reach_m: float = 0.0) -> float | None:
        """The height of the top of `surface` (``under``, ``reach_m``).

        Args:
            under: a point in the world frame.
            reach_m: see `surface`.

        Returns:
            The top's height, or None on the floor.
        """
        surface = self.surface(under, reach_m)
        return None if surface is None else surface_top(surface)

    def points_near(self, leave_out: Collection[int], outside: Sequence[Box] = (), margin_m: float = 0.0
                    ) -> np.ndarray:
        """The points of everything remembered but the tables and counters (what the arm works
        over, kept above by the plans' surface) and the instances ``leave_out`` (what it works on):
        what the arm is to keep off.

        Args:
            leave_out: ids of instances whose points are not wanted.
            outside: boxes (lo, hi) whose points, within ``margin_m``, are not wanted either (what
                stood under a thing that goes back over it, what stands in a drawer).
            margin_m: how far beyond a box its points may show (the memory's voxels).

        Returns:
            (N, 3) world points.
        """
        surfaces = {inst.id for inst in self.surfaces()}
        points = [inst.points() for inst in self.memory.live() if inst.id not in leave_out and inst.id not in surfaces]
        near = np.vstack(points) if points else np.zeros((0, 3))
        for lo, hi in outside:
            if len(near):
                near = near[~np.all((near >= np.asarray(lo) - margin_m) & (near <= np.asarray(hi) + margin_m), axis=1)]
        return near

    def remembered(self, records: dict[int, Record], inst: Instance) -> Record | None:
        """What ``records`` holds for ``inst``, under its id or an id the memory has since merged into
        it (the drawer seen open is the drawer that was closed); re-keyed to its id.

        Args:
            records: instance id -> what the robot keeps about it.
            inst: the instance.

        Returns:
            Its record, or None.
        """
        for key in list(records):
            if key != inst.id and self.memory.get(key).id == inst.id:
                records[inst.id] = records.pop(key)
        return records.get(inst.id)


def surface_top(surface: Instance) -> float:
    """The height of a table's or counter's top: the 99th percentile of its points' heights.

    Args:
        surface: a remembered table or counter.

    Returns:
        The height (m).
    """
    return float(np.percentile(surface.points()[:, 2], 99))
