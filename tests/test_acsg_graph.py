"""The ACSG as data: JSON round trip, DAG rules, ground-truth conversion, retrieval plans, picture, CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest

from agent.app.cli.acsg import main as acsg_main
from agent.acsg.draw import draw_acsg, layout
from agent.acsg.graph import ACSG, CycleError, UnknownObjectError
from agent.acsg.json_format import (
    FORMAT,
    VERSION,
    acsg_from_dict,
    acsg_to_dict,
    from_ground_truth,
    load_acsg,
    save_acsg,
)
from agent.acsg.nodes import ACSGError
from agent.acsg.order import depths, topological_order
from agent.acsg.plan import retrieval_actions, retrieval_plan


def obstruction_graph() -> ACSG:
    """The paper's Fig. 2 in small: a bottle stands in front of a cabinet door, an apple is inside."""
    g = ACSG({"task": "hand-made"})
    g.add_object("o1", "table")
    g.add_object("o2", "cabinet", instance="2", attributes={"colour": "white"})
    g.add_object("o3", "door", instance="3")
    g.add_object("o4", "handle", instance="4")
    g.add_object("o5", "bottle", instance="5", centroid=[0.1, -0.3, 0.85], extent=[0.07, 0.07, 0.2])
    g.add_object("o6", "apple", instance="6", attributes={"colour": "red"},
                 points=np.array([[0.0, 0.1, 0.8], [0.01, 0.1, 0.81]]))
    g.add_edge("o1", "o2", relation="on")
    g.add_edge("o2", "o3", relation="belongs")
    g.add_edge("o3", "o4", relation="belongs")
    g.add_edge("o1", "o5", relation="on")
    g.add_edge("o2", "o6", relation="inside")
    g.add_action("open:3", "open", "o3", params={"handle": "o4"})
    g.add_action("pick:5", "pick", "o5")
    g.add_edge("open:3", "o6")
    g.add_edge("pick:5", "open:3")
    return g


def matryoshka_graph() -> ACSG:
    """A drawer holding a box over a box over a doll."""
    g = ACSG()
    g.add_object("o1", "table")
    g.add_object("o2", "drawer chest")
    g.add_object("o3", "drawer")
    g.add_object("o4", "box")
    g.add_object("o5", "box")
    g.add_object("o6", "doll")
    g.add_edge("o1", "o2", relation="on")
    g.add_edge("o2", "o3", relation="belongs")
    g.add_action("open:3", "open", "o3")
    g.add_edge("o3", "o4", relation="inside")
    g.add_edge("open:3", "o4")
    g.add_action("pick:4", "pick", "o4")
    g.add_edge("o4", "o5", relation="inside")
    g.add_edge("pick:4", "o5")
    g.add_action("pick:5", "pick", "o5")
    g.add_edge("o5", "o6", relation="inside")
    g.add_edge("pick:5", "o6")
    return g


# ---- structure and JSON --------------------------------------------------------------------------

def test_edges_get_their_kind_and_default_relation() -> None:
    g = obstruction_graph()
    assert g.edge("o3", "open:3").kind == "object-action"
    assert g.edge("o3", "open:3").relation == "can be opened"
    assert g.edge("o5", "pick:5").relation == "can be picked"
    assert g.edge("open:3", "o6").relation == "reveals"
    assert g.edge("pick:5", "open:3").relation == "precondition"
    assert g.action("open:3").primitive == "open_door" and g.action("open:3").undo == "close_door"
    assert g.action("pick:5").primitive == "pick_away" and g.action("pick:5").undo == "pick_back"
    assert g.parent("o6") == ("o2", "inside")
    assert [n.id for n in g.nodes() if not g.predecessors(n.id)] == ["o1"]


def test_json_round_trip_keeps_everything() -> None:
    g = obstruction_graph()
    g.action("open:3").state = "explored"
    g.object("o6").explored = True
    text = json.dumps(acsg_to_dict(g))
    data = json.loads(text)
    assert data["format"] == FORMAT and data["version"] == VERSION
    back = acsg_from_dict(json.loads(text))
    assert acsg_to_dict(back) == acsg_to_dict(g)
    assert [n.id for n in back.nodes()] == [n.id for n in g.nodes()]
    np.testing.assert_allclose(back.object("o5").centroid, [0.1, -0.3, 0.85])
    assert back.object("o6").points.shape == (2, 3)
    assert back.object("o6").explored and back.action("open:3").state == "explored"
    assert back.action("open:3").params == {"handle": "o4"}
    assert back.meta == {"task": "hand-made"}


def test_save_and_load(tmp_path) -> None:
    g = obstruction_graph()
    path = save_acsg(g, tmp_path / "g.json")
    assert acsg_to_dict(load_acsg(path)) == acsg_to_dict(g)


