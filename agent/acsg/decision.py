"""The decision module's two roles (RoboEXP §IV-A, App. I-C): proposer and verifier.

`RuleDecisionModule` is the simulator's default: the commonsense an LMM brings, written down.
Storage opens, things that could cover something are lifted, the rest is left alone; blockers
come from geometry hints the perception passes along. `PromptDecisionModule` asks a real (or
simulated) VLM through the project's one question, `VisionLanguageModel.probabilities`, with the
paper's Fig. 7 prompts: the proposer chooses among the three skills by their numbers, the verifier
is asked Yes or No for each surrounding object, since a probability over a few candidate tokens is
what every backend here can give.
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from agent.acsg.interfaces import DecisionContext, Detection, Proposal, object_id
from agent.acsg.nodes import ActionNode, ObjectNode
from agent.vlm.protocol import VisionLanguageModel, VisualQuery

#: Storage whose doors or drawers can hide things (also what a part alone is called).
STORAGE_LABELS = frozenset({
    "cabinet", "drawer chest", "nightstand", "wardrobe", "fridge", "dishwasher", "counter", "cupboard",
    "dresser", "sideboard", "closet", "microwave", "oven", "chest", "drawer", "door",
})
#: Things with no bottom (or a lid) that can cover something beneath them.
COVER_LABELS = frozenset({
    "box", "lid", "cover", "food cover", "cloche", "matryoshka", "matryoshka doll", "nesting doll", "cloth",
    "napkin", "basket",
})
#: Vessels that hide something only when they stand upside down.
VESSEL_LABELS = frozenset({"cup", "mug", "bowl", "bucket", "pot", "glass", "jar"})


def _owner(context: DecisionContext, node_id: str) -> str:
    """The piece a part or handle belongs to (walking up 'belongs' edges); the node itself otherwise."""
    graph = context.graph
    while True:
        parent = graph.parent(node_id)
        if parent is None or parent[1] != "belongs":
            return node_id
        node_id = parent[0]


def surrounding_objects(action: ActionNode, context: DecisionContext, radius_m: float | None = None) -> list[Detection]:
    """The objects the verifier should consider for ``action``, as in the reference code: in view,
    standing on a root (the table), not the piece being opened nor its own parts, not moved away,
    and (with ``radius_m`` and known centroids) within that distance of the handle or part.

    Args:
        action: the action judged (its target, and its handle when it has one).
        context: the graph and what is in view.
        radius_m: how near the handle or part an object must be (any distance when None).

    Returns:
        The objects' detections.
    """
    graph = context.graph
    owner = _owner(context, action.target)
    anchor_id = action.params.get("handle", action.target)
    anchor = context.visible.get(anchor_id) or context.visible.get(action.target)
    found = []
    for det in context.visible.values():
        if det.id in (action.target, owner) or det.id in context.moved_away or det.relation != "on":
            continue
        if det.parent is None or object_id(det.parent) not in graph or graph.parent(object_id(det.parent)) is not None:
            continue
        if _owner(context, det.id) == owner:
            continue
        if radius_m is not None and anchor is not None and anchor.centroid is not None and det.centroid is not None:
            if float(np.linalg.norm(det.centroid - anchor.centroid)) > radius_m:
                continue
        found.append(det)
    return found


def _boxes_overlap(lo_a: np.ndarray, hi_a: np.ndarray, lo_b: np.ndarray, hi_b: np.ndarray, by_m: float = 0.0
                   ) -> bool:
    """Whether box a overlaps box b, or any of boxes b (corners (N, 3)), by more than ``by_m``
    along every axis."""
    lo_b, hi_b = np.atleast_2d(lo_b), np.atleast_2d(hi_b)
    return bool(np.any(np.all(lo_a + by_m < hi_b, axis=1) & np.all(lo_b + by_m < hi_a, axis=1)))


@dataclass(frozen=True)
class RuleDecisionModule:
    """Commonsense rules standing in for the LMM.

    Proposer: storage (by label, or anything with openable parts) -> "open"; covers, and vessels
    marked upside down (attribute ``upside_down``) -> "pick"; anything else -> "none".
    Verifier: only opening can be blocked; an object blocks it when its ``blocks`` hint names the
    part, or its box overlaps the part's ``swept`` hint (lo, hi: one box, or the corners of
    several) by more than ``sweep_margin_m``; storage never does, as it is not picked up.

    ``sweep_margin_m``: how deep an object's box must reach into the swept box to block. The boxes
    a robot's memory gives reach up to a voxel (1 cm) past the thing on each side: a box standing
    4 cm beside a chest was remembered 3.4 cm wider, 7 mm into what the chest's drawer sweeps, and
    was lifted out of a way it was never in (recursive 1087 of tuning-wide).
    """

    storage_labels: Collection[str] = STORAGE_LABELS
    cover_labels: Collection[str] = COVER_LABELS
    vessel_labels: Collection[str] = VESSEL_LABELS
    sweep_margin_m: float = 0.01

    def propose(self, obj: ObjectNode, context: DecisionContext) -> Proposal:
        """Open storage and what has parts, pick up covers and upturned vessels, leave the rest.

        Args:
            obj: the object judged.
            context: the graph and what is in view.

        Returns:
            "open", "pick" or "none".
        """
        label = obj.label.lower()
        if label in self.storage_labels or self._has_parts(obj, context):
            return "open"
        if label in self.cover_labels or (label in self.vessel_labels and obj.attributes.get("upside_down")):
            return "pick"
        return "none"

    @staticmethod
    def _has_parts(obj: ObjectNode, context: DecisionContext) -> bool:
        graph = context.graph
        for child in graph.successors(obj.id, "object-object"):
            edge = graph.edge(obj.id, child)
            if edge is not None and edge.relation == "belongs" and graph.object(child).label in ("door", "drawer"):
                return True
        return False

    def verify(self, action: ActionNode, context: DecisionContext) -> list[str]:
        """The objects in view standing in what opening the part sweeps; nothing blocks other actions.

        Args:
            action: the action judged.
            context: the graph and what is in view.

        Returns:
            The blockers' node ids.
        """
        if action.type != "open":
            return []
        target = context.graph.object(action.target)
        part = context.visible.get(target.id)
        swept = part.hints.get("swept") if part is not None else None
        blockers = []
        for det in surrounding_objects(action, context):
            if det.label.lower() in self.storage_labels:
                continue  # furniture is not lifted out of the way (a chest seen apart from its own drawers)
            named = det.hints.get("blocks", ())
            if target.id in named or (target.instance is not None and target.instance in named):
                blockers.append(det.id)
            elif swept is not None and (box := _box(det)) is not None:
                lo, hi = (np.asarray(v, dtype=float) for v in swept)
                if _boxes_overlap(*box, lo, hi, self.sweep_margin_m):
                    blockers.append(det.id)
        return blockers


def _box(det: Detection) -> tuple[np.ndarray, np.ndarray] | None:
    """(lo, hi) corners of what was seen of ``det``: its ``box`` hint, else its extent about its
    centroid. A memory's centroid is the mean of its points, which crowd where the camera sees
    most: a bottle seen from above had the mean of its points 1.9 cm over its middle, the box laid
    about that mean reached into what the drawer over it sweeps, and the bottle was taken out of
    the drawer's way a second time, a precondition the scene does not have (occlusion 1156 of
    tuning-wide)."""
    if "box" in det.hints:
        lo, hi = det.hints["box"]
        return np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    if det.centroid is None or det.extent is None:
        return None
    return det.centroid - det.extent / 2, det.centroid + det.extent / 2


# The paper's Fig. 7 prompts (identical in the authors' released prompt files).
PROPOSER_SYSTEM = (
    "You are an assistant tasked with aiding in the construction of a complete scene graph for a tabletop "
    "environment. The objective is to identify all objects hidden from the current observation in the tabletop "
    "setting. Your role involves selecting appropriate actions or opting not to take any action based on "
    "commonsense knowledge in response to queries with current observations. Your responses will guide a robot "
    "in efficiently exploring the environment. Approach each step thoughtfully, and analyze the fundamental "
    "problem deeply, considering the potential vagueness or inaccuracy in the queries. Adhere to the provided "
    "formats in your instructions."
)
PROPOSER_USER = (
    "Analyze and provide your final answer for each new query object/part category, considering the given "
    "surrounding objects and observations in the tabletop scene from different viewpoints. The query object/part "
    "will be enclosed in a green bounding box, though it may not always be fully accurate. Choose from three "
    "skills: 1. Open the doors or drawers. 2. Pick up / Open the top object. 3. No action. The primary goal is to "
    "select an action that has the potential to reveal hidden objects. The secondary goal is to act efficiently, "
    "performing only necessary actions to uncover hidden objects. For example, if an object contains doors or "
    "drawers and can potentially store something inside, opt for the first skill \"Open the doors or drawers\". "
    "If an object has no bottom side and can potentially cover something beneath it, choose the second skill "
    "\"Pick up / Open the top object\"; otherwise, select the third skill \"No action\" to ensure efficiency."
)
VERIFIER_SYSTEM = (
    "You are an assistant tasked with evaluating the feasibility of actions within a tabletop environment. Your "
    "role is to select suitable objects that could obstruct open actions based on queries and current "
    "observations. Provide guidance for a robot's planning process. Approach each step thoughtfully, analyzing "
    "the underlying problem thoroughly while considering potential vagueness or inaccuracy in the queries. "
    "Follow the provided formats in your instructions."
)
VERIFIER_USER = (
    "Provide an analysis and your final answer each time I present a new query object/part category, the list of "
    "surrounding objects you need to consider and observations of the corresponding in the tabletop scene from "
    "different viewpoints. The query object/part is enclosed in a green bounding box, which may not always be "
    "fully accurate. Use the given list of surrounding objects, maintaining the provided names. Only consider the "
    "surrounding objects in the given list. The objective is to identify all objects that could potentially "
    "block open actions. If an object obstructs the door or drawer from opening, include it in the final list of "
    "objects. Analyze the action movement and identify the blocking objects."
)
#: Skill number -> proposal, in the order the prompt lists the skills.
SKILLS: dict[str, Proposal] = {"1": "open", "2": "pick", "3": "none"}


def proposer_prompt(obj: ObjectNode, surrounding: list[str]) -> str:
    """The proposer's question about ``obj``; the answer is one skill number.

    Args:
        obj: the object asked about.
        surrounding: the labels of the other objects in view.

    Returns:
        The prompt.
    """
    around = ", ".join(surrounding) if surrounding else "none"
    return (f"{PROPOSER_SYSTEM}\n\n{PROPOSER_USER}\n\nQuery object: {obj.describe()}. Surrounding objects: "
            f"[{around}]. Answer with the number of the skill only: 1, 2 or 3.")


def verifier_prompt(part: ObjectNode, candidate: str, surrounding: list[str]) -> str:
    """The verifier's question whether ``candidate`` blocks opening ``part``; the answer is Yes or No.

    Args:
        part: the part to open.
        candidate: the label of the object that may block it.
        surrounding: the labels of the objects around it.

    Returns:
        The prompt.
    """
    return (f"{VERIFIER_SYSTEM}\n\n{VERIFIER_USER}\n\nQuery: the process of open {part.describe()}. Given object "
            f"list [{', '.join(surrounding)}]. Could the {candidate} block the {part.label} from opening? "
            f"Answer with Yes or No.")


@dataclass
class PromptDecisionModule:
    """Proposer and verifier asked of ``vlm``; ``camera`` gives the frame sent with each query
    (None sends no image, for text-only or fake models). The verifier names an object a blocker
    when P(Yes) ≥ ``yes_threshold``; ``radius_m`` limits the candidates as the reference does
    (it uses 0.2 m around the handle; None considers every object standing on the table)."""

    vlm: VisionLanguageModel
    camera: Callable[[], Any] | None = None
    yes_threshold: float = 0.5
    radius_m: float | None = None
    queries: list[VisualQuery] = field(default_factory=list, repr=False)

    def __post_init__(self) -> None:
        if not 0.0 < self.yes_threshold < 1.0:
            raise ValueError(f"decision.yes_threshold: {self.yes_threshold} must lie in (0, 1)")

    def _ask(self, prompt: str, candidates: tuple[str, ...]) -> dict[str, float]:
        query = VisualQuery(self.camera() if self.camera else None, prompt, candidates)  # type: ignore[arg-type]
        self.queries.append(query)
        probs = self.vlm.probabilities(query)
        missing = [c for c in candidates if c not in probs]
        if missing:
            raise ValueError(f"vlm {getattr(self.vlm, 'name', '?')}: no probability for candidates {missing}")
        return probs

    def propose(self, obj: ObjectNode, context: DecisionContext) -> Proposal:
        """Ask the VLM the proposer's question and take its likeliest skill.

        Args:
            obj: the object judged.
            context: the graph and what is in view.

        Returns:
            "open", "pick" or "none".
        """
        around = [d.label for d in context.visible.values() if d.id != obj.id]
        probs = self._ask(proposer_prompt(obj, around), tuple(SKILLS))
        return SKILLS[max(SKILLS, key=lambda k: probs[k])]

    def verify(self, action: ActionNode, context: DecisionContext) -> list[str]:
        """Ask the VLM the verifier's question about each object around the part to open.

        Args:
            action: the action judged.
            context: the graph and what is in view.

        Returns:
            The node ids of the objects it says block; empty for actions other than open.
        """
        if action.type != "open":
            return []
        part = context.graph.object(action.target)
        candidates = surrounding_objects(action, context, self.radius_m)
        names = [d.label for d in candidates]
        blockers = []
        for det in candidates:
            probs = self._ask(verifier_prompt(part, det.label, names), ("Yes", "No"))
            if probs["Yes"] / max(probs["Yes"] + probs["No"], 1e-12) >= self.yes_threshold:
                blockers.append(det.id)
        return blockers
