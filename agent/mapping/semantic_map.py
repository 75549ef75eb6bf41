"""The semantic map: how worth exploring the VLM judged each part of the floor (§IV-C of the paper).

In Explore until Confident each prompt point p carries a semantic value
SV_p = exp(τ_LSV·LSV_p + τ_GSV·GSV), where LSV_p is the VLM's normalised probability of p's letter
and GSV its normalised P('Yes') that anything in view is worth exploring. The map spreads each value over a disc around p with Gaussian weights,
because a point stands for the region around it, not a single cell.

Values combine as the reference code does: per cell a weighted running mean,
new = (old·w_old + v·w) / (w_old + w), kept here in closed form as Σw·v / Σw. A running mean alone
would paint a flat disc (the first value fills every cell whatever its weight), so the map is *read*
as a blend between that mean and a neutral default, trusting the mean by its accumulated weight
capped at 1: the centre of a fresh update reads v, the value fades toward the default with
distance, and cells seen again and again read their mean.

The default is the value an indifferent VLM would give (every letter equally likely, P('Yes') one
half), so places no prompt point has reached are neither favoured nor punished: regions the VLM
liked read higher, regions it disliked lower.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from agent.mapping.grid import GridSpec


@dataclass(frozen=True)
class SemanticValueConfig:
    """Temperatures of eq. (3) and the Gaussian footprint of a prompt point (reference: 1 m, 0.5 m)."""

    tau_lsv: float = 1.0
    tau_gsv: float = 1.0
    radius_m: float = 1.0
    sigma_m: float = 0.5


def semantic_value(lsv_p: float | np.ndarray, gsv: float,
                   config: SemanticValueConfig = SemanticValueConfig()) -> np.ndarray:
    """SV_p = exp(τ_LSV·LSV_p + τ_GSV·GSV), eq. (3); ``lsv_p`` may hold one value per prompt point.

    Args:
        lsv_p: LSV of each prompt point (or one).
        gsv: GSV of the view.
        config: the temperatures τ.

    Returns:
        SV_p, shaped like ``lsv_p``.
    """
    return np.exp(config.tau_lsv * np.asarray(lsv_p, dtype=float) + config.tau_gsv * gsv)


def indifferent_value(config: SemanticValueConfig = SemanticValueConfig(), num_points: int = 3,
                      use_lsv: bool = True, use_gsv: bool = True) -> float:
    """The SV of an uninformative answer: LSV = 1/num_points, GSV = 1/2 (each 0 where ablated).

    Used as the map's default so that unvalued cells sit in the middle of the range that real
    answers produce under the same ablation.

    Args:
        config: the temperatures τ.
        num_points: the prompt points per view.
        use_lsv: whether LSV counts (ablation).
        use_gsv: whether GSV counts (ablation).

    Returns:
        The SV.
    """
    lsv = 1.0 / num_points if use_lsv else 0.0
    gsv = 0.5 if use_gsv else 0.0
    return float(semantic_value(lsv, gsv, config))


class SemanticMap:
    """A float grid of semantic values on the exploration map's GridSpec.

    Args:
        spec: the exploration map's grid.
        config: the temperatures τ.
        default: the value of unwritten cells (`indifferent_value` when None).
    """

    def __init__(self, spec: GridSpec, config: SemanticValueConfig = SemanticValueConfig(),
                 default: float | None = None) -> None:
        self.spec = spec
        self.config = config
        self.default = indifferent_value(config) if default is None else float(default)
        self.weight = np.zeros(spec.shape)  # Σ w per cell
        self._weighted_sum = np.zeros(spec.shape)  # Σ w·v per cell

    def update(self, points_xy: ArrayLike, values: ArrayLike) -> None:
        """Fold one image's prompt points (N, 2) world x, y and their SVs (N,) into the map."""
        points_xy = np.asarray(points_xy, dtype=float).reshape(-1, 2)
        values = np.asarray(values, dtype=float).reshape(-1)
        if len(points_xy) != len(values):
            raise ValueError(f"{len(points_xy)} points but {len(values)} values")
        for point, value in zip(points_xy, values):
            window, weights = self._footprint(point)
            self.weight[window] += weights
            self._weighted_sum[window] += weights * value

    def mean(self) -> np.ndarray:
        """The running weighted mean per cell (the default where nothing was written).

        Returns:
            The mean, one per cell.
        """
        return self._mean(self.weight, self._weighted_sum)

    def values(self) -> np.ndarray:
        """The map as planners read it: the mean, blended toward the default where weight is below 1.

        Returns:
            The values, one per cell.
        """
        return self._blend(self.weight, self._weighted_sum)

    def values_at(self, cells: np.ndarray) -> np.ndarray:
        """`values` of some cells only, the same to the bit: a planner reads a few cells a step.

        Args:
            cells: the cells (K, 2) as (row, col), on the grid.

        Returns:
            Their values (K,).
        """
        cells = np.asarray(cells, dtype=int).reshape(-1, 2)
        rows, cols = cells[:, 0], cells[:, 1]
        return self._blend(self.weight[rows, cols], self._weighted_sum[rows, cols])

    def _mean(self, weight: np.ndarray, weighted_sum: np.ndarray) -> np.ndarray:
        valued = weight > 0
        return np.where(valued, weighted_sum / np.where(valued, weight, 1.0), self.default)

    def _blend(self, weight: np.ndarray, weighted_sum: np.ndarray) -> np.ndarray:
        confidence = np.minimum(weight, 1.0)
        return self.default + confidence * (self._mean(weight, weighted_sum) - self.default)

    def _footprint(self, point_xy: np.ndarray) -> tuple[tuple[slice, slice], np.ndarray]:
        """The grid window around a point and its Gaussian weights there, zero beyond the radius."""
        radius, res = self.config.radius_m, self.spec.resolution
        low = self.spec.to_cell(point_xy - radius)
        high = self.spec.to_cell(point_xy + radius) + 1
        rows, cols = (_clipped(int(low[axis]), int(high[axis]), self.spec.shape[axis]) for axis in (0, 1))
        x0, y0 = self.spec.origin_xy
        xs = x0 + (np.arange(cols.start, cols.stop) + 0.5) * res
        ys = y0 + (np.arange(rows.start, rows.stop) + 0.5) * res
        squared = (xs[None, :] - point_xy[0]) ** 2 + (ys[:, None] - point_xy[1]) ** 2
        weights = np.exp(-squared / (2 * self.config.sigma_m**2))
        weights[squared > radius**2] = 0.0
        return (rows, cols), weights


def _clipped(start: int, stop: int, size: int) -> slice:
    """[start, stop) cut to [0, size), empty (never negative, which numpy reads from the end) outside."""
    start = min(max(start, 0), size)
    return slice(start, min(max(stop, start), size))
