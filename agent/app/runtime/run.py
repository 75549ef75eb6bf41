"""One EQA episode from start to finish: bring up or join a world, run the tree, record the run."""

from __future__ import annotations

import json
import logging
import threading
import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

import py_trees

from behaviours import blackboard as bb
from worlds.bus.keys import Keys
from worlds.bus.rpc import QueryFailed
from agent.app.config import Config
from agent.eqa.calibration import CalibrationError
from agent.app.runtime.calibrations import calibration_for
from agent.eqa.stopping import StopRuleName, StoppingRule, make_rule
from agent.mapping.occupancy import ExplorationMap
from agent.app.runtime.control import EpisodeControl
from agent.app.runtime.control_bus import ControlServer
from agent.app.runtime.episode import EpisodeOutcome, EpisodeRunner, SnapshotSink
from agent.app.runtime.episode_bus import EpisodeBus
from agent.app.runtime.plugged import PlugError, make_plugged_skills, plug_into
from agent.app.runtime.record import SnapshotLog, write_json_atomic
from agent.app.runtime.recording import Recorder, warm_up
from agent.app.runtime.request import RunRequest
from agent.app.runtime.viewer import RECORDING_FILE
from agent.pose import Pose2D
from agent.timing import StageTimer
from worlds.bus.link import WorldLink
from agent.app.runtime.world_process import WorldStartError
from agent.vlm.backends import make_vlm
from agent.vlm.errors import VLMError
from agent.vlm.protocol import VisionLanguageModel
from behaviours.eqa_tree import EqaTreeParts, build_eqa_tree
from skills.ports import PortedSkill
from worlds.bus.questions import LETTERS

log = logging.getLogger(__name__)


class RunError(RuntimeError):
    """The episode could not start (no world, a bad reset); the run folder says so too."""


def run_episode(request: RunRequest, timer: StageTimer | None = None,
                extra_sinks: list[SnapshotSink] | None = None, bus: EpisodeBus | None = None) -> dict[str, Any]:
    """Run one episode and return its result (also written to ``<out_root>/<run_id>/result.json``).

    Args:
        request: what to run: seed, settings, scene, where results go, which world.
        timer: times the stages, if given.
        extra_sinks: where else the tree's snapshots go.
        bus: the episode's end of the bus, opened beforehand for this request (`EpisodeBus.open`),
            its world perhaps started already; opened here when None, closed here either way.
            The world is started once the settings proved usable (the VLM, the calibration, the
            skills plugged into the tree), unless it was started before.

    Returns:
        The result.
    """
    started_at = time.time() if request.started_at is None else request.started_at
    bus = bus or EpisodeBus.open(request)
    config, folder, link = request.config, bus.folder, bus.link
    result: dict[str, Any] = {"run_id": bus.run_id, "seed": request.seed, "namespace": bus.namespace,
                              "world": "connected" if request.connect else "spawned", "endpoint": bus.endpoint,
                              "listen": bus.listen}
    first_observation = FirstObservation()
    try:
        vlm = make_vlm(config.vlm)  # a bad model path or backend fails now
        stopping, result["stop"] = _stopping_rule(config)  # so does a calibration that does not fit
        plugged = make_plugged_skills(config.tree, link)  # and a skill the settings put into the tree
        bus.start_world()
        if request.record:
            threading.Thread(target=warm_up, name="recording warm-up", daemon=True).start()
        bus.wait_ready(config.bus.world_start_timeout_s)
        reset_request: dict[str, Any] = {"seed": request.seed}
        if request.scenario is not None:
            reset_request["scenario"] = request.scenario
        if request.scene is not None:
            reset_request["scene"] = request.scene
        reset = link.call("reset", reset_request, timeout_s=config.bus.world_start_timeout_s)
        scenario = reset.meta["scenario"]
        result.update(_scenario_fields(scenario, config))
        recorder = _recorder(request, folder / RECORDING_FILE, bus.run_id)
        outcome, world_map, trajectory = _run_tree(bus.run_id, scenario, reset.meta, config, vlm, stopping, link,
                                                   bus.session, Keys(bus.namespace), folder, timer,
                                                   extra_sinks or [], plugged, recorder, first_observation)
        evaluation = _episode_report(link, config.bus.query_timeout_s) if _world_may_report(outcome, link) else None
    except (WorldStartError, QueryFailed, KeyError, VLMError, CalibrationError, PlugError) as error:
        ended = "" if isinstance(error, WorldStartError) else bus.world_log()  # a start error says it already
        reason = f"the episode could not start: {error}{ended}"
        result.update({"status": "failed", "reason": reason, "correct": False})
        write_json_atomic(folder / "result.json", result)
        raise RunError(f"{reason}\n(run folder: {folder})") from None
    except KeyboardInterrupt:  # before the tree ran: nothing to keep but the record of it
        result.update({"status": "interrupted", "reason": "interrupted (SIGINT) before the episode began",
                       "correct": False})
        write_json_atomic(folder / "result.json", result)
        return {**result, "folder": str(folder)}
    finally:
        bus.close()
    if first_observation.at is not None:
        result["startup_s"] = round(first_observation.at - started_at, 3)
    result.update(_outcome_fields(outcome, result))
    result["evaluation"] = evaluation
    if timer is not None:
        result["timings"] = timer.summary()
    write_json_atomic(folder / "result.json", result)
    if request.save_map:
        from agent.app.runtime.plots import save_map_png  # matplotlib is loaded only to draw

        save_map_png(folder / "map.png", world_map, trajectory, result)
    result["folder"] = str(folder)
    return result


