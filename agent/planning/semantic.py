"""Semantic-value-weighted frontier exploration (Explore until Confident, §IV-D and App. B).

Each frontier p gets the weight w_p = exp(τ_SV·SV_p + τ_SV,normal·SV_p,normal), eq. (A6): SV_p is
the semantic map at the frontier, SV_p,normal the mean along its normal into the unexplored side
out to d_SV. The second term is what steers the robot *toward* a valued region that lies a few
metres beyond a frontier, rather than only to frontiers that happen to sit on one. The next
frontier is then *sampled* ∝ w_p, not taken as the best, so that a wrong VLM judgement only
tilts exploration rather than trapping the robot (`agent.planning.frontier_choice`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from enum import StrEnum

import numpy as np

from agent.mapping.grid import GridSpec
from agent.mapping.semantic_map import SemanticMap, SemanticValueConfig, indifferent_value, semantic_value
from agent.planning.frontier import Frontier


class ExploreMethod(StrEnum):
    """The exploration policies compared in the paper's Fig. 7a/b.

    - ``fbe``: plain frontier-based exploration, no VLM values (here: the nearest frontier).
    - ``semantic``: the full method, SV from both LSV and GSV.
    - ``semantic-no-lsv``: LSV = 0 for every point, so all points of one image get the same SV,
      exp(τ_GSV·GSV): the map only learns whether a view as a whole is worth exploring, not which
      direction in it (coarser values; the paper finds it explores less efficiently overall).
    - ``semantic-no-gsv``: GSV = 0, so SV = exp(τ_LSV·LSV_p): values compare directions within one
      image only, and an image of irrelevant places still gets a confident best direction; the
      paper finds this myopic (good early, then stuck in wrongly chosen places).
    - ``lfe``: not from that paper: learning-augmented frontier exploration (`agent.lfe.explore`),
      the Bellman recursion over the area and time the shipped network predicts beyond each
      frontier. It covers the home fast but knows nothing of the question.
    """

    FBE = "fbe"
    SEMANTIC = "semantic"
    SEMANTIC_NO_LSV = "semantic-no-lsv"
    SEMANTIC_NO_GSV = "semantic-no-gsv"
    LFE = "lfe"


@dataclass(frozen=True)
class MethodFlags:
    use_lsv: bool
    use_gsv: bool
    use_semantic: bool  # False: pick frontiers without the semantic map (FBE's nearest, or LFE)


def method_flags(method: ExploreMethod | str) -> MethodFlags:
    """What a method uses; raises ValueError for an unknown name."""
    method = ExploreMethod(method)
    return MethodFlags(
        use_lsv=method in (ExploreMethod.SEMANTIC, ExploreMethod.SEMANTIC_NO_GSV),
        use_gsv=method in (ExploreMethod.SEMANTIC, ExploreMethod.SEMANTIC_NO_LSV),
        use_semantic=method not in (ExploreMethod.FBE, ExploreMethod.LFE),
    )


def new_semantic_map(spec: GridSpec, method: ExploreMethod | str,
                     config: SemanticValueConfig = SemanticValueConfig(), num_points: int = 3) -> SemanticMap:
    """An empty semantic map whose default is the indifferent value under the method's ablation."""
    flags = method_flags(method)
    return SemanticMap(spec, config, indifferent_value(config, num_points, flags.use_lsv, flags.use_gsv))


def point_values(letter_probs: Sequence[float], p_yes: float, method: ExploreMethod | str,
                 config: SemanticValueConfig = SemanticValueConfig()) -> np.ndarray:
    """SV of each prompt point from the VLM's answers, with the method's ablation applied.

    ``letter_probs`` are the VLM's probabilities (or any non-negative scores) of the points'
    letters, in prompt-point order; they are normalised here to LSV (uniform if all are zero).
    ``p_yes`` is the normalised P('Yes') of the GSV prompt, P(Yes) / (P(Yes) + P(No)).
    """
    flags = method_flags(method)
    probs = np.asarray(letter_probs, dtype=float)
    total = probs.sum()
    lsv = probs / total if total > 0 else np.full(len(probs), 1.0 / max(len(probs), 1))
    lsv = lsv if flags.use_lsv else np.zeros_like(lsv)
    gsv = float(p_yes) if flags.use_gsv else 0.0
    return semantic_value(lsv, gsv, config)


@dataclass(frozen=True)
class FrontierWeightConfig:
    """Temperatures of eq. (A6) and how far along the normal SV_p,normal looks (App. B: 3 m)."""

    tau_sv: float = 1.0
    tau_sv_normal: float = 1.0
    d_sv_m: float = 3.0


def normal_ray_cells(spec: GridSpec, frontier: Frontier, d_sv_m: float) -> np.ndarray:
    """Cells (K, 2) one resolution apart along the normal, from one step out to ``d_sv_m``, in the grid."""
    steps = np.arange(1, int(round(d_sv_m / spec.resolution)) + 1) * spec.resolution
    points = spec.to_world(np.asarray(frontier.centre)) + steps[:, None] * np.asarray(frontier.normal)[None, :]
    cells = spec.to_cell(points)
    return cells[spec.inside(cells)]


def frontier_log_weights(frontiers: Sequence[Frontier], values: np.ndarray, spec: GridSpec,
                         config: FrontierWeightConfig = FrontierWeightConfig(),
                         default: float = 1.0) -> np.ndarray:
    """log w_p = τ_SV·SV_p + τ_SV,normal·SV_p,normal for each frontier, from a grid of SVs.

    Weights are returned as exponents because with larger temperatures exp() overflows; a ray that
    leaves the grid at once reads ``default`` (pass the semantic map's).
    """
    logs = np.zeros(len(frontiers))
    for i, frontier in enumerate(frontiers):
        ray = normal_ray_cells(spec, frontier, config.d_sv_m)
        along = float(values[ray[:, 0], ray[:, 1]].mean()) if len(ray) else default
        logs[i] = config.tau_sv * float(values[frontier.centre]) + config.tau_sv_normal * along
    return logs
