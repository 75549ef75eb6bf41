"""Arm skills as py_trees behaviours: plan from the arm's state, then run the plan command by command.

An `ArmSkill` reads what to act on from the blackboard key `SKILL_TARGET` (a `SkillTarget`: a part's
geometry, an object's grasp point, a point to look at; all perceived, world frame) and writes how it
went to `SKILL_RESULT` (a `SkillResult`). Its life, one tick at a time, never blocking for more
than a poll except the planning itself (tens to hundreds of milliseconds of IK):

1. ask the world for the robot's description, once per `WorldLink` (the URDF, the arm's joints and
   limits: the planner is built from the same text the world simulates), and for the arm's state;
2. from the joints and the TCP's world pose, read where the base stands, and plan
   (`skills.arm.plan.ArmPlanner`): a planning error is FAILURE with its reason;
3. send the plan's steps one after another (``arm_trajectory`` with the samples as an array,
   ``gripper``), RUNNING while each is in flight, and check every reply:

   - a move that stopped on a contact, or fell short of its target by more than `BLOCKED_RAD` (a
     push too gentle for the world to report as a contact still holds the arm back), fails; but a
     touch grasp's approach (`Step.touch`) that stops on touching only what it reaches for, or is
     held back touching nothing else, has arrived (what follows is re-timed from where it stopped);
   - closing the gripper must catch what the step expects (a handle, an object), or, closing the
     fingers before a touch grasp's approach, nothing;
   - a move that carries a part (`skills.arm.plan.PartMotion`) measures the part's opening from where
     the TCP, which holds the handle, ended; the part must have gone at least `MIN_PART_SHARE` of
     the way, else "the drawer did not open"; a part held back by its joint's end (a drawer pulled
     past its travel) is fine as long as it got that far, and the opening reached is reported;
   - before the gripper lets go after a motion that ended off its target, the arm is told to hold
     where it really is (else it would spring to the target once free), and any move whose
     samples no longer start where the arm is gets re-timed from there.

A failure while the hand holds something, or with its fingers closed, first opens the gripper
(RUNNING until it has), so the base is not left tied to furniture and the next grasp starts with
the fingers open, then fails. `run_skill` ticks a one-behaviour tree to the
end, for scripts and tests.
"""

from __future__ import annotations

import logging
import time
import weakref
from dataclasses import dataclass, field, replace
from typing import Any, ClassVar

import numpy as np
import py_trees
from py_trees.common import Access, Status

from worlds.bus.codec import Message
from worlds.bus.rpc import PendingReply, QueryFailed
from agent.perception.geometry import PartGeometry
from worlds.bus.link import WorldLink
from skills.arm.planner import ArmPlanner
from skills.arm.skill_plan import SkillPlan, SkillPlanError, Step

log = logging.getLogger(__name__)

SKILL_TARGET = "skill_target"  # SkillTarget: what the next arm skill acts on
SKILL_RESULT = "skill_result"  # SkillResult: how the last arm skill went

#: A move that ends further than this (rad or m, any joint) from its last sample was held back.
BLOCKED_RAD = 0.03
#: A motion that ends further than this from its last sample is held where it is before letting go.
HOLD_RAD = 0.01
#: Re-time a move whose first sample is further than this from where the arm is.
RETIME_RAD = 0.005
#: The share of a planned opening or closing the part must make for the skill to count it done.
MIN_PART_SHARE = 0.6
#: Seconds allowed for a command beyond its motion's duration (the world runs faster than real time).
COMMAND_SLACK_S = 30.0
#: Fingers closer than this (m between them) are closed: a failure opens them again.
FINGERS_CLOSED_M = 0.01
#: What a grasp holds when it holds what the step expects, and what it says otherwise.
_EXPECTED = {
    "handle": (lambda label: label.get("category") == "handle", "not a handle"),
    "object": (lambda label: label.get("link") is None, "part of a piece of furniture, not an object"),
}


