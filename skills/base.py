"""Arm skills as py_trees behaviours: plan from the arm's state, then run the plan command by command.

An `ArmSkill` takes what to act on through its input ports (`skills.ports`: a part's geometry, an
object's grasp point, a point to look at; all perceived, world frame) and gives how it went on its
output port ``result`` (a `SkillResult`). Its life, one tick at a time, never blocking for more
than a poll except the planning itself (tens to hundreds of milliseconds of IK):

1. ask the world for the robot's description, once per `SkillContext` (the URDF, the arm's joints and
   limits: the planner is built from the same text the world simulates), and for the arm's state;
2. from the joints and the TCP's world pose, read where the base stands, and plan
   (`skills.arm.planner.ArmPlanner`): a planning error is FAILURE with its reason;
3. send the plan's steps one after another (``arm_trajectory`` with the samples as an array,
   ``gripper``), RUNNING while each is in flight, and check every reply:

   - (`skills.replies.step_problem`) a move that stopped on a contact, or fell short of its target
     by more than `BLOCKED_RAD` (a
     push too gentle for the world to report as a contact still holds the arm back), fails; but a
     touch grasp's approach (`Step.touch`) that stops on touching only what it reaches for, or is
     held back touching nothing else, has arrived (what follows is re-timed from where it stopped),
     and so has the back-off from what the hand let go of, held back by a touch too light to report;
   - closing the gripper must catch what the step expects (a handle, an object), or, closing the
     fingers before a touch grasp's approach, nothing;
   - a move that carries a part (`skills.arm.skill_plan.PartMotion`) measures the part's opening from where
     the TCP, which holds the handle, ended; the part must have gone at least `MIN_PART_SHARE` of
     the way, else "the drawer did not open"; a part held back by its joint's end (a drawer pulled
     past its travel) is fine as long as it got that far, and the opening reached is reported;
   - before the gripper lets go after a motion that ended off its target, the arm is told to hold
     where it really is (else it would spring to the target once free), and after one that moved
     a door or drawer, to hold still for `SETTLE_S` (a drawer pulled against the end of its travel
     rebounds, and let go mid-rebound ran 10 cm back in; one pushed shut sprang 1 cm out); any
     move whose samples no longer start where the arm is gets re-timed from there.

A failure while the hand holds something, or with its fingers closed, first opens the gripper
(RUNNING until it has), so the base is not left tied to furniture and the next grasp starts with
the fingers open, then fails. An object the hand carries is first carried back along the moves
made since it was grasped (`skills.arm.retrace.way_back`), at the careful speed, and so put down
where it was grasped rather than wherever the arm stopped. `skills.running.run_to_end` runs one
skill to its end, for the scene-graph executor, scripts and tests.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np
from py_trees.common import Status

from worlds.bus.codec import Message
from worlds.bus.rpc import PendingReply, QueryFailed
from skills.arm.planner import ArmPlanner
from skills.arm.retrace import way_back
from skills.arm.skill_plan import SkillPlan, SkillPlanError, Step
from skills.context import SkillContext
from skills.ports import Port, PortedSkill, input_port, output_port
from skills.replies import arm_state, step_problem, thing_name, touched_names
from agent.pose import Pose2D

log = logging.getLogger(__name__)

#: A motion that ends further than this from its last sample is held where it is before letting go.
HOLD_RAD = 0.01
#: How long (s) the arm holds still after moving a door or drawer, before letting go of its handle.
SETTLE_S = 0.3
#: Re-time a move whose first sample is further than this from where the arm is.
RETIME_RAD = 0.005
#: Seconds allowed for a command beyond its motion's duration (the world runs faster than real time).
COMMAND_SLACK_S = 30.0
#: Fingers closer than this (m between them) are closed: a failure opens them again.
FINGERS_CLOSED_M = 0.01
@dataclass(frozen=True, eq=False)
class SkillResult:
    """How a skill went. ``ok`` and ``reason`` (why it failed; empty on success) as the ACSG's
    executor wants them; ``held``: what the gripper holds at the end (a world label or None);
    ``tcp_pose``: the TCP's final world pose; ``achieved``: the part's opening it was left at (m or
    rad; doors and drawers). ``planning_ms`` / ``execution_s``: wall time of planning (the plan call,
    whether it succeeded or not) and of running the steps; ``steps_done`` of ``steps``;
    ``contacts``: what the arm touched on the way; ``info``: the plan's figures (IK and trajectory
    time, motion seconds, grasp or camera pose...); ``joints``: the arm's joint positions in the
    last reply (rad or m, in the planner's ``joint_names`` order), None when no reply carried them;
    ``unplanned``: it failed because no plan was found (nothing moved), which callers tell apart
    from a move that went wrong."""

    ok: bool
    reason: str = ""
    skill: str = ""
    held: dict[str, Any] | None = None
    tcp_pose: np.ndarray | None = None
    achieved: float | None = None
    planning_ms: float = 0.0
    execution_s: float = 0.0
    steps_done: int = 0
    steps: int = 0
    contacts: list[dict[str, Any]] = field(default_factory=list)
    info: dict[str, Any] = field(default_factory=dict)
    joints: np.ndarray | None = None
    unplanned: bool = False


class ArmSkill(PortedSkill):
    """Base of the arm primitives: subclasses set `skill_name`, add their `ports` to these, and
    implement `plan` from the inputs."""

    ports: tuple[Port, ...] = (
        input_port("surface_z", float, "the top of what the furniture or object stands on, which the hand "
                   "keeps above (m)", default=None),
        input_port("label", str, "names the target in messages (\"drawer 12\")", default=""),
        output_port("result", SkillResult, "how the skill went"),
    )

    def __init__(self, context: SkillContext, name: str | None = None, bindings: Mapping[str, Any] | None = None,
                 *, timeout_s: float = 10.0) -> None:
        """Args:
            context: the world link, and the arm's planner shared by the skills run in it.
            name: the node's name (default: the class name).
            bindings: the ports' values or ``"{key}"``s (see `skills.ports`).
            timeout_s: how long a query for the arm's state or the description may take.
        """
        super().__init__(context, name, bindings)
        self.timeout_s = timeout_s
        self._wake: Callable[[], None] | None = None
        self._reset()

    # -- for subclasses ------------------------------------------------------------------------

    def plan(self, planner: ArmPlanner, q: np.ndarray, base_pose: Pose2D,
             inputs: Mapping[str, Any]) -> SkillPlan:
        """The steps of this skill.

        Args:
            planner: the arm's planner.
            q: the arm's joints now.
            base_pose: where the base stands (x, y, yaw).
            inputs: the input ports' values.

        Returns:
            The plan.

        Raises:
            SkillPlanError: (or ValueError) naming what is missing or unreachable.
        """
        raise NotImplementedError

    # -- py_trees ------------------------------------------------------------------------------

    def _reset(self) -> None:
        self._phase = "describe"
        self._pending: PendingReply | None = None
        self._plan: SkillPlan | None = None
        self._steps: list[Step] = []
        self._index = 0
        self._last: dict[str, Any] | None = None  # the latest arm state any reply carried
        self._achieved: float | None = None
        self._contacts: list[dict[str, Any]] = []
        self._run_began: float | None = None
        self._planning_ms = 0.0
        self._holding_still = False
        self._failure = ""
        self._request_error = ""
        self._unplanned = False

    def setup(self, **kwargs: Any) -> None:
        """Take the tree's ``wake``, if it hands one: each reply of the world then wakes the tree.

        Args:
            **kwargs: py_trees' setup arguments; ``wake`` is called once a reply is in.
        """
        self._wake = kwargs.get("wake")

    def initialise(self) -> None:
        super().initialise()
        self._reset()
        try:
            if self.context.planner is None:
                self._pending = self.link.describe(self.timeout_s, self._wake)
            else:
                self._phase, self._pending = "state", self._ask("arm_state", {})
        except QueryFailed as error:
            self._pending = None
            self._request_error = str(error)

    def update(self) -> Status:
        if self.input_problem():
            return self._fail(self.input_problem())
        if self._pending is None:
            return self._fail(self._request_error or "no command in flight")
        try:
            message = self._pending.poll()
        except QueryFailed as error:
            if self._phase == "release":
                return self._failed(f"{self._failure}; but letting go failed: {error}")
            return self._fail(f"{self._doing()}: {error}")
        if message is None:
            self.feedback_message = f"{self._doing()} ({self._pending.elapsed_s:.1f} s)"
            return Status.RUNNING
        self._pending = None
        if self._phase == "describe":
            return self._described(message)
        if self._phase == "state":
            return self._planned(message)
        if self._phase == "release":
            return self._released(message)
        if self._phase == "carry back":
            return self._carried_back(message)
        return self._step_done(message)

    def terminate(self, new_status: Status) -> None:
        if new_status == Status.INVALID and self._pending is not None:
            log.info("%s interrupted while %s", self.name, self._doing())
        self._pending = None

    # -- phases --------------------------------------------------------------------------------

    def _described(self, message: Message) -> Status:
        try:
            self.context.planner = ArmPlanner.from_description(message.meta)
        except (ValueError, KeyError) as error:
            return self._fail(f"robot description: {error}")
        self._phase = "state"
        return self._send(lambda: self._ask("arm_state", {}))

    def _planned(self, message: Message) -> Status:
        planner = self.context.planner
        assert planner is not None
        began = time.perf_counter()
        try:
            self._last = arm_state(message.meta)
            q, tcp = self._last["q"], self._last["tcp_pose"]
            base_pose = planner.base_pose_from(q, tcp)
            self._plan = self.plan(planner, q, base_pose, self.inputs)
        except (SkillPlanError, ValueError) as error:
            self._planning_ms = 1e3 * (time.perf_counter() - began)
            self._unplanned = True
            return self._fail(f"plan: {error}")
        self._planning_ms = 1e3 * (time.perf_counter() - began)
        log.info("%s", self._plan.describe())
        self._steps = list(self._plan.steps)
        self._phase, self._index = "run", 0
        self._run_began = time.perf_counter()
        return self._next()

    def _next(self) -> Status:
        """Send the next step, or finish."""
        planner = self.context.planner
        assert planner is not None and self._last is not None
        if self._index >= len(self._steps):
            return self._succeed()
        step = self._steps[self._index]
        if step.kind == "gripper":
            moved_part = self._index > 0 and self._steps[self._index - 1].part_motion is not None
            off_target = self._last["final_error"] > HOLD_RAD
            if step.action == "open" and (off_target or moved_part) and not self._holding_still:
                self._holding_still = True  # hold where the arm is before letting go
                hold = planner.hold(self._last["q"], SETTLE_S if moved_part else 0.0)
                return self._send(lambda: self._send_move(hold))
            self._holding_still = False
            return self._send(lambda: self._ask("gripper", {"action": step.action}))
        if step.samples is not None and np.abs(step.samples[0] - self._last["q"]).max() > RETIME_RAD:
            try:
                step = planner.retime(step, self._last["q"])
            except (RuntimeError, ValueError) as error:
                return self._fail(f"{step.name}: re-timing it from where the arm is: {error}")
            self._steps[self._index] = step
        return self._send(lambda: self._send_move(step))

    def _send_move(self, step: Step) -> PendingReply:
        assert step.samples is not None
        timeout = step.duration_s + COMMAND_SLACK_S
        meta = {"dt": step.dt, "stop_on_contact": step.stop_on_contact, "stop_on_new_contact": step.stop_on_new_contact}
        return self._ask("arm_trajectory", meta, timeout,
                         arrays={"samples": np.ascontiguousarray(step.samples, dtype=np.float64)})

    def _ask(self, verb: str, meta: dict[str, Any], timeout_s: float | None = None,
             arrays: dict[str, np.ndarray] | None = None) -> PendingReply:
        """Send ``verb`` to the world; its reply wakes the tree (`setup`'s ``wake``), if any."""
        return self.link.request(verb, meta, timeout_s or self.timeout_s, arrays, self._wake)

    def _send(self, request: Any) -> Status:
        try:
            self._pending = request()
        except (QueryFailed, ValueError) as error:
            return self._fail(f"{self._doing()}: {error}")
        self.feedback_message = self._doing()
        return Status.RUNNING

    def _step_done(self, message: Message) -> Status:
        try:
            state = arm_state(message.meta)
        except ValueError as error:
            return self._fail(f"{self._doing()}: {error}")
        previous, self._last = self._last, state
        if self._holding_still and self._steps[self._index].kind == "gripper":
            return self._next()  # the hold is done; now let go
        step = self._steps[self._index]
        if step.kind != "gripper":
            self._contacts += state["contacts"]
        problem, achieved = step_problem(step, state, previous)
        if achieved is not None:
            self._achieved = achieved
        if problem:
            return self._fail(f"{step.name}: {problem}")
        self._index += 1
        return self._next()

    # -- ends ----------------------------------------------------------------------------------

    def _doing(self) -> str:
        if self._phase == "describe":
            return "asking for the robot's description"
        if self._phase == "state":
            return "asking for the arm's state"
        if self._phase == "release":
            return "letting go after a failure"
        if self._phase == "carry back":
            return "carrying the object back to where it was grasped after a failure"
        if self._holding_still:
            return "holding the arm still before letting go"
        if self._index < len(self._steps):
            step = self._steps[self._index]
            return f"step {self._index + 1}/{len(self._steps)} {step.name}"
        return "done"

    def _result(self, ok: bool, reason: str) -> SkillResult:
        plan = self._plan
        execution = time.perf_counter() - self._run_began if self._run_began is not None else 0.0
        info: dict[str, Any] = {}
        if plan is not None:
            info = {**plan.info, "ik_ms": plan.ik_ms, "ik_solves": plan.ik_solves,
                    "trajectory_ms": plan.trajectory_ms, "motion_s": plan.duration_s, "base_pose": plan.base_pose}
        last = self._last or {}
        return SkillResult(ok, reason, self.skill_name, last.get("held"), last.get("tcp_pose"), self._achieved,
                           self._planning_ms, execution, self._index,
                           len(self._steps), list(self._contacts), info, last.get("q"), self._unplanned)

    def _succeed(self) -> Status:
        result = self._result(True, "")
        self.set_output("result", result)
        self.feedback_message = self.summary(result)
        return Status.SUCCESS

    def _fail(self, reason: str) -> Status:
        reason = f"{self.skill_name or self.name}: {reason}"
        last = self._last
        if self._phase == "run" and last is not None and (last.get("held") is not None
                                                          or last["gripper_width"] < FINGERS_CLOSED_M):
            # do not stay tied to furniture, nor start the next grasp with closed fingers: open
            # first, then fail (see `_released`); an object carried goes back where it was grasped
            held = last.get("held")
            back = self._carry_back() if held is not None else None
            if back is not None:
                self._phase, self._failure = "carry back", reason
                return self._send(lambda: self._send_move(back))
            return self._let_go(reason)
        return self._failed(reason)

    def _carry_back(self) -> Step | None:
        """The move carrying the object the hand holds back along the moves made since it was
        grasped (`way_back`), from where the arm stopped; None when the hand grasped no object in
        this plan (a handle is let go of where it is)."""
        planner = self.context.planner
        grasps = [k for k, step in enumerate(self._steps[:self._index])
                  if step.kind == "gripper" and step.action == "close" and step.expect_held == "object"]
        if planner is None or not grasps or self._last is None:
            return None
        moves = [step for step in self._steps[grasps[-1] + 1:self._index + 1] if step.samples is not None]
        if not moves:
            return None
        waypoints = planner.kin.clip(way_back(moves, self._last["q"]))
        return Step("move", "carry back to where it was grasped", planner.samples(waypoints, planner.careful_speed),
                    planner.dt, waypoints, planner.careful_speed, stop_on_new_contact=True)

    def _let_go(self, reason: str) -> Status:
        """Open the gripper, then fail with ``reason`` (and what was let go of)."""
        held = (self._last or {}).get("held")
        self._phase, self._failure = "release", reason if held is None else f"{reason} (let go of {thing_name(held)})"
        try:
            self._pending = self._ask("gripper", {"action": "open"})
        except QueryFailed as error:
            return self._failed(f"{self._failure}; but letting go failed: {error}")
        self.feedback_message = self._doing()
        return Status.RUNNING

    def _carried_back(self, message: Message) -> Status:
        """The object is back where it was grasped, or as near as the move got before it met
        something it did not start against: let go of it there."""
        self._take_state(message)
        back = "to where it was grasped"
        if self._last is not None and self._last["stopped_on_contact"]:
            back = f"until it met {touched_names(self._last['contacts'])}"
        return self._let_go(f"{self._failure} (carried back {back})")

    def _released(self, message: Message) -> Status:
        self._take_state(message)
        return self._failed(self._failure)

    def _take_state(self, message: Message) -> None:
        """Keep the arm state a reply after a failure carries, if it is well formed (the failure
        is reported either way)."""
        try:
            self._last = arm_state(message.meta)
        except ValueError:
            pass

    def _failed(self, reason: str) -> Status:
        self._phase = "failed"
        result = self._result(False, reason)
        self.set_output("result", result)
        self.feedback_message = reason
        self._pending = None
        log.info("%s", reason)
        return Status.FAILURE

    def summary(self, result: SkillResult) -> str:
        """One line for the feedback message of a skill that succeeded (with the grasp it took, if any).

        Args:
            result: how the skill went.

        Returns:
            The line, e.g. ``"open: done in 2.1 s (1.8 s of motion, planned in 120 ms)"``.
        """
        grasp = f", {result.info['grasp']} grasp" if "grasp" in result.info else ""
        return (f"{self.skill_name}: done in {result.execution_s:.1f} s ({result.info.get('motion_s', 0.0):.1f} s "
                f"of motion, planned in {result.planning_ms:.0f} ms{grasp})")