def _run_tree(run_id: str, scenario: dict[str, Any], reset_meta: dict[str, Any], config: Config,
              vlm: VisionLanguageModel, stopping: StoppingRule,
              link: WorldLink, session: Any, keys: Keys, folder: Path, timer: StageTimer | None,
              extra_sinks: list[SnapshotSink], plugged: list[tuple[str, PortedSkill]],
              recorder: Recorder | None = None, first_observation: FirstObservation | None = None
              ) -> tuple[EpisodeOutcome, ExplorationMap, list]:
    py_trees.blackboard.Blackboard.clear()
    start = Pose2D.of(reset_meta["base_pose"])
    writer = bb.seed_board(bb.EpisodeStart(scenario["question"], list(scenario["choices"]),
                                           config.episode.budget or int(scenario["budget"]), start, config.map,
                                           config.explore.strategy, config.semantic_values))
    parts = EqaTreeParts(link, vlm, config.explore, config.episode.vlm_timeout_s,
                         config.bus.move_timeout_s, timer, config.prompt_points, config.semantic_values,
                         config.frontier_weights, int(scenario["seed"]), folder / "prompts", stopping,
                         act=config.act)
    publisher = session.declare_publisher(keys.agent_tree)
    events = session.declare_publisher(keys.agent_events)
    snapshot_log = SnapshotLog(folder / "snapshots.jsonl")
    sinks = [snapshot_log, lambda data: publisher.put(json.dumps(data, ensure_ascii=False)), *extra_sinks]
    events.put(json.dumps({"event": "started", "run": run_id, "question": scenario["question"]}))
    root = build_eqa_tree(parts)
    plug_into(root, plugged)
    control = EpisodeControl(behaviour.name for behaviour in root.iterate())
    runner = EpisodeRunner(root, run_id, sinks, config.episode.max_seconds, config.episode.tick_period_s,
                           timer, control, config.episode.max_wait_s)
    control_server = ControlServer(session, keys, control)
    if first_observation is not None:
        runner.tree.add_post_tick_handler(first_observation)
    if recorder is not None:
        runner.tree.add_post_tick_handler(recorder.after_tick)
    try:
        outcome = runner.run()
    finally:
        control_server.close()
        snapshot_log.close()
        if recorder is not None:
            recorder.close()
    if control.injected:
        outcome.extra["injected"] = control.injected
    log_of_steps = writer.get(bb.ANSWER_LOG)
    outcome.extra["steps"] = len(log_of_steps)
    outcome.extra["step_scores"] = [s.to_record() for s in log_of_steps.steps]
    writer.register_key(bb.PREDICTION_SET, access=py_trees.common.Access.READ)
    outcome.extra["prediction_set"] = writer.get(bb.PREDICTION_SET)
    outcome.extra["acts"] = [act.to_record() for act in writer.get(bb.ACTS)]
    bound = frozenset().union(*(skill.bound_keys() for _, skill in plugged))
    problems = bb.contract_problems(py_trees.blackboard.Blackboard.storage, bound)
    if problems:  # a leaf that wrote what the contract does not say: a bug to see, not to hide
        log.error("the blackboard breaks the EQA tree's contract: %s", "; ".join(problems))
        outcome.extra["contract_problems"] = problems
    events.put(json.dumps({"event": "ended", "run": run_id, **asdict(outcome)}, default=str))
    publisher.undeclare()
    events.undeclare()
    world_map, trajectory = writer.get(bb.MAP), writer.get(bb.TRAJECTORY)
    # The blackboard is global: clearing it frees this episode's TSDF now rather than at
    # interpreter exit, where open3d reports any device memory still held as a leak and fails.
    py_trees.blackboard.Blackboard.clear()
    return outcome, world_map, trajectory


