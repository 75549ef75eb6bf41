"""An episode's Rerun recording (``recording.rrd`` in its run folder), written from the blackboard.

`Recorder.after_tick` runs after every tick of the tree (a py_trees post-tick handler). It only
reads: the values the EQA tree keeps on the blackboard (`behaviours.blackboard` names them), and
the root's status. It logs a value only when it changed (a new observation, a new map revision, a
new step), on two timelines: ``step`` (the answer log's length) and ``tick``. Nothing it does can
end or change the episode: a failure to record is logged, and the episode goes on.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import py_trees
import rerun as rr

from behaviours import blackboard as bb
from agent.app.runtime import recording_log as view
from agent.app.runtime.viewer import LiveViewer

log = logging.getLogger(__name__)


class Recorder:
    """Writes one episode's recording, and streams it to a live viewer when one is given.

    Args:
        path: the ``.rrd`` file to write.
        run_id: the run's id, the recording's id.
        live: a started viewer to stream to as well, or None.
    """

    def __init__(self, path: Path, run_id: str, live: LiveViewer | None = None) -> None:
        self.path = path
        self.stream = rr.RecordingStream("homebot", recording_id=run_id)
        self.stream.set_sinks(rr.FileSink(path), *(live.sinks if live is not None else []))
        self.stream.send_recording_name(run_id)
        self._seen: dict[str, Any] = {}  # what was logged last, per kind: objects by identity, else a value
        self._status: str | None = None
        self._steps_logged = 0
        self._acts_logged = 0
        self._arm_logged = 0  # skill runs of the acts logged

    def after_tick(self, tree: py_trees.trees.BehaviourTree) -> None:
        """Log what changed on the tick just run; never raises.

        Args:
            tree: the tree just ticked (its ``count`` is the ticks before this one).
        """
        try:
            self._record(tree.count + 1, tree.root.status.name)
        except Exception:  # a recording that fails must not fail the tick, and so the episode
            log.exception("recording to %s failed on tick %d", self.path, tree.count + 1)

    def close(self) -> None:
        """Write what is buffered and close the file."""
        try:
            self.stream.flush()
            self.stream.disconnect()
        except Exception:
            log.exception("closing the recording %s failed", self.path)

    def _record(self, tick: int, status: str) -> None:
        board = {key.lstrip("/"): value for key, value in py_trees.blackboard.Blackboard.storage.items()}
        answer_log = board.get(bb.ANSWER_LOG)
        self.stream.set_time("tick", sequence=tick)
        self.stream.set_time("step", sequence=len(answer_log) if answer_log is not None else 0)
        if status != self._status:
            self._status = status
            view.log_status(self.stream, status)
        observation, inside_view = board.get(bb.OBSERVATION), board.get(bb.INSIDE_VIEW)
        if observation is not None and self._changed(bb.OBSERVATION, observation):
            view.log_observation(self.stream, observation)
        if inside_view is not None and self._changed(bb.INSIDE_VIEW, inside_view):
            view.log_inside_view(self.stream, inside_view)
        world_map = board.get(bb.MAP)
        if world_map is not None:
            self._record_map(world_map, board)
        if answer_log is not None:
            for scores in answer_log.steps[self._steps_logged:]:
                view.log_scores(self.stream, scores)
            self._steps_logged = len(answer_log.steps)
        prediction_set = board.get(bb.PREDICTION_SET)
        if prediction_set is not None and self._changed(bb.PREDICTION_SET, tuple(prediction_set)):
            view.log_prediction_set(self.stream, prediction_set)
        acts = board.get(bb.ACTS) or []
        for act in acts[self._acts_logged:]:
            view.log_act(self.stream, f"{act.storage} {act.part}: {act.outcome or act.reason or 'tried'}")
        look_inside = board.get(bb.LOOK_INSIDE_STATE)
        if len(acts) > self._acts_logged and look_inside is not None:  # an act ended: its arm's runs, joints named
            self._arm_logged = view.log_skill_runs(self.stream, look_inside.arm, self._arm_logged)
        self._acts_logged = len(acts)

    def _record_map(self, world_map: Any, board: dict[str, Any]) -> None:
        """The map's layers on a new revision, the route when it grew, the plan when it is new, the
        frontiers weighed and the prompt's lettered points when they changed, and the semantic
        values when they took in a new view."""
        if self._changed(bb.MAP, (id(world_map), world_map.revision)):
            view.log_map(self.stream, world_map)
        trajectory = board.get(bb.TRAJECTORY) or []
        if trajectory and self._changed(bb.TRAJECTORY, (len(trajectory), trajectory[-1])):
            view.log_trajectory(self.stream, world_map.spec, trajectory)
        if bb.PLAN in board and self._changed(bb.PLAN, board[bb.PLAN]):
            view.log_plan(self.stream, world_map.spec, board[bb.PLAN])
        for key, log_points in ((bb.FRONTIER_CHOICES, view.log_frontier_choices),
                                (bb.DIRECTION_PROMPTS, view.log_direction_prompts)):
            points = board.get(key)
            if points is not None and self._changed(key, tuple(points)):
                log_points(self.stream, world_map.spec, points)
        semantic_map = board.get(bb.SEMANTIC_MAP)
        if semantic_map is not None and self._changed(bb.SEMANTIC_MAP, float(semantic_map.weight.sum())):
            view.log_semantic_values(self.stream, semantic_map)

    def _changed(self, kind: str, value: Any) -> bool:
        """Whether ``value`` differs from what was last logged for ``kind``: another object, or for
        the plain keys (tuples, numbers) another value."""
        previous = self._seen.get(kind, _NOTHING)
        if previous is value or (isinstance(value, (tuple, float)) and previous == value):
            return False
        self._seen[kind] = value
        return True


_NOTHING = object()  # what was logged before anything was


def warm_up() -> None:
    """Make once, and drop, what the first tick would log first: Rerun's first array (pyarrow loads
    its pandas support for it, a third of a second). For a thread started while the world comes
    up, so that the episode's first tick does not wait for it; nothing is logged."""
    rr.Scalars(0.0)
