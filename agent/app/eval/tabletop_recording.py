"""A tabletop episode's Rerun recording: the action-conditioned scene graph it explored, and for the
robot's episodes the arm's joints after each skill run.

Written as ``recording.rrd`` in the scene's folder under an interactive evaluation's
``recordings/`` when ``homebot eval interactive --record`` asks for it; `homebot replay` opens it.
A recording that cannot be written is logged and the evaluation goes on.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import rerun as rr

from agent.acsg.graph import ACSG
from agent.app.runtime.viewer import RECORDING_FILE
from skills.base import SkillResult

log = logging.getLogger(__name__)

ACSG_ENTITY = "acsg"
ARM_JOINTS = "arm/joints"
SKILL_LOG = "arm/skill"


@dataclass
class SkillRuns:
    """Each skill run's name, whether it succeeded and the arm's joints it ended with, in order; a
    `skills.robot_body.RobotBody` skill listener."""

    runs: list[tuple[str, bool, np.ndarray | None]] = field(default_factory=list)

    def __call__(self, name: str, result: SkillResult) -> None:
        """Keep one run.

        Args:
            name: the skill's registered name.
            result: how it went.
        """
        self.runs.append((name, result.ok, result.joints))


def record_graph(folder: Path, run_id: str, graph: ACSG, skills: SkillRuns | None = None,
                 joint_names: Sequence[str] = ()) -> None:
    """Write ``<folder>/recording.rrd`` with the explored graph: its nodes (objects by label, actions
    by type and target) and its edges, directed; and, given ``skills``, on the ``skill`` timeline
    (one step per run) each run's name and outcome and the arm's joints it ended with, a scalar per
    joint under ``arm/joints/<joint>``.

    Args:
        folder: the scene's folder (made when missing).
        run_id: the recording's id.
        graph: the explored graph.
        skills: the skill runs, or None.
        joint_names: the arm's joints in the order of the runs' positions (``joint<i>`` where unknown).
    """
    try:
        folder.mkdir(parents=True, exist_ok=True)
        stream = rr.RecordingStream("homebot", recording_id=run_id)
        stream.set_sinks(rr.FileSink(folder / RECORDING_FILE))
        nodes = [node.to_dict() for node in graph.nodes()]
        labels = [entry.get("label") or f"{entry['type']} {entry['target']}" for entry in nodes]
        stream.log(ACSG_ENTITY, rr.GraphNodes([entry["id"] for entry in nodes], labels=labels),
                   rr.GraphEdges([(edge.source, edge.target) for edge in graph.edges()], graph_type="directed"))
        for index, (name, ok, joints) in enumerate(skills.runs if skills is not None else [], start=1):
            stream.set_time("skill", sequence=index)
            stream.log(SKILL_LOG, rr.TextLog(f"{name}: {'done' if ok else 'failed'}", level="INFO" if ok else "WARN"))
            for j, position in enumerate(joints if joints is not None else []):
                joint = joint_names[j] if j < len(joint_names) else f"joint{j}"
                stream.log(f"{ARM_JOINTS}/{joint}", rr.Scalars(float(position)))
        stream.flush()
        stream.disconnect()
    except Exception:  # a recording must not cost the evaluation its result
        log.exception("no recording of %s: %s could not be written", run_id, folder)
