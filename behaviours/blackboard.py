"""Names of the blackboard keys the EQA tree shares, in one place so behaviours agree on them."""

QUESTION = "question"  # str
CHOICES = "choices"  # list[str], four of them, padded
BUDGET = "budget"  # int, steps
OBSERVATION = "observation"  # agent.observation.Observation, the newest frame
INSIDE_VIEW = "inside_view"  # agent.observation.Observation, what the VLM is shown of storage just opened
MAP = "map"  # agent.mapping.occupancy.ExplorationMap
ANSWER_LOG = "answer_log"  # agent.eqa.answers.AnswerLog
PLAN = "plan"  # agent.planning.explore.MovePlan, the next move
FRONTIER_GOAL = "frontier_goal"  # numpy (x, y) of the frontier the robot heads for, or None
TRAJECTORY = "trajectory"  # list[tuple[float, float, float]], base poses along the route driven (corners, ends)
EXPLORATION_COMPLETE = "exploration_complete"  # bool, no reachable frontier is left
ANSWER = "answer"  # dict, written once when the episode answers
SEMANTIC_MAP = "semantic_map"  # agent.mapping.semantic_map.SemanticMap, semantic methods only
STOP_DECISION = "stop_decision"  # agent.eqa.stopping.StopDecision once the stopping rule decides, else None
PREDICTION_SET = "prediction_set"  # list[str], the running conformal set (cp rule only, else None)
Q_HAT = "q_hat"  # float, the calibrated conformal threshold q̂ (cp rule only, else None)
EPSILON = "epsilon"  # float, the miscoverage ε the user accepts (cp rule only, else None)
ACTS = "acts"  # list[dict], every time the robot opened (or tried to open) storage to look inside
