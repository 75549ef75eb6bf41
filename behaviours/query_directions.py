"""QueryDirections: ask the VLM which way to explore, and write its answer into the semantic map.

The visual prompt of Explore until Confident (§IV-C): up to three free floor points in view are
drawn as letters; LSV is the VLM's choice among the letters, GSV its P(Yes) that anything in view
is worth exploring. Each point's value exp(τ_LSV·LSV + τ_GSV·GSV) goes into the semantic map. The
annotated image of every step that asked is saved, so a person can see what the VLM was shown, and
the points with their letters and LSV go to ``direction_prompts`` (for the recording).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image
from py_trees.common import Access, Status

from behaviours import blackboard as bb
from behaviours.choices import DirectionPrompt
from agent.eqa.prompts import YES_NO, gsv_prompt, lsv_prompt
from agent.mapping.semantic_map import SemanticValueConfig
from agent.observation import Observation
from agent.planning.prompt_points import PromptPoint, PromptPointConfig, prompt_points
from agent.planning.explore_method import ExploreStrategy
from agent.timing import StageTimer
from agent.vlm.annotate import draw_marks
from agent.vlm.protocol import VisionLanguageModel, VisualQuery
from behaviours.async_vlm import AsyncVLMQuery


class QueryDirections(AsyncVLMQuery):
    """Asks the VLM which way to explore (LSV over lettered floor points, GSV of the view) into the semantic map.

    Args:
        vlm: the model asked.
        strategy: which semantic values the method uses.
        rng: the prompt points' generator.
        points: how prompt points are placed.
        values: the temperatures τ.
        timeout_s: how long an answer may take.
        timer: times the queries, if given.
        images_dir: where the marked prompt images are saved, if anywhere.
        name: the node's name.
    """

    stage = "vlm_directions"

    def __init__(self, vlm: VisionLanguageModel, strategy: ExploreStrategy, rng: np.random.Generator,
                 points: PromptPointConfig = PromptPointConfig(), values: SemanticValueConfig = SemanticValueConfig(),
                 timeout_s: float = 30.0, timer: StageTimer | None = None, images_dir: Path | None = None,
                 name: str = "QueryDirections") -> None:
        super().__init__(name, vlm, timeout_s, timer)
        self.strategy, self.rng, self.points_config, self.values_config = strategy, rng, points, values
        self.images_dir = images_dir
        self.blackboard = self.attach_blackboard_client(name=name)
        for key in (bb.QUESTION, bb.OBSERVATION, bb.MAP, bb.ANSWER_LOG):
            self.blackboard.register_key(key, access=Access.READ)
        self.blackboard.register_key(bb.SEMANTIC_MAP, access=Access.WRITE)  # the directions' values go into it
        self.blackboard.register_key(bb.DIRECTION_PROMPTS, access=Access.WRITE)

    def inputs(self) -> tuple[Observation, str, list[PromptPoint], int]:
        observation: Observation = self.blackboard.get(bb.OBSERVATION)
        points = prompt_points(self.blackboard.get(bb.MAP), observation.base_pose[:2], observation.depth,
                               observation.intrinsics, observation.camera_to_world, self.rng, self.points_config)
        return observation, self.blackboard.get(bb.QUESTION), points, len(self.blackboard.get(bb.ANSWER_LOG))

    def ask(self, observation: Observation, question: str, points: list[PromptPoint],
            step: int) -> tuple[list[PromptPoint], dict[str, float], float]:
        if not points:
            return points, {}, 0.5
        marks = {p.letter: (float(p.pixel[0]), float(p.pixel[1])) for p in points}
        letters = tuple(p.letter for p in points)
        lsv = self.vlm.probabilities(VisualQuery(observation, lsv_prompt(question), letters, marks))
        gsv = self.vlm.probabilities(VisualQuery(observation, gsv_prompt(question), YES_NO, marks))
        if self.images_dir is not None:
            self.images_dir.mkdir(parents=True, exist_ok=True)
            Image.fromarray(draw_marks(observation.rgb, marks)).save(self.images_dir / f"step-{step:03d}.png")
        return points, lsv, gsv["Yes"]

    def use(self, answer: tuple[list[PromptPoint], dict[str, float], float]) -> Status:
        points, lsv, p_yes = answer
        floor_z = self.points_config.floor_z
        self.blackboard.set(bb.DIRECTION_PROMPTS, [DirectionPrompt(round(float(p.xy[0]), 3), round(float(p.xy[1]), 3),
                                                                   floor_z, p.letter, float(lsv[p.letter]))
                                                   for p in points])
        if not points:
            self.feedback_message = "no free floor in view to point at"
            return Status.SUCCESS
        values = self.strategy.point_values([lsv[p.letter] for p in points], p_yes, self.values_config)
        self.blackboard.get(bb.SEMANTIC_MAP).update(np.array([p.xy for p in points]), values)
        best = max(lsv, key=lsv.__getitem__)
        self.feedback_message = f"{len(points)} directions: LSV favours {best} ({lsv[best]:.2f}), GSV {p_yes:.2f}"
        return Status.SUCCESS
