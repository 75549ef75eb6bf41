"""Interactive exploration: the order the action stack gives, obstruction handling, the decision
modules, and exploring every ground-truth tabletop scene back to its start state."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pytest

from agent.acsg.decision import PROPOSER_USER, VERIFIER_USER, PromptDecisionModule, RuleDecisionModule
from agent.acsg.interactive_exploration import InteractiveExploreConfig, explore
from agent.acsg.interfaces import DecisionContext, Detection, SkillCall, SkillResult
from agent.acsg.json_format import from_ground_truth
from agent.acsg.metrics import aligned_edit_distance, episode_metrics, position_recovery
from agent.acsg.nodes import ActionNode, ObjectNode
from agent.acsg.plan import retrieval_plan
from agent.acsg.symbolic import SymbolicScene, Thing
from agent.vlm.protocol import VisualQuery


@dataclass
class Recorder:
    """Wraps the rule module and the scene so every judgement and primitive lands in one list."""

    scene: SymbolicScene
    decision: object = field(default_factory=RuleDecisionModule)
    events: list[str] = field(default_factory=list)

    def observe(self):
        return self.scene.observe()

    def propose(self, obj: ObjectNode, context: DecisionContext):
        self.events.append(f"propose {obj.id}")
        return self.decision.propose(obj, context)

    def verify(self, action: ActionNode, context: DecisionContext) -> list[str]:
        blockers = self.decision.verify(action, context)
        self.events.append(f"verify {action.id} -> {blockers}")
        return blockers

    def execute(self, call: SkillCall) -> SkillResult:
        result = self.scene.execute(call)
        self.events.append(f"{call.primitive} {call.target}" + ("" if result.ok else " FAILED"))
        return result

    def run(self, **config):
        return explore(self, self, self, InteractiveExploreConfig(**config) if config else None)


def matryoshka() -> SymbolicScene:
    return SymbolicScene([
        Thing("1", "table"),
        Thing("2", "box", "1", "on", (0.0, 0.0, 0.8), pickable=True),
        Thing("3", "box", "2", "inside", (0.0, 0.0, 0.78), hidden_by=("2",), pickable=True),
        Thing("4", "doll", "3", "inside", (0.0, 0.0, 0.77), hidden_by=("2", "3"), pickable=True),
    ])


def cabinet_behind_bottle(jar: str | None = None) -> SymbolicScene:
    """A bottle in the door's swing, an apple inside; ``jar`` "blocking" or "aside" adds a jar."""
    things = [
        Thing("1", "table"),
        Thing("2", "cabinet", "1", "on", (0.0, 0.2, 0.75)),
        Thing("3", "door", "2", "belongs", part="door"),
        Thing("4", "handle", "3", "belongs"),
        Thing("6", "apple", "2", "inside", (0.0, 0.2, 0.8), hidden_by=("3",), pickable=True),
        Thing("5", "bottle", "1", "on", (0.1, -0.1, 0.85), blocks=("3",), pickable=True),
    ]
    if jar is not None:
        blocks = ("3",) if jar == "blocking" else ()
        things.append(Thing("7", "jar", "1", "on", (0.2, -0.1, 0.8), blocks=blocks, pickable=True))
    return SymbolicScene(things)


# ---- the stack order ---------------------------------------------------------------------------

def test_matryoshka_is_explored_depth_first_and_put_back() -> None:
    run = Recorder(matryoshka())
    result = run.run()
    assert result.steps() == ["pick_away o2", "pick_away o3", "pick_back o3", "pick_back o2"]
    judged = [e for e in run.events if not e.startswith("verify")]
    assert judged == ["propose o1", "propose o2", "pick_away o2", "propose o3", "pick_away o3", "propose o4",
                      "pick_back o3", "pick_back o2"]
    assert [e.revealed for e in result.log] == [("o3",), ("o4",), (), ()]
    g = result.graph
    assert g.edge("pick:2", "o3").relation == "reveals" and g.edge("pick:3", "o4").relation == "reveals"
    assert g.parent("o4") == ("o3", "inside")
    assert result.unexplored == frozenset() and result.returned_to_start and not result.truncated
    assert retrieval_plan(g, "doll") == ["pick away box (o2)", "pick away box (o3)", "pick doll (o4)"]
    assert position_recovery(run.scene.start_positions(), run.scene.positions(), tolerance_m=1e-9) == 1.0


