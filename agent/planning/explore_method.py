"""What each exploration method means, decided in one place.

The method is named once, in the configuration (``explore.method``); everything that behaves
differently under one method or another (whether the tree asks the VLM for directions, whether a
semantic map is kept, how the VLM's answers become values, how a frontier is chosen) asks the
`ExploreStrategy` made from that name rather than comparing names itself.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from enum import StrEnum

import numpy as np

from agent.mapping.grid import GridSpec
from agent.mapping.semantic_map import SemanticMap, SemanticValueConfig, indifferent_value, semantic_value


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
    - ``lfe``: not from that paper: learning-augmented frontier exploration (`agent.lfe.eqa_frontier`),
      the Bellman recursion over the area and time the shipped network predicts beyond each
      frontier. It covers the home fast but knows nothing of the question.
    """

    FBE = "fbe"
    SEMANTIC = "semantic"
    SEMANTIC_NO_LSV = "semantic-no-lsv"
    SEMANTIC_NO_GSV = "semantic-no-gsv"
    LFE = "lfe"


@dataclass(frozen=True)
class ExploreStrategy:
    """What one exploration method uses, made once from its name (`of`) and asked by the tree.

    ``use_lsv`` / ``use_gsv``: whether the VLM's local / global semantic values count;
    ``use_semantic``: whether the tree asks the VLM for directions and keeps a semantic map that
    weighs frontiers (False for FBE's nearest frontier and for LFE); ``learned``: whether frontiers
    are chosen over the learned network's estimates (LFE).
    """

    method: ExploreMethod
    use_lsv: bool
    use_gsv: bool
    use_semantic: bool
    learned: bool

    @classmethod
    def of(cls, method: ExploreMethod | str) -> ExploreStrategy:
        """The strategy of a method by its name.

        Args:
            method: one of `ExploreMethod`'s values.

        Returns:
            What the method uses.

        Raises:
            ValueError: for an unknown name.
        """
        method = ExploreMethod(method)
        return cls(
            method=method,
            use_lsv=method in (ExploreMethod.SEMANTIC, ExploreMethod.SEMANTIC_NO_GSV),
            use_gsv=method in (ExploreMethod.SEMANTIC, ExploreMethod.SEMANTIC_NO_LSV),
            use_semantic=method not in (ExploreMethod.FBE, ExploreMethod.LFE),
            learned=method == ExploreMethod.LFE,
        )

    def new_semantic_map(self, spec: GridSpec, config: SemanticValueConfig = SemanticValueConfig(),
                         num_points: int = 3) -> SemanticMap:
        """An empty semantic map whose default is the indifferent value under this method's ablation.

        Args:
            spec: the grid of the robot's map.
            config: the temperatures of the semantic values.
            num_points: prompt points per image.

        Returns:
            The map, every cell at the indifferent value.
        """
        return SemanticMap(spec, config, indifferent_value(config, num_points, self.use_lsv, self.use_gsv))

    def point_values(self, letter_probs: Sequence[float], p_yes: float,
                     config: SemanticValueConfig = SemanticValueConfig()) -> np.ndarray:
        """SV of each prompt point from the VLM's answers, with this method's ablation applied.

        Args:
            letter_probs: the VLM's probabilities (or any non-negative scores) of the points'
                letters, in prompt-point order; normalised here to LSV (uniform if all are zero).
            p_yes: the normalised P('Yes') of the GSV prompt, P(Yes) / (P(Yes) + P(No)).
            config: the temperatures of the semantic values.

        Returns:
            One value per point.
        """
        probs = np.asarray(letter_probs, dtype=float)
        total = probs.sum()
        lsv = probs / total if total > 0 else np.full(len(probs), 1.0 / max(len(probs), 1))
        lsv = lsv if self.use_lsv else np.zeros_like(lsv)
        gsv = float(p_yes) if self.use_gsv else 0.0
        return semantic_value(lsv, gsv, config)
