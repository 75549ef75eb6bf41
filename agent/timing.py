"""Per-stage timings of an episode, for `homebot bench step` and the run record.

Plain Python and numpy, so that the pure libraries (`agent.lfe`) can time their stages without
loading the runtime."""

from __future__ import annotations

import time
from collections import defaultdict
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np


class StageTimer:
    """Collects durations in milliseconds by stage name, each stage's in the order they were recorded
    (a stage timed once a step, such as the map's, holds the steps in order)."""

    def __init__(self) -> None:
        self.samples: dict[str, list[float]] = defaultdict(list)

    def record(self, stage: str, milliseconds: float) -> None:
        """Add one sample of a stage's time.

        Args:
            stage: the stage's name.
            milliseconds: how long it took.
        """
        self.samples[stage].append(float(milliseconds))

    @contextmanager
    def measure(self, stage: str) -> Iterator[None]:
        """Time the ``with`` block as one sample of ``stage``.

        Args:
            stage: the stage's name.
        """
        started = time.perf_counter()
        try:
            yield
        finally:
            self.record(stage, (time.perf_counter() - started) * 1000.0)

    def summary(self) -> dict[str, dict[str, float]]:
        """Count, median, p95 and max per stage.

        Returns:
            The figures by stage name (milliseconds).
        """
        return {
            stage: {
                "count": len(values),
                "median_ms": float(np.median(values)),
                "p95_ms": float(np.percentile(values, 95)),
                "max_ms": float(np.max(values)),
            }
            for stage, values in self.samples.items()
            if values
        }