def test_obstruction_moves_the_bottle_until_the_door_is_shut_again() -> None:
    run = Recorder(cabinet_behind_bottle())
    result = run.run()
    assert result.steps() == ["pick_away o5", "open_door o3", "close_door o3", "pick_back o5"]
    assert run.events[run.events.index("verify open:3 -> ['o5']"):] == [
        "verify open:3 -> ['o5']", "verify pick:5 -> []", "pick_away o5", "open_door o3", "propose o6",
        "close_door o3", "pick_back o5",
    ]
    g = result.graph
    assert g.edge("pick:5", "open:3").relation == "precondition"
    assert g.edge("open:3", "o6").relation == "reveals"
    assert g.action("open:3").params == {"handle": "o4"}
    assert retrieval_plan(g, "apple") == ["pick away bottle (o5)", "open door (o3)", "pick apple (o6)"]
    assert result.returned_to_start and result.unexplored == frozenset()
    assert run.scene.part_states() == run.scene.start_part_states()


def test_two_blockers_are_put_back_in_reverse() -> None:
    result = Recorder(cabinet_behind_bottle(jar="blocking")).run()
    assert result.steps() == ["pick_away o5", "pick_away o7", "open_door o3", "close_door o3", "pick_back o7",
                              "pick_back o5"]
    assert result.graph.predecessors("open:3", "action-action") == ["pick:5", "pick:7"]


def test_a_box_in_a_drawer_is_lifted_and_put_back_before_the_drawer_closes() -> None:
    scene = SymbolicScene([
        Thing("1", "table"),
        Thing("2", "drawer chest", "1", "on"),
        Thing("3", "drawer", "2", "belongs", part="drawer"),
        Thing("4", "drawer", "2", "belongs", part="drawer"),
        Thing("5", "box", "3", "inside", hidden_by=("3",), pickable=True),
        Thing("6", "soap", "5", "inside", hidden_by=("3", "5"), pickable=True),
        Thing("7", "cup", "4", "inside", hidden_by=("4",), pickable=True),
    ])
    result = Recorder(scene).run()
    assert result.steps() == ["open_drawer o3", "pick_away o5", "pick_back o5", "close_drawer o3",
                              "open_drawer o4", "close_drawer o4"]
    assert retrieval_plan(result.graph, "soap") == ["open drawer (o3)", "pick away box (o5)", "pick soap (o6)"]



def test_an_action_reveals_only_what_lies_inside_what_it_opened_or_lifted() -> None:
    """A soap on the chest's top and a can on the table come into view only once a drawer stands
    open (from where the robot stood to open it, in the world); neither lay inside what was opened."""
    scene = SymbolicScene([
        Thing("1", "table"),
        Thing("2", "drawer chest", "1", "on"),
        Thing("3", "drawer", "2", "belongs", part="drawer"),
        Thing("4", "cup", "3", "inside", hidden_by=("3",), pickable=True),
        Thing("5", "soap", "2", "on", hidden_by=("3",)),
        Thing("6", "can", "1", "on", hidden_by=("3",)),
        Thing("7", "box", "1", "on", pickable=True),
        Thing("8", "apple", "7", "inside", hidden_by=("7",), pickable=True),
        Thing("9", "mug", "1", "on", hidden_by=("7",)),
    ])
    result = Recorder(scene).run()
    g = result.graph
    assert {e.target for e in g.edges("action-object")} == {"o4", "o8"}
    assert g.edge("open:3", "o4").relation == "reveals" and g.edge("pick:7", "o8").relation == "reveals"
    assert g.parent("o5") == ("o2", "on") and g.parent("o9") == ("o1", "on")
    assert {o.id for o in g.objects()} >= {"o5", "o6", "o9"}
    assert [e.revealed for e in result.log if e.revealed] == [("o4",), ("o8",)]

def test_without_the_verifier_the_blocked_door_fails_and_nothing_needs_undoing() -> None:
    class Blind(RuleDecisionModule):
        def verify(self, action, context):
            return []

    scene = cabinet_behind_bottle()
    result = Recorder(scene, Blind()).run()
    assert result.steps() == ["open_door o3"]
    assert not result.log[0].ok and "blocked by bottle 5" in result.log[0].reason
    assert result.graph.action("open:3").state == "failed"
    assert result.unexplored == frozenset({"open:3"})
    assert "o6" not in result.graph  # the apple was never seen
    assert result.returned_to_start


