"""Table I metrics on hand-made graphs and states with known answers."""

from __future__ import annotations

import math

import pytest

from agent.acsg.graph import ACSG
from agent.acsg.metrics import (
    aligned_edit_distance,
    edit_distance,
    episode_metrics,
    graph_edit_distance,
    hidden_objects,
    is_success,
    mean_and_sem,
    need_to_explore,
    object_recovery,
    position_recovery,
    scene_restored,
    state_recovery,
    unexplored_space,
)


def scene(missing_apple: bool = False, prefix: str = "o", banana_label: str = "banana",
          apple_relation: str = "inside") -> ACSG:
    """A cabinet with a bottle in front of its door and an apple and a banana inside."""
    g = ACSG()
    for name, label in [("1", "table"), ("2", "cabinet"), ("3", "door"), ("4", "handle"), ("5", "bottle"),
                        ("6", "apple"), ("7", banana_label)]:
        if not (missing_apple and name == "6"):
            g.add_object(f"{prefix}{name}", label)
    n = lambda i: f"{prefix}{i}"  # noqa: E731
    g.add_edge(n(1), n(2), relation="on")
    g.add_edge(n(2), n(3), relation="belongs")
    g.add_edge(n(3), n(4), relation="belongs")
    g.add_edge(n(1), n(5), relation="on")
    g.add_action(f"open:{prefix}3", "open", n(3), state="explored")
    g.add_action(f"pick:{prefix}5", "pick", n(5), state="explored")
    g.add_edge(f"pick:{prefix}5", f"open:{prefix}3")
    for i in ("6", "7"):
        if missing_apple and i == "6":
            continue
        g.add_edge(n(2), n(i), relation=apple_relation if i == "6" else "inside")
        g.add_edge(f"open:{prefix}3", n(i))
    return g


# ---- graph edit distance and success ---------------------------------------------------------------

def test_identical_graphs_are_zero_apart_and_a_success() -> None:
    assert graph_edit_distance(scene(), scene()) == 0.0
    assert edit_distance(scene(), scene()).exact
    assert is_success(scene(), scene())


def test_a_missing_object_costs_its_node_and_its_edges() -> None:
    # the apple node, its 'inside' edge and its 'reveals' edge: 3 operations
    assert graph_edit_distance(scene(missing_apple=True), scene()) == 3.0
    assert graph_edit_distance(scene(), scene(missing_apple=True)) == 3.0
    assert not is_success(scene(missing_apple=True), scene())


def test_one_missing_node_and_edge_costs_two() -> None:
    truth = scene()
    truth.add_object("o8", "cup")
    truth.add_edge("o1", "o8", relation="on")
    assert aligned_edit_distance(scene(), truth) == 2
    assert graph_edit_distance(scene(), truth) == 2.0


def test_substitutions_cost_one() -> None:
    assert graph_edit_distance(scene(banana_label="plum"), scene()) == 1.0  # node label edited
    assert graph_edit_distance(scene(apple_relation="under"), scene()) == 1.0  # edge relation edited


def test_node_ids_do_not_matter() -> None:
    other = scene(prefix="n")
    assert aligned_edit_distance(other, scene()) > 0  # the id matching is only a bound
    assert graph_edit_distance(other, scene()) == 0.0
    assert is_success(other, scene())


def test_a_ground_truth_scene_against_itself_with_an_object_dropped() -> None:
    from agent.acsg.json_format import from_ground_truth
    from worlds.tabletop import tabletop_variant

    truth = tabletop_variant("drawer-door", 1).ground_truth_acsg()
    leaf = next(e["target"] for e in truth["edges"] if e["type"] == "action-object")
    fewer = {"nodes": [n for n in truth["nodes"] if n["id"] != leaf],
             "edges": [e for e in truth["edges"] if leaf not in (e["source"], e["target"])]}
    result = edit_distance(from_ground_truth(fewer), from_ground_truth(truth), timeout_s=20.0)
    assert result.value == 3.0 and result.exact


# ---- recovery and unexplored space -----------------------------------------------------------------

def test_object_recovery_counts_hidden_objects_found() -> None:
    truth = scene()
    assert sorted(hidden_objects(truth)) == ["o6", "o7"]
    assert object_recovery(scene(), truth) == 1.0
    assert object_recovery(scene(missing_apple=True), truth) == 0.5
    assert object_recovery(scene(missing_apple=True), truth, by="id") == 0.5
    assert object_recovery(scene(prefix="n"), truth, by="label") == 1.0
    assert object_recovery(scene(prefix="n"), truth, by="id") == 0.0
    with pytest.raises(ValueError, match="by: 'name'"):
        object_recovery(scene(), truth, by="name")


def test_position_and_state_recovery() -> None:
    start = {"5": (0.0, 0.0, 0.8), "6": (0.1, 0.2, 0.8), "7": (0.3, 0.2, 0.8), "8": (0.5, 0.0, 0.8)}
    final = {"5": (0.0, 0.005, 0.8), "6": (0.1, 0.25, 0.8), "7": (0.3, 0.2, 0.8)}  # 8 lost, 6 moved 5 cm
    assert position_recovery(start, final, tolerance_m=0.01) == 0.5
    assert position_recovery(start, final, tolerance_m=0.1) == 0.75
    assert position_recovery({}, {}) == 1.0
    states = {"door": 0.0, "drawer": 0.0, "flap": 0.0, "lid": 0.0}
    assert state_recovery(states, {"door": 0.0, "drawer": 0.3, "flap": 0.0, "lid": 0.0}) == 0.75
    assert scene_restored(start, start, states, states)
    assert not scene_restored(start, final, states, states)
    assert not scene_restored(start, start, states, {**states, "lid": 1.0})


def test_unexplored_space_counts_opens_and_revealing_picks_only() -> None:
    truth = scene()
    truth.add_object("o8", "box")
    truth.add_object("o9", "doll")
    truth.add_edge("o1", "o8", relation="on")
    truth.add_action("pick:o8", "pick", "o8")
    truth.add_edge("o8", "o9", relation="inside")
    truth.add_edge("pick:o8", "o9")
    assert need_to_explore(truth) == ["open:o3", "pick:o8"]  # the bottle's pick only clears the way
    assert unexplored_space(truth, ["open:o3"]) == 0.5
    assert unexplored_space(truth, ["open:o3", "pick:o8", "pick:o5"]) == 0.0
    assert unexplored_space(truth, scene()) == 0.5  # a graph counts its explored actions
    assert unexplored_space(ACSG(), []) == 0.0


def test_episode_metrics_and_table_summary() -> None:
    m = episode_metrics(scene(missing_apple=True), scene(), {"5": (0, 0, 0)}, {"5": (0, 0, 0)}, {"3": 0.0},
                        {"3": 1.0})
    assert not m.success and m.graph_edit_distance == 3.0 and m.object_recovery == 0.5
    assert m.position_recovery == 1.0 and m.state_recovery == 0.0 and not m.state_recovered
    assert m.unexplored_space == 0.0
    assert set(m.as_dict()) >= {"success", "graph_edit_distance", "unexplored_space"}
    mean, sem = mean_and_sem([1, 1, 1, 0])
    assert mean == 0.75 and sem == pytest.approx(math.sqrt(0.25 / 4))
    assert mean_and_sem([2.0]) == (2.0, 0.0)
    with pytest.raises(ValueError):
        mean_and_sem([])
