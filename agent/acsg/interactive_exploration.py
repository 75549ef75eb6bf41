"""Interactive exploration (RoboEXP Algorithm 1, with Algorithms 2 and 3) over an action stack.

Every object in the unexplored set U is judged by the proposer. An "open" on a piece of storage
becomes one open action per door or drawer of it (a part without parts is opened itself); a
"pick" becomes one pick action. Each action goes on the LIFO action stack as a pair, the undo
first and the action above it:

    pick  ->  push pick_back, push pick_away
    open  ->  push close,     push open

so the action runs, what it reveals is judged at once and its own pairs land on top of the
undo, and only when all of that is done is the action undone. Depth first falls out of the stack:
a Matryoshka doll is lifted, the smaller doll found under it is lifted and put back, then the big
one is put back; a drawer is closed only after the box found in it was lifted and put back. Every
action found is undone, which is the paper's greedy return of the scene to its start state.

Before an action runs the verifier is asked once which objects are in its way. If any are,
Algorithm 3 adds a pick action per blocker with a precondition edge to the blocked action, and the
stack is rearranged (the blocked action's undo was on top, paired with it):

    before: [... close]                       (open was just popped)
    after:  [... pick_back b1, pick_back b2, close, open, pick_away b2, pick_away b1]

giving pick_away b1 -> pick_away b2 -> open -> (what it reveals) -> close -> pick_back b2 ->
pick_back b1: the blockers stay away until the door is shut again, which is what a door that
swings through a bottle's place needs. (The reference code opens and closes in one skill, so its
pick_back sits right under the open; splitting the two keeps the same nesting.)

Objects seen in one observation are explored in the order perceived: their pairs are pushed in
reverse so the first object's action runs first. A failed action is marked failed and its undo
is dropped (nothing to undo); a failed undo leaves the scene changed and says so in the notes.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from agent.acsg.graph import ACSG, CycleError
from agent.acsg.interfaces import (
    PROPOSALS,
    DecisionContext,
    DecisionModule,
    Detection,
    Perception,
    SkillCall,
    SkillExecutor,
    object_id,
)
from agent.acsg.nodes import ACSGError, ActionNode, ObjectNode
from agent.acsg.primitives import PICK_AWAY, open_primitive

#: Labels of parts that open; a part with a handle of its own opens too, whatever its label.
OPENABLE_PARTS = frozenset({"door", "drawer", "flap", "lid"})


@dataclass(frozen=True)
class InteractiveExploreConfig:
    max_steps: int = 1000  # executed primitives before exploration gives up (truncated)
    reward_lambda: float = 0.1  # λ of R = ΔV + max(0, −ΔU) − λ, 0 < λ < 1

    def __post_init__(self) -> None:
        if self.max_steps < 1:
            raise ValueError(f"explore.max_steps: {self.max_steps} must be at least 1")
        if not 0.0 < self.reward_lambda < 1.0:
            raise ValueError(f"explore.reward_lambda: {self.reward_lambda} must lie in (0, 1)")


@dataclass(frozen=True)
class LogEntry:
    """One executed primitive: what, on which object, whether it worked, what it revealed, its reward."""

    step: int
    primitive: str
    action: str
    target: str
    label: str
    ok: bool
    reason: str = ""
    revealed: tuple[str, ...] = ()
    reward: float = 0.0

    def describe(self) -> str:
        """One line for the log: the primitive, what it acted on, what it revealed, or why it failed.

        Returns:
            The line.
        """
        text = f"{self.primitive} {self.label} ({self.target})"
        if self.revealed:
            text += f" -> reveals {', '.join(self.revealed)}"
        return text if self.ok else f"{text} FAILED: {self.reason}"


@dataclass(frozen=True)
class ExplorationResult:
    graph: ACSG
    log: tuple[LogEntry, ...]
    unexplored: frozenset[str]  # U at the end: empty after a complete exploration
    returned_to_start: bool  # every action that changed the scene was undone
    truncated: bool  # stopped at max_steps with work left
    notes: tuple[str, ...] = ()

    def steps(self) -> list[str]:
        """The executed primitives as ``"<primitive> <node id>"``, failures included, in order.

        Returns:
            The steps.
        """
        return [f"{e.primitive} {e.target}" for e in self.log]

    @property
    def total_reward(self) -> float:
        return float(sum(e.reward for e in self.log))


@dataclass
class _Entry:
    """A stack entry: run ``action`` (undo False) or undo it (undo True)."""

    action: str
    undo: bool
    verified: bool = False


@dataclass
class Explorer:
    """Algorithm 1 over the three interfaces; `run` explores until U and the stack are empty."""

    perception: Perception
    decision: DecisionModule
    executor: SkillExecutor
    config: InteractiveExploreConfig = field(default_factory=InteractiveExploreConfig)

    def __post_init__(self) -> None:
        self.graph = ACSG()
        self.unexplored: dict[str, None] = {}  # U, an ordered set
        self.stack: list[_Entry] = []
        self.log: list[LogEntry] = []
        self.notes: list[str] = []
        self.visible: dict[str, Detection] = {}
        self.moved_away: set[str] = set()
        self.outstanding: dict[str, None] = {}  # actions done and not yet undone
        self._pending: list[Detection] = []  # relation hints whose parent is not known yet

    # ---- the loop ----------------------------------------------------------------------------
    def run(self) -> ExplorationResult:
        """Perceive, then explore objects and run the stacked actions until nothing is left (or the step budget runs out).

        Returns:
            The explored graph and the log.
        """
        self._perceive(revealed_by=None)
        truncated = False
        while True:
            self._explore_objects()
            if not self.stack:
                break
            if len(self.log) >= self.config.max_steps:
                truncated = True
                self.notes.append(f"stopped after {len(self.log)} primitives with {len(self.stack)} still stacked")
                break
            entry = self.stack.pop()
            action = self.graph.action(entry.action)
            if not entry.undo and not entry.verified:
                entry.verified = True
                blockers = self._blockers(action)
                if blockers:
                    self._add_preconditions(entry, action, blockers)
                    continue
            self._execute(entry, action)
        return ExplorationResult(
            graph=self.graph, log=tuple(self.log), unexplored=frozenset(self.unexplored),
            returned_to_start=not self.outstanding, truncated=truncated, notes=tuple(self.notes),
        )

    def context(self) -> DecisionContext:
        """What the decision module judges from now: the graph, what is in view, what was moved away.

        Returns:
            The context.
        """
        return DecisionContext(self.graph, dict(self.visible), frozenset(self.moved_away))

    # ---- memory: nodes and spatial relations (Algorithm 2) ------------------------------------
    def _perceive(self, revealed_by: ActionNode | None) -> list[str]:
        """Observe; add what is new, with its relations, and reveal edges from ``revealed_by`` to
        what of it lies inside what that action opened or lifted (`_opened_or_lifted`).

        Returns:
            The ids of the objects ``revealed_by`` revealed.
        """
        detections = self.perception.observe()
        self.visible = {d.id: d for d in detections}
        new: list[str] = []
        revealed: list[str] = []
        for det in detections:
            if det.id in self.graph:
                continue
            is_part = det.relation == "belongs"  # judged through what it belongs to, as in the reference
            self.graph.add_object(det.id, det.label, instance=det.instance, attributes=dict(det.attributes),
                                  centroid=det.centroid, extent=det.extent, explored=is_part)
            new.append(det.id)
            if not is_part:
                self.unexplored[det.id] = None
            if det.parent is not None:
                self._pending.append(det)
        self._add_relations()
        if revealed_by is not None:
            inside = self._opened_or_lifted(revealed_by)
            revealed = [d.id for d in detections
                        if d.id in new and d.relation == "inside" and d.parent and object_id(d.parent) in inside]
            for node in revealed:
                self.graph.add_edge(revealed_by.id, node, "action-object", "reveals")
        self._fold_absorbed(detections)
        return revealed

    def _opened_or_lifted(self, action: ActionNode) -> set[str]:
        """What ``action`` opened or lifted, as what a thing it revealed lies inside: the box it
        picked away, or the door or drawer it opened and the piece that part belongs to (a drawer
        holds its things, a cabinet those behind its door).

        A thing first seen after an action is not always what the action revealed: the base
        drove to a new stand for it, and a soap on the drawer chest's top, hidden behind a box
        from where the robot first looked, came into view as a drawer opened (recursive 1214 of
        tuning-wide); a can on the table beside a cabinet likewise as its door opened (occlusion
        1256). Only what lies inside what was opened or lifted was hidden by it.
        """
        parent = self.graph.parent(action.target)
        return {action.target} | ({parent[0]} if parent is not None and parent[1] == "belongs" else set())

    def _fold_absorbed(self, detections: list[Detection]) -> None:
        """Fold the node of each instance the perception has found to be another one (``absorbed``)
        into that one's: left in, the graph would keep a thing twice. Actions proposed on it and
        never run go with it; a node something was done to (an action run on it, moved away)
        stays, with a note."""
        for det in detections:
            for instance in det.hints.get("absorbed", ()):
                other = object_id(instance)
                if other == det.id or other not in self.graph or det.id not in self.graph:
                    continue
                actions = self.graph.successors(other, "object-action")
                if other in self.moved_away or any(self.graph.action(a).state != "unexplored" for a in actions):
                    self.notes.append(f"{other} is {det.id}, but was acted on: both kept")
                    continue
                for action in actions:
                    self._forget_action(action)
                self.graph.merge_objects(det.id, other)
                self.unexplored.pop(other, None)
                self.visible.pop(other, None)

    def _forget_action(self, action_id: str) -> None:
        """Take an action never run out of the graph, the stack and U."""
        self.graph.remove_action(action_id)
        self.stack = [entry for entry in self.stack if entry.action != action_id]
        self.unexplored.pop(action_id, None)

    def _add_relations(self) -> None:
        waiting = []
        for det in self._pending:
            parent = object_id(det.parent)  # type: ignore[arg-type]
            if parent not in self.graph:
                waiting.append(det)
                continue
            try:
                self.graph.add_edge(parent, det.id, "object-object", det.relation)
            except ACSGError as error:  # a perception slip must not end the exploration
                self.notes.append(f"relation of {det.id} dropped: {error}")
        self._pending = waiting

    # ---- decisions: proposer ------------------------------------------------------------------
    def _explore_objects(self) -> None:
        """Judge every unexplored object; push the pairs of all proposed actions, first one on top."""
        objects = [n for n in self.unexplored if self.graph.node(n).kind == "object"]
        if not objects:
            return
        context = self.context()
        planned: list[ActionNode] = []
        for node_id in objects:
            obj = self.graph.object(node_id)
            proposal = self.decision.propose(obj, context)
            if proposal not in PROPOSALS:
                raise ValueError(f"proposal for {node_id}: {proposal!r} is not one of {PROPOSALS}")
            obj.explored = True
            del self.unexplored[node_id]
            if proposal == "open":
                planned += self._open_actions(obj)
            elif proposal == "pick":
                planned.append(self._pick_action(obj))
        for action in reversed([a for a in planned if a.state == "unexplored"]):
            self._push_pair(action)

    def _push_pair(self, action: ActionNode) -> None:
        if action.undo is not None:
            self.stack.append(_Entry(action.id, undo=True))
        self.stack.append(_Entry(action.id, undo=False))

    def _open_actions(self, obj: ObjectNode) -> list[ActionNode]:
        """One open action per openable part of ``obj``; ``obj`` itself when it has none."""
        parts = [self.graph.object(c) for c in self._children(obj.id, "belongs") if self._openable(c)]
        actions = []
        for part in parts or [obj]:
            handles = [c for c in self._children(part.id, "belongs") if self.graph.object(c).label == "handle"]
            action_id = f"open:{part.instance or part.id}"
            if action_id in self.graph:
                actions.append(self.graph.action(action_id))
                continue
            params = {"handle": handles[0]} if handles else {}
            action = self.graph.add_action(action_id, "open", part.id, open_primitive(part.label), params=params)
            self.unexplored[action.id] = None
            actions.append(action)
        return actions

    def _pick_action(self, obj: ObjectNode) -> ActionNode:
        action_id = f"pick:{obj.instance or obj.id}"
        if action_id in self.graph:
            return self.graph.action(action_id)
        action = self.graph.add_action(action_id, "pick", obj.id, PICK_AWAY)
        self.unexplored[action.id] = None
        return action

    def _children(self, node_id: str, relation: str) -> list[str]:
        return [c for c in self.graph.successors(node_id, "object-object")
                if self.graph.edge(node_id, c).relation == relation]  # type: ignore[union-attr]

    def _openable(self, node_id: str) -> bool:
        if self.graph.object(node_id).label in OPENABLE_PARTS:
            return True
        return any(self.graph.object(c).label == "handle" for c in self._children(node_id, "belongs"))

    # ---- decisions: verifier and preconditions (Algorithm 3) ----------------------------------
    def _blockers(self, action: ActionNode) -> list[str]:
        found = []
        for node_id in self.decision.verify(action, self.context()):
            if node_id not in self.graph or self.graph.node(node_id).kind != "object":
                self.notes.append(f"verifier named {node_id!r} for {action.id}, which is no object of the graph")
            elif node_id != action.target and node_id not in self.moved_away and node_id not in found:
                found.append(node_id)
        return found

    def _add_preconditions(self, entry: _Entry, action: ActionNode, blockers: list[str]) -> None:
        """Move the blockers away before ``action`` and put them back after its undo."""
        picks = []
        for blocker in blockers:
            pick = self._pick_action(self.graph.object(blocker))
            try:
                self.graph.add_edge(pick.id, action.id, "action-action", "precondition")
            except CycleError as error:
                self.notes.append(f"precondition {pick.id} -> {action.id} dropped: {error}")
                continue
            picks.append(pick)
        undo = self.stack.pop() if self.stack and self.stack[-1].action == action.id and self.stack[-1].undo else None
        self.stack.extend(_Entry(p.id, undo=True) for p in picks)
        if undo is not None:
            self.stack.append(undo)
        self.stack.append(entry)
        self.stack.extend(_Entry(p.id, undo=False) for p in reversed(picks))

    # ---- action --------------------------------------------------------------------------------
    def _execute(self, entry: _Entry, action: ActionNode) -> None:
        primitive = action.undo if entry.undo else action.primitive
        assert primitive is not None  # undo entries are only pushed for actions that have one
        target = self.graph.object(action.target)
        nodes_before, open_before = len(self.graph), len(self.unexplored)
        result = self.executor.execute(SkillCall(primitive, action.id, target.id, target.instance, dict(action.params)))
        revealed: list[str] = []
        if result.ok:
            if entry.undo:
                self.outstanding.pop(action.id, None)
                if action.type == "pick":
                    self.moved_away.discard(target.id)
            else:
                if action.undo is not None:
                    self.outstanding[action.id] = None
                if action.type == "pick":
                    self.moved_away.add(target.id)
                action.state = "explored"
                self.unexplored.pop(action.id, None)
            revealed = self._perceive(None if entry.undo else action)
        else:
            if entry.undo:
                self.notes.append(f"could not undo {action.id} ({primitive}): {result.reason}")
            else:
                action.state = "failed"
                self._drop_undo(action.id)
            self._perceive(None)
        # R = R_graph + R_explore + R_time = ΔV + max(0, −ΔU) − λ
        reward = len(self.graph) - nodes_before + max(0, open_before - len(self.unexplored)) - self.config.reward_lambda
        self.log.append(LogEntry(len(self.log), primitive, action.id, target.id, target.label, result.ok,
                                 result.reason, tuple(revealed), float(reward)))

    def _drop_undo(self, action_id: str) -> None:
        for index in range(len(self.stack) - 1, -1, -1):
            if self.stack[index].action == action_id and self.stack[index].undo:
                del self.stack[index]
                return


def explore(perception: Perception, decision: DecisionModule, executor: SkillExecutor,
            config: InteractiveExploreConfig | None = None) -> ExplorationResult:
    """Explore until nothing is left to judge or do; see the module docstring for the order.

    Args:
        perception: what detects the objects in view.
        decision: the proposer and verifier.
        executor: what runs the primitives.
        config: the step budget and other settings (defaults when None).

    Returns:
        The explored graph and the log.
    """
    return Explorer(perception, decision, executor, config or InteractiveExploreConfig()).run()