def test_the_symbolic_scene_refuses_the_wrong_order() -> None:
    """Putting the bottle back before closing would leave the door unable to close."""
    scene = cabinet_behind_bottle()

    def call(primitive: str, instance: str) -> SkillResult:
        return scene.execute(SkillCall(primitive, "x", f"o{instance}", instance))

    assert not call("open_door", "3").ok
    assert call("pick_away", "5").ok and call("open_door", "3").ok and call("pick_back", "5").ok
    closing = call("close_door", "3")
    assert not closing.ok and "blocked" in closing.reason
    assert not call("pick_away", "3").ok  # a door is not picked
    assert not call("open_drawer", "3").ok  # nor opened as a drawer


@dataclass
class TwoViewsOfOneMug:
    """A table with a mug on it, and a drawer chest whose drawer holds an apple. The first look
    sees the mug twice (from the wrist above, from the head beside), as two instances; once the
    drawer is opened, the perception has found the second to be the first (``absorbed``)."""

    looks: int = 0

    def observe(self) -> list[Detection]:
        self.looks += 1
        found = [Detection("1", "table"), Detection("2", "drawer chest", "1", "on"),
                 Detection("3", "drawer", "2", "belongs"), Detection("4", "handle", "3", "belongs")]
        if self.looks == 1:
            return [*found, Detection("5", "mug", "1", "on"), Detection("6", "mug", "1", "on")]
        return [*found, Detection("5", "mug", "1", "on", hints={"absorbed": ("6",)}),
                Detection("7", "apple", "2", "inside")]

    def execute(self, call: SkillCall) -> SkillResult:
        return SkillResult(True)


def test_a_thing_the_perception_finds_it_saw_twice_is_one_node() -> None:
    perception = TwoViewsOfOneMug()
    result = explore(perception, RuleDecisionModule(), perception)
    mugs = [node.id for node in result.graph.objects() if node.label == "mug"]
    assert mugs == ["o5"]
    assert result.graph.edge("o1", "o5").relation == "on"
    assert result.graph.successors("open:3", "action-object") == ["o7"]


@dataclass
class ABoxSeenAgainWherePutDown:
    """A box on a table, lifted off a smaller box and put down: the look after the put-down sees
    the smaller box (8) and, as a new thing, the box where it was put down (9); the explorer
    judges both. The look after the smaller box is lifted finds box 9 to be box 2 (``absorbed``
    into the older one), before anything was done to 9."""

    looks: int = 0
    calls: list[str] = field(default_factory=list)

    def observe(self) -> list[Detection]:
        self.looks += 1
        table, box = Detection("1", "table"), Detection("2", "box", "1", "on")
        if self.looks == 1:
            return [table, box]
        if self.looks == 2:
            return [table, box, Detection("8", "box", "1", "on"), Detection("9", "box", "1", "on")]
        return [table, Detection("2", "box", "1", "on", hints={"absorbed": ("9",)}), Detection("8", "box", "1", "on")]

    def execute(self, call: SkillCall) -> SkillResult:
        self.calls.append(f"{call.primitive} {call.target}")
        return SkillResult(True)


def test_a_node_found_to_be_another_goes_with_the_actions_never_run_on_it() -> None:
    perception = ABoxSeenAgainWherePutDown()
    result = explore(perception, RuleDecisionModule(), perception)
    assert [node.id for node in result.graph.objects() if node.label == "box"] == ["o2", "o8"]
    assert "pick:9" not in result.graph
    assert perception.calls == ["pick_away o2", "pick_away o8", "pick_back o8", "pick_back o2"]  # 9 never lifted
    assert result.returned_to_start and not result.notes


def test_rewards_follow_the_paper() -> None:
    result = Recorder(cabinet_behind_bottle()).run(reward_lambda=0.25)
    # pick_away: no new node, U loses pick:5 -> 1 - λ; open: the apple is new (+1), U gains the apple
    # and loses open:3 (ΔU = 0) -> 1 - λ; the undos change nothing -> -λ.
    assert [e.reward for e in result.log] == pytest.approx([0.75, 0.75, -0.25, -0.25])
    assert result.total_reward == pytest.approx(1.0)


def test_truncation_and_bad_proposals() -> None:
    result = Recorder(matryoshka()).run(max_steps=2)
    assert result.truncated and not result.returned_to_start and len(result.log) == 2

    class Wrong(RuleDecisionModule):
        def propose(self, obj, context):
            return "smash"

    with pytest.raises(ValueError, match="proposal for o1: 'smash'"):
        Recorder(matryoshka(), Wrong()).run()


