"""What one blackboard value looks like in a Rerun recording: the archetypes logged for it, and
where (the entity paths `homebot replay` and the tests read back).

Each function logs one kind of value at the stream's current time; `agent.app.runtime.recording`
decides when. The 2D map is drawn with north up: map images are flipped so that image rows run
from the map's top (largest y) down, and the path and plan are given in those pixels.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import rerun as rr

from agent.eqa.answers import StepScores
from agent.mapping.grid import GridSpec
from agent.mapping.occupancy import ExplorationMap
from agent.mapping.semantic_map import SemanticMap
from agent.observation import Observation
from agent.planning.frontier_plan import MovePlan
from agent.pose import Pose2D
from behaviours.choices import DirectionPrompt, FrontierChoice
from skills.skill_runs import SkillRuns

ARM_JOINTS = "arm/joints"  # a scalar per joint, after each skill run
SKILL_LOG = "arm/skill"  # each skill run's name and outcome
CAMERA = "world/camera"
RGB = f"{CAMERA}/rgb"
DEPTH = f"{CAMERA}/depth"
SEGMENTATION = f"{CAMERA}/segmentation"
WORLD_TRAJECTORY = "world/trajectory"
MAP_LAYERS = ("explored", "occupied", "free")
MAP_TRAJECTORY = "map/trajectory"
PLAN_PATH = "map/plan/path"
PLAN_FRONTIER = "map/plan/frontier"
SEMANTIC_VALUES = "map/semantic_value"
FRONTIERS = "map/frontiers"
MAP_PROMPTS = "map/prompts"
WORLD_PROMPTS = "world/prompts"
ANSWERS = "answers"
RELEVANCE = "answers/relevance"
PREDICTION_SET = "answers/prediction_set"
TREE_STATUS = "tree/status"
TREE_STATUS_TEXT = "tree/status_text"
INSIDE_VIEW = "acts/inside_view"
ACT_LOG = "acts/log"

#: The tree's root status as a number, for the status plot.
STATUS_CODES = {"INVALID": 0.0, "RUNNING": 1.0, "SUCCESS": 2.0, "FAILURE": -1.0}


def log_observation(stream: rr.RecordingStream, observation: Observation) -> None:
    """The head camera: where it stood (pose and intrinsics), and its colour, depth and segmentation,
    the segmentation labelled with the frame's instances.

    Args:
        stream: the recording.
        observation: the frame.
    """
    intrinsics = observation.intrinsics
    pose = observation.camera_to_world
    stream.log(CAMERA, rr.Transform3D(translation=pose[:3, 3], mat3x3=pose[:3, :3]),
               rr.Pinhole(image_from_camera=intrinsics.matrix(), resolution=[intrinsics.width, intrinsics.height],
                          camera_xyz=rr.ViewCoordinates.RDF))
    stream.log(RGB, rr.Image(observation.rgb))
    millimetres = np.clip(np.round(observation.depth * 1000.0), 0, np.iinfo(np.uint16).max).astype(np.uint16)
    stream.log(DEPTH, rr.DepthImage(millimetres, meter=1000.0))  # half the size of metres as float32
    # Instance ids start at 0 and -1 means nothing, while Rerun's class 0 is the background: shift by one.
    labels = [rr.AnnotationInfo(id=label.id + 1, label=f"{label.colour} {label.category}".strip())
              for label in observation.labels]
    stream.log(SEGMENTATION, rr.AnnotationContext(labels),
               rr.SegmentationImage((observation.segmentation + 1).astype(np.uint16)))


def log_trajectory(stream: rr.RecordingStream, spec: GridSpec, trajectory: Sequence[Pose2D]) -> None:
    """The route driven so far, on the floor in 3D and over the map in 2D.

    Args:
        stream: the recording.
        spec: the map's grid.
        trajectory: the base poses in order.
    """
    xy = np.array([[pose.x, pose.y] for pose in trajectory], dtype=float)
    stream.log(WORLD_TRAJECTORY, rr.LineStrips3D([np.column_stack([xy, np.zeros(len(xy))])], colors=[[255, 140, 0]]))
    stream.log(MAP_TRAJECTORY, rr.LineStrips2D([map_pixels(spec, xy)], colors=[[255, 140, 0]], draw_order=10.0))


def log_map(stream: rr.RecordingStream, world_map: ExplorationMap) -> None:
    """The map's layers, one image each: explored, occupied and free cells in white.

    Args:
        stream: the recording.
        world_map: the map.
    """
    for layer in MAP_LAYERS:
        cells = getattr(world_map, layer)
        stream.log(f"map/{layer}", rr.Image(np.flipud(cells).astype(np.uint8) * 255))


def log_plan(stream: rr.RecordingStream, spec: GridSpec, plan: MovePlan | None) -> None:
    """The next move: its path, and the frontier it heads for labelled with its size and the path's
    length to it; nothing (cleared) when there is no plan.

    Args:
        stream: the recording.
        spec: the map's grid.
        plan: the plan, or None.
    """
    if plan is None:
        return _clear(stream, PLAN_PATH, PLAN_FRONTIER)
    stream.log(PLAN_PATH, rr.LineStrips2D([map_pixels(spec, plan.path_xy)], colors=[[0, 160, 255]], draw_order=11.0))
    if plan.frontier is None:
        return _clear(stream, PLAN_FRONTIER)
    cells = spec.to_world(plan.frontier.cells)
    label = f"frontier of {plan.frontier.size} cells, {plan.goal_distance_m:.1f} m away"
    stream.log(PLAN_FRONTIER, rr.Points2D(map_pixels(spec, cells), colors=[[255, 0, 200]], radii=0.5,
                                          labels=[label] + [""] * (len(cells) - 1), draw_order=12.0))


def log_frontier_choices(stream: rr.RecordingStream, spec: GridSpec, choices: Sequence[FrontierChoice]) -> None:
    """The candidate frontiers of the last choice at their centres, each labelled with its share of
    the semantic weight (or, without weights, its path length) and drawn larger the more it
    weighs; the chosen one magenta and labelled so. Nothing (cleared) when there were none.

    Args:
        stream: the recording.
        spec: the map's grid.
        choices: the candidates.
    """
    if not choices:
        return _clear(stream, FRONTIERS)
    labels = [("chosen " if c.chosen else "") + (f"w {c.weight:.2f}" if c.weight is not None else f"{c.distance_m:.1f} m")
              for c in choices]
    radii = [1.0 + 4.0 * (c.weight if c.weight is not None else 0.25) for c in choices]
    colors = [[255, 0, 200] if c.chosen else [230, 200, 0] for c in choices]
    xy = np.array([[c.x, c.y] for c in choices], dtype=float)
    stream.log(FRONTIERS, rr.Points2D(map_pixels(spec, xy), radii=radii, colors=colors, labels=labels, draw_order=13.0))


def log_direction_prompts(stream: rr.RecordingStream, spec: GridSpec, prompts: Sequence[DirectionPrompt]) -> None:
    """The lettered points of the last visual prompt, labelled with their letter and LSV: over the
    map in 2D and on the floor in 3D. Nothing (cleared) when the view had none.

    Args:
        stream: the recording.
        spec: the map's grid.
        prompts: the points.
    """
    if not prompts:
        return _clear(stream, MAP_PROMPTS, WORLD_PROMPTS)
    labels = [f"{p.letter} {p.value:.2f}" for p in prompts]
    xy = np.array([[p.x, p.y] for p in prompts], dtype=float)
    stream.log(MAP_PROMPTS, rr.Points2D(map_pixels(spec, xy), radii=1.5, colors=[[0, 200, 120]], labels=labels,
                                        draw_order=14.0))
    stream.log(WORLD_PROMPTS, rr.Points3D([[p.x, p.y, p.z] for p in prompts], radii=0.08, colors=[[0, 200, 120]],
                                          labels=labels))


def log_semantic_values(stream: rr.RecordingStream, semantic_map: SemanticMap) -> None:
    """The semantic value map as the planners read it, one value per cell.

    Args:
        stream: the recording.
        semantic_map: the map.
    """
    stream.log(SEMANTIC_VALUES, rr.Image(np.flipud(semantic_map.values()).astype(np.float32)))


def log_scores(stream: rr.RecordingStream, scores: StepScores) -> None:
    """One step's answer probabilities and relevance, a scalar each.

    Args:
        stream: the recording.
        scores: the step's scores.
    """
    for letter, probability in scores.answer_probs.items():
        stream.log(f"{ANSWERS}/{letter}", rr.Scalars(float(probability)))
    stream.log(RELEVANCE, rr.Scalars(float(scores.relevance)))


def log_prediction_set(stream: rr.RecordingStream, prediction_set: Sequence[str]) -> None:
    """The conformal prediction set, as text.

    Args:
        stream: the recording.
        prediction_set: the letters in the set.
    """
    stream.log(PREDICTION_SET, rr.TextLog("{" + ", ".join(prediction_set) + "}", level="INFO"))


def log_status(stream: rr.RecordingStream, status: str) -> None:
    """The tree's root status, as a number to plot and as text.

    Args:
        stream: the recording.
        status: the status' name (RUNNING, SUCCESS, FAILURE, INVALID).
    """
    stream.log(TREE_STATUS, rr.Scalars(STATUS_CODES.get(status, 0.0)))
    stream.log(TREE_STATUS_TEXT, rr.TextLog(status, level="WARN" if status == "FAILURE" else "INFO"))


def log_inside_view(stream: rr.RecordingStream, view: Observation) -> None:
    """What the wrist camera saw inside storage just opened (side by side when several).

    Args:
        stream: the recording.
        view: the views, as one observation.
    """
    stream.log(INSIDE_VIEW, rr.Image(view.rgb))


def log_act(stream: rr.RecordingStream, text: str) -> None:
    """One try to open storage and look inside, as a line of text.

    Args:
        stream: the recording.
        text: what the try did.
    """
    stream.log(ACT_LOG, rr.TextLog(text, level="INFO"))


def _clear(stream: rr.RecordingStream, *entities: str) -> None:
    """Clear what was drawn at ``entities`` (their children stay)."""
    for entity in entities:
        stream.log(entity, rr.Clear(recursive=False))


def map_pixels(spec: GridSpec, xy: np.ndarray) -> np.ndarray:
    """World (N, 2) points as (N, 2) pixel positions on the flipped map images.

    Args:
        spec: the map's grid.
        xy: the world points (x, y).

    Returns:
        The pixels (column, row), continuous.
    """
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    column = (xy[:, 0] - spec.origin_xy[0]) / spec.resolution
    row = spec.shape[0] - (xy[:, 1] - spec.origin_xy[1]) / spec.resolution
    return np.column_stack([column, row])


def log_skill_runs(stream: rr.RecordingStream, skills: SkillRuns, start: int) -> int:
    """Log the runs of ``skills`` from index ``start`` on, one step of the ``skill`` timeline each:
    its name and outcome under `SKILL_LOG`, a scalar per joint under `ARM_JOINTS`.

    Args:
        stream: the recording.
        skills: the runs.
        start: how many of them were logged before.

    Returns:
        How many are logged now.
    """
    runs = list(skills.runs)
    for index, (name, ok, joints) in enumerate(runs[start:], start=start + 1):
        stream.set_time("skill", sequence=index)
        stream.log(SKILL_LOG, rr.TextLog(f"{name}: {'done' if ok else 'failed'}", level="INFO" if ok else "WARN"))
        for j, position in enumerate(joints if joints is not None else []):
            stream.log(f"{ARM_JOINTS}/{skills.joint(j)}", rr.Scalars(float(position)))
    return len(runs)