def test_cycles_are_refused_with_the_cycle_named() -> None:
    g = obstruction_graph()
    with pytest.raises(CycleError) as caught:
        g.add_edge("open:3", "pick:5")
    assert caught.value.cycle == ["open:3", "pick:5", "open:3"]
    assert "would close the cycle" in str(caught.value)
    with pytest.raises(CycleError):
        g.add_edge("o6", "o1", relation="on")  # o1 -> o2 -> o6 already
    with pytest.raises(CycleError):
        g.add_edge("o4", "o4", relation="on")
    assert g.edge("open:3", "pick:5") is None  # nothing was added


def test_an_object_merged_into_another_hands_it_its_edges_and_leaves() -> None:
    g = obstruction_graph()
    g.add_object("o7", "apple", instance="7")  # a second view of the apple, first taken for another
    g.add_edge("o2", "o7", relation="inside")
    g.add_edge("open:3", "o7")
    g.add_object("o8", "apple")
    g.add_edge("o7", "o8", relation="on")  # an edge only the copy had
    g.merge_objects("o6", "o7")
    assert "o7" not in g
    assert g.edge("o2", "o6").relation == "inside" and g.edge("open:3", "o6") is not None
    assert g.edge("o6", "o8").relation == "on"
    assert not any("o7" in (e.source, e.target) for e in g.edges())
    with pytest.raises(ACSGError, match="pick:5 act on o5"):
        g.merge_objects("o6", "o5")  # the bottle has a pick of its own
    assert "o5" in g


def test_bad_edges_and_nodes_name_the_field() -> None:
    g = obstruction_graph()
    with pytest.raises(ACSGError, match="relation 'reveals' is not one of"):
        g.add_edge("o1", "o6", relation="reveals")
    with pytest.raises(ACSGError, match="kind 'action-object' joins a object to a object"):
        g.add_edge("o1", "o6", kind="action-object", relation="reveals")
    with pytest.raises(ACSGError, match="already there as object-object 'inside'"):
        g.add_edge("o2", "o6", relation="on")
    assert g.add_edge("o2", "o6", relation="inside") is g.edge("o2", "o6")  # the same edge is fine
    with pytest.raises(ACSGError, match="'o99': not in the graph"):
        g.add_edge("o1", "o99", relation="on")
    with pytest.raises(ACSGError, match="already in the graph"):
        g.add_object("o1", "table")
    with pytest.raises(ACSGError, match="centroid must have shape"):
        g.add_object("o7", "cup", centroid=[1.0, 2.0])
    with pytest.raises(ACSGError, match="type 'smash' is not one of"):
        g.add_action("smash:5", "smash", "o5")
    with pytest.raises(ACSGError, match="target 'open:3' is not an object node"):
        g.add_action("pick:x", "pick", "open:3")


def test_reading_bad_json_names_the_field() -> None:
    data = acsg_to_dict(obstruction_graph())
    with pytest.raises(ACSGError, match="acsg version"):
        acsg_from_dict({**data, "version": 99})
    with pytest.raises(ACSGError, match="acsg format"):
        acsg_from_dict({**data, "format": "other"})
    broken = {**data, "nodes": [*data["nodes"], {"id": "x", "kind": "thing"}]}
    with pytest.raises(ACSGError, match=r"nodes\[8\].kind"):
        acsg_from_dict(broken)
    cyclic = {**data, "edges": [*data["edges"], {"source": "open:3", "target": "pick:5", "type": "action-action",
                                                 "relation": "precondition"}]}
    with pytest.raises(CycleError):
        acsg_from_dict(cyclic)


def test_topological_order_puts_preconditions_first_and_is_stable() -> None:
    g = obstruction_graph()
    order = topological_order(g)
    assert order.index("pick:5") < order.index("open:3") < order.index("o6")
    assert order == topological_order(g)
    assert depths(g)["o1"] == 0 and depths(g)["o6"] > depths(g)["open:3"]


# ---- ground truth ----------------------------------------------------------------------------------

def test_ground_truth_converts_and_round_trips() -> None:
    from worlds.tabletop import tabletop_variant

    scene = tabletop_variant("occlusion", 0)
    truth = scene.ground_truth_acsg()
    g = from_ground_truth(truth)
    assert len(g.objects()) == sum(n["kind"] == "object" for n in truth["nodes"])
    assert len(g.actions()) == sum(n["kind"] == "action" for n in truth["nodes"])
    assert len(g.edges()) == len(truth["edges"])
    assert g.meta == {"task": "occlusion", "seed": 0}
    assert acsg_to_dict(acsg_from_dict(truth)) == acsg_to_dict(g)  # acsg_from_dict recognises the ground truth
    assert acsg_to_dict(acsg_from_dict({"seed": 0, "acsg": truth})) == acsg_to_dict(g)  # and a suite record
    assert acsg_to_dict(acsg_from_dict(json.loads(json.dumps(acsg_to_dict(g))))) == acsg_to_dict(g)
    for edge in truth["edges"]:
        assert g.edge(edge["source"], edge["target"]).relation == edge["relation"]
    opens = [a for a in g.actions() if a.type == "open"]
    assert opens and all(a.primitive in ("open_door", "open_drawer") and "handle" in a.params for a in opens)