# ---- the prompt module with a fake VLM ------------------------------------------------------------

class FakeVLM:
    """Answers the proposer by the query object's label, the verifier Yes for bottles only."""

    name = "fake"

    def __init__(self) -> None:
        self.queries: list[VisualQuery] = []

    def probabilities(self, query: VisualQuery) -> dict[str, float]:
        self.queries.append(query)
        if query.candidates == ("1", "2", "3"):
            label = query.prompt.split("Query object: ")[1].split(".")[0].split()[-1]
            skill = {"cabinet": "1", "box": "2"}.get(label, "3")
            return {c: 0.8 if c == skill else 0.1 for c in query.candidates}
        assert query.candidates == ("Yes", "No")
        yes = 0.9 if "Could the bottle block" in query.prompt else 0.2
        return {"Yes": yes, "No": 1 - yes}


def test_prompt_module_asks_the_vlm_with_the_papers_prompts() -> None:
    vlm = FakeVLM()
    frames = []

    def camera():
        frames.append(object())
        return frames[-1]

    decision = PromptDecisionModule(vlm, camera=camera)
    scene = cabinet_behind_bottle(jar="aside")
    result = Recorder(scene, decision).run()
    assert result.steps() == ["pick_away o5", "open_door o3", "close_door o3", "pick_back o5"]
    proposer = [q for q in vlm.queries if q.candidates == ("1", "2", "3")]
    verifier = [q for q in vlm.queries if q.candidates == ("Yes", "No")]
    assert len(proposer) == 5  # table, cabinet, bottle, jar, apple: parts are judged through the cabinet
    assert all(PROPOSER_USER in q.prompt for q in proposer)
    assert len(verifier) == 2 and all(VERIFIER_USER in q.prompt for q in verifier)
    assert "Given object list [bottle, jar]" in verifier[0].prompt
    assert [q.observation for q in vlm.queries] == frames  # a fresh frame with every query
    assert decision.queries == vlm.queries


def test_prompt_module_rejects_a_model_that_skips_a_candidate() -> None:
    class Mute:
        name = "mute"

        def probabilities(self, query):
            return {"1": 1.0}

    with pytest.raises(ValueError, match="no probability for candidates"):
        Recorder(matryoshka(), PromptDecisionModule(Mute())).run()


def test_rule_module_judges_by_commonsense() -> None:
    from agent.acsg.graph import ACSG

    g = ACSG()
    context = DecisionContext(g, {})
    rule = RuleDecisionModule()
    judged = {label: rule.propose(g.add_object(f"o{i}", label, attributes=attrs), context)
              for i, (label, attrs) in enumerate([("cabinet", {}), ("fridge", {}), ("box", {}), ("lid", {}),
                                                  ("apple", {}), ("bowl", {}), ("cup", {"upside_down": True})])}
    assert judged == {"cabinet": "open", "fridge": "open", "box": "pick", "lid": "pick", "apple": "none",
                      "bowl": "none", "cup": "pick"}
    g.add_object("t", "table")
    g.add_object("d", "door")
    g.add_edge("t", "d", relation="belongs")
    assert rule.propose(g.object("t"), context) == "open"  # anything with a door opens


def test_the_rule_verifier_never_names_furniture_as_an_obstacle() -> None:
    from agent.acsg.graph import ACSG
    from agent.acsg.interfaces import Detection

    g = ACSG()
    for node_id, label in (("o0", "table"), ("o1", "drawer chest"), ("o2", "drawer chest"), ("o3", "drawer"),
                           ("o4", "bottle")):
        g.add_object(node_id, label)
    g.add_edge("o2", "o3", relation="belongs")
    g.add_edge("o0", "o1", relation="on")
    g.add_edge("o0", "o2", relation="on")
    g.add_edge("o0", "o4", relation="on")
    opening = g.add_action("open:3", "open", "o3", "open_drawer")
    swept = ((0.0, -0.4, 0.7), (0.4, 0.0, 0.9))
    in_the_way = {"centroid": np.array([0.2, -0.2, 0.8]), "extent": np.array([0.1, 0.1, 0.1])}
    visible = {
        "o3": Detection("3", "drawer", "2", "belongs", hints={"swept": swept}),
        # The chest seen apart from its own drawer (a second fragment), and a bottle, both in the way.
        "o1": Detection("1", "drawer chest", "0", "on", **in_the_way),
        "o4": Detection("4", "bottle", "0", "on", **in_the_way),
    }
    assert RuleDecisionModule().verify(opening, DecisionContext(g, visible)) == ["o4"]


