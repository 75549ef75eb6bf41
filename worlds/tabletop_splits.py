"""The fixed splits of the tabletop variants' seeds: which scenes are tuned on, which are reported.

A variant is any seed (`worlds.tabletop.tabletop_variant`). The tuning seeds are the scenes whose
failures are traced and fixed one by one; a figure measured on them says how well the fixes fit
those scenes, not how exploration holds on others. The reported seeds, far from them, are only ever
run whole, at the end, for the published table (`homebot eval interactive --split reported`): no
single episode of them is looked at, and nothing is tuned on them. Kept apart from
`worlds.tabletop` so the command line can name the splits without loading the simulator.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Split:
    """A fixed range of variant seeds per task and what it may be used for.

    Attributes:
        name: what the evaluation calls it (``--split``).
        seed_base: the first seed.
        variants: how many seeds per task, from ``seed_base`` on.
        use: what it is for, in a few words (shown in the CLI's help).
    """

    name: str
    seed_base: int
    variants: int
    use: str

    def seeds(self) -> range:
        """The split's seeds, the same for every task.

        Returns:
            ``seed_base`` .. ``seed_base + variants - 1``.
        """
        return range(self.seed_base, self.seed_base + self.variants)


#: The splits of the tabletop seeds. Traces, tests and tuning use the tuning seeds only (and, when
#: more scenes are needed to trace a cause, ``tuning-wide``); ``reported`` is run whole, at the end,
#: for the published table, and no single episode of it is looked at.
SPLITS = {split.name: split for split in (
    Split("tuning", 0, 10, "traced and tuned on (Table I's first ten variants)"),
    Split("tuning-wide", 1_000, 100, "more tuning scenes, for tracing a cause"),
    Split("reported", 10_000, 30, "never traced; run whole for the reported table"),
)}
