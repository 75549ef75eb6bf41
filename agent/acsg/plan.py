"""Object retrieval from an ACSG (RoboEXP §III-A, App. I-B).

To fetch an object, run every action on the paths from the roots to its node, in topological
order, then take it: "to reach the tape inside a cabinet whose door is blocked by a condiment:
1) pick up the condiment, 2) open the cabinet, 3) retrieve the tape". The graph's edges already say
which actions matter: reveal edges lead from the action that uncovers a thing to it, precondition
edges from the action that must come first, so the actions among a node's ancestors are exactly
what must be done, and the DAG's order is an order that works.
"""

from __future__ import annotations

from agent.acsg.graph import ACSG
from agent.acsg.nodes import ActionNode, ObjectNode
from agent.acsg.order import ancestors, topological_order

_VERB = {"open": "open", "close": "close", "pick": "pick away", "place": "place", "look": "look at"}


def retrieval_actions(graph: ACSG, target: ObjectNode | str) -> list[ActionNode]:
    """The actions to run before ``target`` (a node, id, instance or label) can be taken.

    Args:
        graph: the graph.
        target: the object.

    Returns:
        The actions, in order.

    Raises:
        UnknownObjectError: the target is unknown or ambiguous.
    """
    node = target if isinstance(target, ObjectNode) else graph.find_object(target)
    before = ancestors(graph, node.id)
    return [graph.action(n) for n in topological_order(graph, before) if graph.node(n).kind == "action"]


def describe_action(graph: ACSG, action: ActionNode) -> str:
    """'open door (o6)', 'pick away bottle (o4)': the verb, what it acts on and that node's id.

    Args:
        graph: the graph.
        action: the action.

    Returns:
        The description.
    """
    target = graph.object(action.target)
    return f"{_VERB.get(action.type, action.type)} {target.label} ({target.id})"


def retrieval_plan(graph: ACSG, object_label_or_id: str, take: bool = True) -> list[str]:
    """The steps to fetch an object, as text: the actions in order, then picking it (``take``).

    Unknown or ambiguous names raise `UnknownObjectError` (a ValueError) that lists the choices.

    Args:
        graph: the graph.
        object_label_or_id: the object.
        take: whether picking it ends the plan.

    Returns:
        The steps.

    Raises:
        UnknownObjectError: the object is unknown or ambiguous.
    """
    node = graph.find_object(object_label_or_id)
    steps = [describe_action(graph, action) for action in retrieval_actions(graph, node)]
    if take:
        steps.append(f"pick {node.label} ({node.id})")
    return steps
