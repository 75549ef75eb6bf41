"""The ACSG as JSON: our format, the ground truth's, and the files that hold either.

Our JSON (`FORMAT`, `VERSION`) keeps the ground truth's edge fields, so the two read alike; the
ground truth of `worlds.tabletop_scene` itself converts with `from_ground_truth`, and
`acsg_from_dict` takes either, or a suite record holding one.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from agent.acsg.graph import ACSG
from agent.acsg.nodes import ACSGError, ActionNode, ObjectNode
from agent.acsg.primitives import PICK_AWAY, open_primitive

FORMAT = "homebot.acsg"
VERSION = 1


def acsg_to_dict(graph: ACSG) -> dict[str, Any]:
    """The graph in our format, for files and suite records.

    Args:
        graph: the graph.

    Returns:
        A JSON-able dict: format, version, meta, nodes (insertion order), edges.
    """
    return {"format": FORMAT, "version": VERSION, "meta": dict(graph.meta),
            "nodes": [n.to_dict() for n in graph.nodes()],
            "edges": [e.to_dict() for e in graph.edges()]}


def acsg_from_dict(data: Mapping[str, Any]) -> ACSG:
    """Read our format, a ground-truth ACSG (`worlds.tabletop_scene`), or a suite record holding one.

    Args:
        data: the parsed JSON.

    Returns:
        The graph.

    Raises:
        ACSGError: neither format, an unknown version, or a node or edge that breaks the rules.
    """
    if not isinstance(data, Mapping):
        raise ACSGError(f"acsg: expected a JSON object, got {type(data).__name__}")
    if "format" not in data:
        if "acsg" in data:
            return acsg_from_dict(data["acsg"])
        if "nodes" in data and "edges" in data:
            return from_ground_truth(data)
        raise ACSGError("acsg: neither our format (no 'format' field) nor a ground-truth graph (no 'nodes')")
    if data["format"] != FORMAT:
        raise ACSGError(f"acsg format: {data['format']!r} is not {FORMAT!r}")
    if not isinstance(data.get("version"), int) or not 1 <= data["version"] <= VERSION:
        raise ACSGError(f"acsg version: {data.get('version')!r}; this reader knows versions 1 to {VERSION}")
    graph = ACSG(data.get("meta"))
    for index, entry in enumerate(data.get("nodes", [])):
        kind = entry.get("kind")
        if kind == "object":
            graph.add_node(ObjectNode.from_dict(entry))
        elif kind == "action":
            graph.add_node(ActionNode.from_dict(entry))
        else:
            raise ACSGError(f"nodes[{index}].kind: {kind!r} is neither 'object' nor 'action'")
    for index, entry in enumerate(data.get("edges", [])):
        try:
            graph.add_edge(entry["source"], entry["target"], entry.get("type"), entry.get("relation"))
        except KeyError as missing:
            raise ACSGError(f"edges[{index}]: missing field {missing}") from None
    for action in graph.actions():
        if action.target not in graph:
            raise ACSGError(f"action {action.id}: target {action.target!r} is not in the graph")
    return graph


def from_ground_truth(data: Mapping[str, Any]) -> ACSG:
    """The ground-truth JSON of `TabletopScene.ground_truth_acsg` as an `ACSG`, to score against.

    Object labels are the categories (colour goes to the attributes); every node counts as
    explored, since the ground truth is what a finished exploration should hold.

    Args:
        data: the ground truth's JSON.

    Returns:
        The graph.

    Raises:
        ACSGError: a missing field or an unknown node kind.
    """
    graph = ACSG({key: data[key] for key in ("task", "seed") if key in data})
    nodes = data.get("nodes")
    if not isinstance(nodes, list):
        raise ACSGError("ground truth: 'nodes' must be a list")
    for index, entry in enumerate(nodes):
        try:
            if entry["kind"] == "object":
                attributes = {k: entry[k] for k in ("colour",) if k in entry}
                graph.add_object(entry["id"], entry["category"], instance=entry.get("instance"),
                                 attributes=attributes, explored=True)
        except KeyError as missing:
            raise ACSGError(f"ground truth nodes[{index}]: missing field {missing}") from None
    for index, entry in enumerate(nodes):
        if entry["kind"] == "action":
            try:
                target = graph.object(entry["target"])
                primitive = open_primitive(target.label) if entry["type"] == "open" else PICK_AWAY
                params = {k: entry[k] for k in ("handle",) if k in entry}
                graph.add_node(ActionNode(entry["id"], entry["type"], target.id, primitive, params, "explored"))
            except KeyError as missing:
                raise ACSGError(f"ground truth nodes[{index}]: missing field {missing}") from None
        elif entry["kind"] != "object":
            raise ACSGError(f"ground truth nodes[{index}].kind: {entry['kind']!r} is neither 'object' nor 'action'")
    for index, entry in enumerate(data.get("edges", [])):
        try:
            graph.add_edge(entry["source"], entry["target"], entry["type"], entry["relation"])
        except KeyError as missing:
            raise ACSGError(f"ground truth edges[{index}]: missing field {missing}") from None
    return graph


def save_acsg(graph: ACSG, path: Path | str) -> Path:
    """Write the graph to a file in our format, for `load_acsg` and ``homebot acsg``.

    Args:
        graph: the graph.
        path: the file to write.

    Returns:
        The path written.
    """
    path = Path(path)
    path.write_text(json.dumps(acsg_to_dict(graph), indent=2) + "\n")
    return path


def load_acsg(path: Path | str, seed: int | None = None) -> ACSG:
    """An ACSG from a file: our JSON, a ground-truth graph, a suite record, or a suite's JSON lines.

    Args:
        path: the file.
        seed: picks the record of a JSON-lines file; without it the file must hold one.

    Returns:
        The graph.

    Raises:
        ACSGError: the file cannot be read, is not JSON, holds no single matching record, or
            holds a graph that breaks the rules.
    """
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as error:
        raise ACSGError(f"{path}: cannot read ({error.strerror})") from None
    if path.suffix == ".jsonl":
        records = [json.loads(line) for line in text.splitlines() if line.strip()]
        if seed is not None:
            records = [r for r in records if r.get("seed") == seed]
        if len(records) != 1:
            which = f"seed {seed}" if seed is not None else "one record (pass a seed)"
            raise ACSGError(f"{path}: expected {which}, found {len(records)} records")
        return acsg_from_dict(records[0])
    try:
        data = json.loads(text)
    except json.JSONDecodeError as error:
        raise ACSGError(f"{path}: not JSON ({error.msg} at line {error.lineno})") from None
    return acsg_from_dict(data)