@dataclass(frozen=True, eq=False)
class SkillTarget:
    """What an arm skill acts on, perceived, in the world frame (metres, radians).

    - doors and drawers: ``geometry`` (the part as seen closed, `agent.perception.geometry`), and
      ``amount``: how far to open it (OpenDoor, OpenDrawer; default `DEFAULT_AMOUNT`) or how far it
      stands open now (CloseDoor, CloseDrawer; required). With ``geometry_is_open`` the geometry was
      taken with the part open by ``amount``. ``surface_z``: the top of what the furniture stands
      on, which the hand keeps above (optional);
    - picks: ``object_point`` (the top-down grasp point, e.g. `top_grasp_point` of its points),
      ``object_extent`` (dx, dy, dz of its points) and ``place_point``: where the grasp point is to
      be once the object stands at its destination (PickAway: an idle spot; PickBack: where it was);
    - the wrist camera: ``look_point`` and optionally ``standoff_m`` / ``pitch_deg`` (LookAt).

    ``label`` names the target in messages ("drawer 12").
    """

    geometry: PartGeometry | None = None
    amount: float | None = None
    geometry_is_open: bool = False
    surface_z: float | None = None
    object_point: np.ndarray | None = None
    object_extent: np.ndarray | None = None
    place_point: np.ndarray | None = None
    look_point: np.ndarray | None = None
    standoff_m: float | None = None
    pitch_deg: float | None = None
    label: str = ""


@dataclass(frozen=True, eq=False)
class SkillResult:
    """How a skill went. ``ok`` and ``reason`` (why it failed; empty on success) as the ACSG's
    executor wants them; ``held``: what the gripper holds at the end (a world label or None);
    ``tcp_pose``: the TCP's final world pose; ``achieved``: the part's opening it was left at (m or
    rad; doors and drawers). ``planning_ms`` / ``execution_s``: wall time of planning (the plan call,
    whether it succeeded or not) and of running the steps; ``steps_done`` of ``steps``; ``contacts``: what the arm touched on the way; ``info``:
    the plan's figures (IK and trajectory time, motion seconds, grasp or camera pose...)."""

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


#: One planner per world link: building the kinematics takes ~20 ms, the description a query.
_PLANNERS: weakref.WeakKeyDictionary[WorldLink, ArmPlanner] = weakref.WeakKeyDictionary()