def test_every_ground_truth_scene_is_a_dag() -> None:
    from worlds.tabletop import TASKS, tabletop_variant

    for task in TASKS:
        for seed in (0, 5):
            g = from_ground_truth(tabletop_variant(task, seed).ground_truth_acsg())
            assert len(topological_order(g)) == len(g)


# ---- retrieval -----------------------------------------------------------------------------------

def test_retrieval_plan_moves_the_blocker_then_opens_then_picks() -> None:
    g = obstruction_graph()
    assert retrieval_plan(g, "apple") == ["pick away bottle (o5)", "open door (o3)", "pick apple (o6)"]
    assert [a.id for a in retrieval_actions(g, "o6")] == ["pick:5", "open:3"]
    assert retrieval_plan(g, "red apple") == retrieval_plan(g, "6") == retrieval_plan(g, "o6")
    assert retrieval_plan(g, "bottle") == ["pick bottle (o5)"]
    assert retrieval_plan(g, "apple", take=False) == ["pick away bottle (o5)", "open door (o3)"]


def test_retrieval_plan_through_nested_containers() -> None:
    g = matryoshka_graph()
    assert retrieval_plan(g, "doll") == ["open drawer (o3)", "pick away box (o4)", "pick away box (o5)",
                                         "pick doll (o6)"]
    assert retrieval_plan(g, "o5") == ["open drawer (o3)", "pick away box (o4)", "pick box (o5)"]


def test_retrieval_plan_errors_are_clear() -> None:
    g = matryoshka_graph()
    with pytest.raises(UnknownObjectError, match="'banana': no such object.*labels are: box, doll"):
        retrieval_plan(g, "banana")
    with pytest.raises(UnknownObjectError, match="ambiguous, it could be o4 \\(box\\), o5 \\(box\\)"):
        retrieval_plan(g, "box")
    with pytest.raises(UnknownObjectError):
        retrieval_plan(g, "open:3")  # an action is not an object


# ---- picture and CLI --------------------------------------------------------------------------------

def test_layout_is_layered_top_down() -> None:
    g = obstruction_graph()
    pos = layout(g)
    for edge in g.edges():
        assert pos[edge.source][1] > pos[edge.target][1]
    assert len(set(pos.values())) == len(pos)


def test_draw_writes_a_png(tmp_path) -> None:
    out = draw_acsg(matryoshka_graph(), tmp_path / "g.png", title="nested")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_cli_plan_and_show(tmp_path, capsys) -> None:
    path = save_acsg(obstruction_graph(), tmp_path / "g.json")
    assert acsg_main(["plan", str(path), "apple"]) == 0
    assert capsys.readouterr().out.splitlines() == [
        "1. pick away bottle (o5)", "2. open door (o3)", "3. pick apple (o6)"]
    assert acsg_main(["plan", str(path), "banana"]) == 1
    assert "no such object" in capsys.readouterr().err
    assert acsg_main(["show", str(path), "--out", str(tmp_path / "p.png")]) == 0
    assert (tmp_path / "p.png").exists()
    assert acsg_main(["plan", str(tmp_path / "missing.json"), "apple"]) == 1
    assert "cannot read" in capsys.readouterr().err
    assert acsg_main(["frobnicate"]) == 2


def test_cli_reads_a_suite_file_by_seed(tmp_path, capsys) -> None:
    records = [{"seed": s, "task": "hand-made", "acsg": {"nodes": nodes, "edges": edges}}
               for s, (nodes, edges) in enumerate([
                   ([{"id": "o1", "kind": "object", "instance": 1, "category": "table", "colour": "grey"}], []),
                   ([{"id": "o1", "kind": "object", "instance": 1, "category": "table", "colour": "grey"},
                     {"id": "o2", "kind": "object", "instance": 2, "category": "box", "colour": "red"},
                     {"id": "o3", "kind": "object", "instance": 3, "category": "apple", "colour": "red"},
                     {"id": "pick:2", "kind": "action", "type": "pick", "target": "o2"}],
                    [{"source": "o1", "target": "o2", "type": "object-object", "relation": "on"},
                     {"source": "o2", "target": "pick:2", "type": "object-action", "relation": "can be picked"},
                     {"source": "pick:2", "target": "o3", "type": "action-object", "relation": "reveals"},
                     {"source": "o2", "target": "o3", "type": "object-object", "relation": "inside"}]),
               ])]
    path = tmp_path / "suite.jsonl"
    path.write_text("\n".join(json.dumps(r) for r in records) + "\n")
    assert acsg_main(["plan", str(path), "apple", "--seed", "1"]) == 0
    assert capsys.readouterr().out.splitlines() == ["1. pick away box (o2)", "2. pick apple (o3)"]
    assert acsg_main(["plan", str(path), "apple"]) == 1
    assert "pass a seed" in capsys.readouterr().err
