"""Action-conditioned scene graphs and interactive exploration (RoboEXP), as a pure library.

- `nodes`: object and action nodes and the four edge kinds;
- `graph`: the ACSG and its edits, kept acyclic; `order`: paths, ancestors, topological order, depth;
- `json_format`: our JSON, the ground truth's, and files of either;
- `primitives`: the skill names an action runs and what undoes each;
- `plan`: object retrieval, the actions on the paths from the roots in topological order;
- `draw`: a layered picture of a graph;
- `interfaces`: Perception, DecisionModule and SkillExecutor, and what crosses them;
- `explore`: Algorithm 1 with the action stack and Algorithm 3's preconditions;
- `decision`: the commonsense rule module and the VLM prompt module (proposer and verifier);
- `symbolic`: a symbolic tabletop to explore without a simulator;
- `metrics`: Table I (success, object and state recovery, unexplored space, graph edit distance);
- `cli`: ``homebot acsg plan`` and ``show``.

No simulator, bus or behaviour tree is imported here; networkx (metrics) and matplotlib (draw)
are imported only when used.
"""

from agent.acsg.decision import PromptDecisionModule, RuleDecisionModule
from agent.acsg.interactive_exploration import ExplorationResult, InteractiveExploreConfig, Explorer, LogEntry, explore
from agent.acsg.graph import ACSG, CycleError, UnknownObjectError
from agent.acsg.interfaces import (
    DecisionContext,
    DecisionModule,
    Detection,
    Perception,
    SkillCall,
    SkillExecutor,
    SkillResult,
)
from agent.acsg.json_format import from_ground_truth, load_acsg
from agent.acsg.nodes import ACSGError, ActionNode, Edge, ObjectNode
from agent.acsg.plan import retrieval_actions, retrieval_plan
from agent.acsg.symbolic import SymbolicScene, Thing

__all__ = [
    "ACSG", "ACSGError", "ActionNode", "CycleError", "DecisionContext", "DecisionModule", "Detection", "Edge",
    "ExplorationResult", "InteractiveExploreConfig", "Explorer", "LogEntry", "ObjectNode", "Perception",
    "PromptDecisionModule", "RuleDecisionModule", "SkillCall", "SkillExecutor", "SkillResult", "SymbolicScene",
    "Thing", "UnknownObjectError", "explore", "from_ground_truth", "load_acsg", "retrieval_actions",
    "retrieval_plan",
]