class ArmSkill(py_trees.behaviour.Behaviour):
    """Base of the arm primitives: subclasses set `skill_name` and implement `plan`."""

    skill_name: ClassVar[str] = ""

    def __init__(self, link: WorldLink, name: str | None = None, *, planner: ArmPlanner | None = None,
                 timeout_s: float = 10.0) -> None:
        super().__init__(name or type(self).__name__)
        self.link = link
        self.timeout_s = timeout_s
        self._planner = planner
        self.blackboard = self.attach_blackboard_client(name=self.name)
        self.blackboard.register_key(SKILL_TARGET, access=Access.READ)
        self.blackboard.register_key(SKILL_RESULT, access=Access.WRITE)
        self._reset()

    # -- for subclasses ------------------------------------------------------------------------

    def plan(self, planner: ArmPlanner, q: np.ndarray, base_pose: tuple[float, float, float],
             target: SkillTarget) -> SkillPlan:
        """The steps of this skill from joints ``q`` with the base at ``base_pose``; raise
        SkillPlanError (or ValueError) naming what is missing or unreachable."""
        raise NotImplementedError

    # -- py_trees ------------------------------------------------------------------------------

    def _reset(self) -> None:
        self._phase = "describe"
        self._pending: PendingReply | None = None
        self._plan: SkillPlan | None = None
        self._steps: list[Step] = []
        self._index = 0
        self._last: dict[str, Any] | None = None  # the latest arm state any reply carried
        self._target: Any = None
        self._achieved: float | None = None
        self._contacts: list[dict[str, Any]] = []
        self._run_began: float | None = None
        self._planning_ms = 0.0
        self._holding_after_error = False
        self._failure = ""
        self._request_error = ""

    def initialise(self) -> None:
        self._reset()
        self._target = self.blackboard.get(SKILL_TARGET) if self.blackboard.exists(SKILL_TARGET) else None
        if self._planner is None:
            self._planner = _PLANNERS.get(self.link)
        try:
            if self._planner is None:
                self._pending = self.link.describe(self.timeout_s)
            else:
                self._phase, self._pending = "state", self.link.request("arm_state", {}, self.timeout_s)
        except QueryFailed as error:
            self._pending = None
            self._request_error = str(error)

    def update(self) -> Status:
        if not isinstance(self._target, SkillTarget):
            found = "nothing" if self._target is None else type(self._target).__name__
            return self._fail(f"no target: the blackboard key {SKILL_TARGET!r} holds {found}, not a SkillTarget")
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
        return self._step_done(message)

    def terminate(self, new_status: Status) -> None:
        if new_status == Status.INVALID and self._pending is not None:
            log.info("%s interrupted while %s", self.name, self._doing())
        self._pending = None

    # -- phases --------------------------------------------------------------------------------

    def _described(self, message: Message) -> Status:
        try:
            self._planner = ArmPlanner.from_description(message.meta)
        except (ValueError, KeyError) as error:
            return self._fail(f"robot description: {error}")
        _PLANNERS[self.link] = self._planner
        self._phase = "state"
        return self._send(lambda: self.link.request("arm_state", {}, self.timeout_s))

    def _planned(self, message: Message) -> Status:
        assert self._planner is not None and self._target is not None
        began = time.perf_counter()
        try:
            self._last = arm_state(message.meta)
            q, tcp = self._last["q"], self._last["tcp_pose"]
            base_pose = self._planner.base_pose_from(q, tcp)
            self._plan = self.plan(self._planner, q, base_pose, self._target)
        except (SkillPlanError, ValueError) as error:
            self._planning_ms = 1e3 * (time.perf_counter() - began)
            return self._fail(f"plan: {error}")
        self._planning_ms = 1e3 * (time.perf_counter() - began)
        log.info("%s", self._plan.describe())
        self._steps = list(self._plan.steps)
        self._phase, self._index = "run", 0
        self._run_began = time.perf_counter()
        return self._next()

    def _next(self) -> Status:
        """Send the next step, or finish."""
        assert self._planner is not None and self._last is not None
        if self._index >= len(self._steps):
            return self._succeed()
        step = self._steps[self._index]
        if step.kind == "gripper":
            if step.action == "open" and self._last["final_error"] > HOLD_RAD and not self._holding_after_error:
                self._holding_after_error = True  # hold where the arm is before letting go
                hold = self._planner.hold(self._last["q"])
                return self._send(lambda: self._send_move(hold))
            self._holding_after_error = False
            return self._send(lambda: self.link.request("gripper", {"action": step.action}, self.timeout_s))
        if step.samples is not None and np.abs(step.samples[0] - self._last["q"]).max() > RETIME_RAD:
            try:
                step = self._planner.retime(step, self._last["q"])
            except (RuntimeError, ValueError) as error:
                return self._fail(f"{step.name}: re-timing it from where the arm is: {error}")
            self._steps[self._index] = step
        return self._send(lambda: self._send_move(step))

    def _send_move(self, step: Step) -> PendingReply:
        assert step.samples is not None
        timeout = step.duration_s + COMMAND_SLACK_S
        return self.link.request("arm_trajectory", {"dt": step.dt, "stop_on_contact": step.stop_on_contact},
                                 timeout, arrays={"samples": np.ascontiguousarray(step.samples, dtype=np.float64)})

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
        if self._holding_after_error and self._steps[self._index].kind == "gripper":
            return self._next()  # the hold is done; now let go
        step = self._steps[self._index]
        problem = self._check(step, state, previous)
        if problem:
            return self._fail(f"{step.name}: {problem}")
        self._index += 1
        return self._next()

    def _check(self, step: Step, state: dict[str, Any], previous: dict[str, Any] | None) -> str:
        """Why the reply to ``step`` means the skill failed ("" when it is fine)."""
        held = state["held"]
        if step.kind == "gripper":
            if step.action == "close" and step.expect_held is None:
                return "" if held is None else f"the fingers caught {_name(held)} closing before the approach"
            if step.action == "close":
                if held is None:
                    return f"the gripper closed on nothing ({state['gripper_width'] * 1000:.0f} mm between the fingers)"
                expected, otherwise = _EXPECTED[step.expect_held]
                if not expected(held):
                    return f"the gripper holds {_name(held)}, {otherwise}"
            elif held is not None:
                return f"the gripper still holds {_name(held)} after opening"
            return ""
        contacts = state["contacts"]
        self._contacts += contacts
        stopped = state["stopped_on_contact"] or state["final_error"] > BLOCKED_RAD
        if step.touch and stopped and all(_EXPECTED[step.touch][0](c) for c in contacts):
            return ""  # a touch grasp's approach found what it reaches for (or a touch too light to report)
        if state["stopped_on_contact"]:
            touched = ", ".join(f"{_name(c)} ({c.get('robot_link')})" for c in contacts) or "something"
            return f"stopped on contact with {touched}"
        if step.part_motion is not None:
            motion = step.part_motion
            achieved = motion.opening(state["tcp_pose"][:3, 3])
            self._achieved = achieved
            want = motion.end - motion.start
            kind = motion.geometry.kind
            if previous is not None and previous["held"] is not None and held is None:
                return f"the gripper lost the {kind}'s handle"
            if (achieved - motion.start) / want < MIN_PART_SHARE:
                verb = "open" if want > 0 else "close"
                return (f"the {kind} did not {verb}: its handle went {abs(achieved - motion.start):.3f} "
                        f"{motion.unit} of the {abs(want):.3f} {motion.unit} planned")
            return ""
        if state["final_error"] > BLOCKED_RAD:
            return (f"the arm stopped {state['final_error']:.3f} rad short of its target: something held it back "
                    f"(a touch too light for the world to report as a contact)")
        if previous is not None and previous["held"] is not None and held is None:
            return f"the gripper lost {_name(previous['held'])}"
        return ""

    # -- ends ----------------------------------------------------------------------------------

    def _doing(self) -> str:
        if self._phase == "describe":
            return "asking for the robot's description"
        if self._phase == "state":
            return "asking for the arm's state"
        if self._phase == "release":
            return "letting go after a failure"
        if self._holding_after_error:
            return "holding the arm where it stopped"
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
                           len(self._steps), list(self._contacts), info)

    def _succeed(self) -> Status:
        result = self._result(True, "")
        self.blackboard.set(SKILL_RESULT, result)
        self.feedback_message = self.summary(result)
        return Status.SUCCESS

    def _fail(self, reason: str) -> Status:
        reason = f"{self.skill_name or self.name}: {reason}"
        last = self._last
        if self._phase == "run" and last is not None and (last.get("held") is not None
                                                          or last["gripper_width"] < FINGERS_CLOSED_M):
            # do not stay tied to furniture, nor start the next grasp with closed fingers: open
            # first, then fail (see `_released`)
            held = last.get("held")
            self._phase, self._failure = "release", reason if held is None else f"{reason} (let go of {_name(held)})"
            try:
                self._pending = self.link.request("gripper", {"action": "open"}, self.timeout_s)
            except QueryFailed as error:
                return self._failed(f"{self._failure}; but letting go failed: {error}")
            self.feedback_message = self._doing()
            return Status.RUNNING
        return self._failed(reason)

    def _released(self, message: Message) -> Status:
        try:
            self._last = arm_state(message.meta)
        except ValueError:
            pass
        return self._failed(self._failure)

    def _failed(self, reason: str) -> Status:
        self._phase = "failed"
        result = self._result(False, reason)
        self.blackboard.set(SKILL_RESULT, result)
        self.feedback_message = reason
        self._pending = None
        log.info("%s", reason)
        return Status.FAILURE

    def summary(self, result: SkillResult) -> str:
        """One line for the feedback message of a skill that succeeded (with the grasp it took, if any)."""
        grasp = f", {result.info['grasp']} grasp" if "grasp" in result.info else ""
        return (f"{self.skill_name}: done in {result.execution_s:.1f} s ({result.info.get('motion_s', 0.0):.1f} s "
                f"of motion, planned in {result.planning_ms:.0f} ms{grasp})")