def _drawer_beside(piece: str, thing: Detection, swept: tuple) -> list[str]:
    """What the rule verifier names in the way of opening the drawer (o3) of ``piece`` (o2), which
    sweeps ``swept``, with ``thing`` (o4) standing on the table (o0)."""
    from agent.acsg.graph import ACSG

    g = ACSG()
    for node_id, label in (("o0", "table"), ("o2", piece), ("o3", "drawer"), ("o4", thing.label)):
        g.add_object(node_id, label)
    g.add_edge("o2", "o3", relation="belongs")
    g.add_edge("o0", "o4", relation="on")
    opening = g.add_action("open:3", "open", "o3", "open_drawer")
    drawer = Detection("3", "drawer", "2", "belongs", hints={"swept": swept})
    return RuleDecisionModule().verify(opening, DecisionContext(g, {"o3": drawer, "o4": thing}))


def test_the_rule_verifier_names_no_obstacle_only_grazing_what_a_drawer_sweeps() -> None:
    """A box beside a chest, its remembered box 7 mm into the sweep (recursive 1087 of tuning-wide),
    is not in the way; one reaching 3 cm into it is."""

    def verified(left_edge: float) -> list[str]:
        box = Detection("4", "box", "0", "on", centroid=np.array([left_edge + 0.13, -0.218, 0.819]),
                        extent=np.array([0.26, 0.33, 0.09]))
        return _drawer_beside("drawer chest", box, ((-0.03, -0.17, 0.75), (0.391, 0.11, 0.91)))

    assert verified(0.384) == []
    assert verified(0.361) == ["o4"]


def test_the_rule_verifier_judges_by_the_box_seen_not_by_one_laid_about_the_mean_of_its_points() -> None:
    """A bottle under a drawer, seen mostly from above: the mean of its points stood 1.9 cm over
    its middle, and a box of its size laid about that mean reached 1 cm into what the
    drawer sweeps (occlusion 1156 of tuning-wide); the box seen stops short of it."""

    def verified(**hints: object) -> list[str]:
        bottle = Detection("4", "bottle", "0", "on", centroid=np.array([0.474, -0.212, 0.899]),
                           extent=np.array([0.09, 0.09, 0.27]), hints=hints)
        return _drawer_beside("nightstand", bottle, ((0.07, -0.25, 1.015), (0.57, 0.04, 1.195)))

    assert verified(box=((0.429, -0.257, 0.745), (0.519, -0.167, 1.015))) == []
    assert verified(box=((0.429, -0.257, 0.775), (0.519, -0.167, 1.045))) == ["o4"]
    assert verified() == ["o4"]  # without the box seen, the extent about the centroid, as before


# ---- every ground-truth scene ----------------------------------------------------------------------

def test_exploring_every_tabletop_scene_recovers_its_ground_truth() -> None:
    from worlds.tabletop import TASKS, VARIANTS, tabletop_variant

    wrong, moved = [], []
    for task in TASKS:
        for seed in range(VARIANTS):
            scene = tabletop_variant(task, seed)
            world = SymbolicScene.from_tabletop(scene)
            result = explore(world, RuleDecisionModule(), world)
            truth = from_ground_truth(scene.ground_truth_acsg())
            metrics = episode_metrics(result.graph, truth, world.start_positions(), world.positions(),
                                      world.start_part_states(), world.part_states(), timeout_s=5.0)
            if not metrics.success or metrics.graph_edit_distance != 0 or metrics.unexplored_space != 0:
                wrong.append((task, seed, aligned_edit_distance(result.graph, truth), metrics))
            if not (metrics.state_recovered and result.returned_to_start) or result.unexplored or result.notes:
                moved.append((task, seed, result.notes, sorted(result.unexplored)))
            assert all(entry.ok for entry in result.log), (task, seed, [e.describe() for e in result.log])
            if task == "occlusion":
                assert truth.edges("action-action"), (task, seed)
                assert set(map(str, truth.edges("action-action"))) == set(map(str, result.graph.edges("action-action")))
    assert not moved, moved
    assert len(wrong) <= 2, wrong  # in fact none today; a few would still be "most"
