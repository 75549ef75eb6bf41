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

import numpy as np

from agent.mapping.grid import GridSpec
from agent.mapping.semantic_map import SemanticMap
from agent.planning.frontier import Frontier


@dataclass(frozen=True)
class FrontierWeightConfig:
    """Temperatures of eq. (A6) and how far along the normal SV_p,normal looks (App. B: 3 m)."""

    tau_sv: float = 1.0
    tau_sv_normal: float = 1.0
    d_sv_m: float = 3.0


def normal_ray_cells(spec: GridSpec, frontier: Frontier, d_sv_m: float) -> np.ndarray:
    """Cells (K, 2) one resolution apart along the normal, from one step out to ``d_sv_m``, in the grid.

    Args:
        spec: the grid.
        frontier: the frontier (its centre and normal).
        d_sv_m: the ray's length.

    Returns:
        The cells.
    """
    steps = np.arange(1, int(round(d_sv_m / spec.resolution)) + 1) * spec.resolution
    points = spec.to_world(np.asarray(frontier.centre)) + steps[:, None] * np.asarray(frontier.normal)[None, :]
    cells = spec.to_cell(points)
    return cells[spec.inside(cells)]


def frontier_log_weights(frontiers: Sequence[Frontier], semantic_map: SemanticMap,
                         config: FrontierWeightConfig = FrontierWeightConfig()) -> np.ndarray:
    """log w_p = τ_SV·SV_p + τ_SV,normal·SV_p,normal for each frontier, from the semantic map.

    Weights are returned as exponents because with larger temperatures exp() overflows; a ray that
    leaves the grid at once reads the map's default. Only the cells read are evaluated
    (`SemanticMap.values_at`).

    Args:
        frontiers: the frontiers.
        semantic_map: the semantic values, on the frontiers' grid.
        config: the temperatures τ and the ray's length.

    Returns:
        log w per frontier.
    """
    logs = np.zeros(len(frontiers))
    for i, frontier in enumerate(frontiers):
        ray = normal_ray_cells(semantic_map.spec, frontier, config.d_sv_m)
        along = float(semantic_map.values_at(ray).mean()) if len(ray) else semantic_map.default
        here = float(semantic_map.values_at(np.asarray(frontier.centre))[0])
        logs[i] = config.tau_sv * here + config.tau_sv_normal * along
    return logs