def arm_state(meta: dict[str, Any]) -> dict[str, Any]:
    """The fields of an arm reply, checked: joints, TCP pose, held, stowed, and a motion's errors and contacts."""
    try:
        q = np.asarray(meta["positions"], dtype=float)
        tcp = np.asarray(meta["tcp_pose"], dtype=float)
    except (KeyError, TypeError, ValueError) as error:
        raise ValueError(f"arm reply: missing or malformed {error}") from None
    if q.ndim != 1 or tcp.shape != (4, 4) or not (np.all(np.isfinite(q)) and np.all(np.isfinite(tcp))):
        raise ValueError("arm reply: positions must be a vector and tcp_pose a finite 4x4 matrix")
    held = meta.get("held")
    return {
        "q": q,
        "tcp_pose": tcp,
        "held": held if isinstance(held, dict) else None,
        "gripper_width": float(meta.get("gripper_width", 0.0)),
        "stowed": bool(meta.get("stowed", False)),
        "final_error": float(meta.get("final_error", 0.0)),
        "stopped_on_contact": bool(meta.get("stopped_on_contact", False)),
        "contacts": [c for c in meta.get("contacts", []) if isinstance(c, dict)],
    }


def _name(label: dict[str, Any]) -> str:
    return f"{label.get('category', 'something')} {label.get('id', '')}".strip()