class FirstObservation:
    """A post-tick handler that notes when (epoch s) the first tick that put an observation on the
    board ended: the episode's first frame is in, decoded and on the board."""

    def __init__(self) -> None:
        self.at: float | None = None

    def __call__(self, tree: py_trees.trees.BehaviourTree) -> None:
        if self.at is None and py_trees.blackboard.Blackboard.exists(bb.OBSERVATION):
            self.at = time.time()


def _recorder(request: RunRequest, path: Path, run_id: str) -> Recorder | None:
    """The episode's recorder when it records; None when it does not, or when the recording cannot
    be opened (that is logged: no recording ends an episode)."""
    if not request.record:
        return None
    try:
        return Recorder(path, run_id, request.viewer)
    except Exception:
        log.exception("no recording of this episode: %s could not be opened", path)
        return None


def _world_may_report(outcome: EpisodeOutcome, link: WorldLink) -> bool:
    """Whether to ask the world for its report: only while its token is there (not when it is gone,
    or went silent), and not after Ctrl-C (which a world started here had too, and which ends the
    command in moments)."""
    return outcome.status != "interrupted" and link.liveness.alive and link.liveness.gone() is None


def _episode_report(link: WorldLink, timeout_s: float) -> dict[str, Any] | None:
    """The world's evaluator-side record of the episode (worlds.evaluation), fetched here, after the
    tree has finished, so no behaviour and no VLM ever sees it; None when the world cannot say
    (it is gone, or predates the command)."""
    try:
        reply = link.call("episode_report", {}, timeout_s=timeout_s).meta
    except QueryFailed as error:
        log.warning("no evaluator's report of the episode: %s", error)
        return None
    return {key: value for key, value in reply.items() if key not in ("ok", "namespace")}


def _stopping_rule(config: Config) -> tuple[StoppingRule, dict[str, Any]]:
    """The configured stopping rule and what the run record says about it."""
    stop = config.stop
    if stop.rule != StopRuleName.CP:
        threshold = {StopRuleName.ENTROPY: stop.entropy_threshold,
                     StopRuleName.RELEVANCE: stop.relevance_threshold}.get(StopRuleName(stop.rule))
        return make_rule(stop, None, LETTERS), {"rule": stop.rule, "threshold": threshold}
    calibration, path = calibration_for(config)
    q_hat = calibration.q_hat(stop.epsilon)
    if q_hat == float("inf"):
        log.warning("stop.epsilon %g is below 1/(N+1) for the %d calibration episodes of %s: "
                    "the conformal set never shrinks, so the robot explores to its budget",
                    stop.epsilon, len(calibration.episodes), path)
    record = {"rule": stop.rule, "epsilon": stop.epsilon, "q_hat": q_hat if q_hat != float("inf") else None,
              "calibration": str(path), "calibration_episodes": len(calibration.episodes)}
    return make_rule(stop, q_hat, LETTERS), record


def _scenario_fields(scenario: dict[str, Any], config: Config) -> dict[str, Any]:
    truth = scenario["answer"]
    return {
        "question": scenario["question"],
        "choices": scenario["choices"],
        "kind": scenario.get("kind"),
        "ground_truth": truth,
        "ground_truth_text": scenario["choices"][LETTERS.index(truth)],
        "budget": config.episode.budget or int(scenario["budget"]),
    }


def _outcome_fields(outcome: EpisodeOutcome, result: dict[str, Any]) -> dict[str, Any]:
    answer = outcome.answer or {}
    letter = answer.get("letter")
    return {
        "status": outcome.status,
        "reason": outcome.reason,
        "failed_behaviour": outcome.failed_behaviour,
        "answer": letter,
        "answer_text": answer.get("text"),
        "correct": letter is not None and letter == result["ground_truth"],
        "answer_detail": answer or None,
        "steps": outcome.extra.get("steps", 0),
        "step_scores": outcome.extra.get("step_scores", []),
        "prediction_set": outcome.extra.get("prediction_set"),
        "acts": outcome.extra.get("acts", []),
        "ticks": outcome.ticks,
        "seconds": round(outcome.seconds, 3),
        **({"contract_problems": outcome.extra["contract_problems"]} if "contract_problems" in outcome.extra else {}),
        **({"injected": outcome.extra["injected"]} if "injected" in outcome.extra else {}),
    }
