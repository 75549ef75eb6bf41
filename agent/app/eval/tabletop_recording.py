"""A tabletop episode's Rerun recording: the action-conditioned scene graph it explored, and for the
robot's episodes the arm's joints after each skill run.

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
from agent.app.runtime.recording_log import log_skill_runs
from skills.skill_runs import SkillRuns

log = logging.getLogger(__name__)

ACSG_ENTITY = "acsg"


def record_graph(folder: Path, run_id: str, graph: ACSG, skills: SkillRuns | None = None) -> None:
    """Write ``<folder>/recording.rrd`` with the explored graph: its nodes (objects by label, actions
    by type and target) and its edges, directed; and, given ``skills``, on the ``skill`` timeline
    (one step per run) each run's name and outcome and the arm's joints it ended with, a scalar per
    joint under ``arm/joints/<joint>``.

    Args:
        folder: the scene's folder (made when missing).
        run_id: the recording's id.
        graph: the explored graph.
        skills: the skill runs, or None.
    """
    try:
        folder.mkdir(parents=True, exist_ok=True)
        stream = rr.RecordingStream("homebot", recording_id=run_id)
        stream.set_sinks(rr.FileSink(folder / RECORDING_FILE))
        nodes = [node.to_dict() for node in graph.nodes()]
        labels = [entry.get("label") or f"{entry['type']} {entry['target']}" for entry in nodes]
        stream.log(ACSG_ENTITY, rr.GraphNodes([entry["id"] for entry in nodes], labels=labels),
                   rr.GraphEdges([(edge.source, edge.target) for edge in graph.edges()], graph_type="directed"))
        if skills is not None:
            log_skill_runs(stream, skills, 0)
        stream.flush()
        stream.disconnect()
    except Exception:  # a recording must not cost the evaluation its result
        log.exception("no recording of %s: %s could not be written", run_id, folder)