def run_skill(skill: type[ArmSkill] | ArmSkill, link: WorldLink, target: SkillTarget, timeout_s: float = 120.0,
              tick_s: float = 0.002) -> SkillResult:
    """Run one skill to its end in a tree of its own, ticking every ``tick_s``; its `SkillResult`.

    ``skill`` is a skill class (made with ``link``) or a skill already made. A tick that raises, or
    a skill still running after ``timeout_s``, gives a failed result saying so.
    """
    behaviour = skill(link) if isinstance(skill, type) else skill
    client = py_trees.blackboard.Client(name=f"run_skill {behaviour.name}")
    client.register_key(SKILL_TARGET, access=Access.WRITE)
    client.register_key(SKILL_RESULT, access=Access.WRITE)
    client.set(SKILL_TARGET, target)
    client.set(SKILL_RESULT, None)
    tree = py_trees.trees.BehaviourTree(behaviour)
    deadline = time.monotonic() + timeout_s
    name = getattr(behaviour, "skill_name", "") or behaviour.name
    try:
        while True:
            try:
                tree.tick()
            except Exception as error:  # a bug in a tick: fail with it rather than hang
                log.exception("%s raised", name)
                behaviour.stop(Status.INVALID)
                return SkillResult(False, f"{name}: {type(error).__name__}: {error}", name)
            if behaviour.status != Status.RUNNING:
                break
            if time.monotonic() > deadline:
                behaviour.stop(Status.INVALID)
                return SkillResult(False, f"{name}: still running after {timeout_s:.0f} s", name)
            time.sleep(tick_s)
        result = client.get(SKILL_RESULT)
        if not isinstance(result, SkillResult):
            ok = behaviour.status == Status.SUCCESS
            result = SkillResult(ok, "" if ok else behaviour.feedback_message, name)
        return result
    finally:
        client.unregister_key(SKILL_TARGET)
        client.unregister_key(SKILL_RESULT)


def with_defaults(target: SkillTarget, **values: Any) -> SkillTarget:
    """``target`` with the given fields filled in where it leaves them None."""
    missing = {key: value for key, value in values.items() if getattr(target, key) is None}
    return replace(target, **missing) if missing else target
