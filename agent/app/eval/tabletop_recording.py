"""A tabletop episode's Rerun recording: the action-conditioned scene graph it explored.

Written as ``recording.rrd`` in the scene's folder under an interactive evaluation's
``recordings/`` when ``homebot eval interactive --record`` asks for it; `homebot replay` opens it.
A recording that cannot be written is logged and the evaluation goes on.
"""

from __future__ import annotations

import logging
from pathlib import Path

import rerun as rr

from agent.acsg.graph import ACSG
from agent.app.runtime.viewer import RECORDING_FILE

log = logging.getLogger(__name__)

ACSG_ENTITY = "acsg"


def record_graph(folder: Path, run_id: str, graph: ACSG) -> None:
    """Write ``<folder>/recording.rrd`` with the explored graph: its nodes (objects by label, actions
    by type and target) and its edges, directed.

    Args:
        folder: the scene's folder (made when missing).
        run_id: the recording's id.
        graph: the explored graph.
    """
    try:
        folder.mkdir(parents=True, exist_ok=True)
        stream = rr.RecordingStream("homebot", recording_id=run_id)
        stream.set_sinks(rr.FileSink(folder / RECORDING_FILE))
        nodes = [node.to_dict() for node in graph.nodes()]
        labels = [entry.get("label") or f"{entry['type']} {entry['target']}" for entry in nodes]
        stream.log(ACSG_ENTITY, rr.GraphNodes([entry["id"] for entry in nodes], labels=labels),
                   rr.GraphEdges([(edge.source, edge.target) for edge in graph.edges()], graph_type="directed"))
        stream.flush()
        stream.disconnect()
    except Exception:  # a recording must not cost the evaluation its result
        log.exception("no recording of %s: %s could not be written", run_id, folder)
