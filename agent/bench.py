"""`homebot bench …`: figures to compare across runs, never assertions."""

from __future__ import annotations

import json
import tempfile
from pathlib import Path
from typing import Any

from agent.config import Config
from agent.runtime.run import RunRequest, run_episode
from agent.runtime.timing import StageTimer

STAGES = ("render", "transport", "tsdf", "planning", "vlm", "tick")


def bench_step(config: Config, seed: int, out_root: Path | None) -> dict[str, Any]:
    """Run one fixed episode with per-stage timing; return the summary and the episode's result."""
    timer = StageTimer()
    with tempfile.TemporaryDirectory(prefix="homebot-bench-") as scratch:
        root = out_root or Path(scratch)
        result = run_episode(RunRequest(seed=seed, config=config, out_root=root), timer=timer)
    summary = timer.summary()
    steps = max(1, result.get("steps", 0))
    return {"seed": seed, "steps": result.get("steps", 0), "status": result["status"],
            "episode_s": result["seconds"], "per_step_ms": 1000.0 * result["seconds"] / steps,
            "stages": {stage: summary[stage] for stage in STAGES if stage in summary}}


def format_step_table(report: dict[str, Any]) -> str:
    lines = [
        f"bench step: seed {report['seed']}, {report['steps']} steps, episode {report['episode_s']:.2f} s "
        f"({report['per_step_ms']:.0f} ms per step), {report['status']}",
        f"{'stage':<10} {'count':>6} {'median ms':>10} {'p95 ms':>9} {'max ms':>9}",
    ]
    for stage, figures in report["stages"].items():
        lines.append(f"{stage:<10} {figures['count']:>6} {figures['median_ms']:>10.2f} "
                     f"{figures['p95_ms']:>9.2f} {figures['max_ms']:>9.2f}")
    lines.append("tick counts every tick, including those that only poll a query in flight.")
    return "\n".join(lines)


def format_world_table(report: dict[str, Any]) -> str:
    lines = [f"bench world: camera {report['camera']}, median of {report['repeats']} homes per area"]
    rows = report["areas"]
    keys = list(next(iter(rows.values())))
    lines.append(f"{'area m²':>8} " + " ".join(f"{key:>14}" for key in keys))
    for area, figures in rows.items():
        lines.append(f"{area:>8} " + " ".join(f"{figures[key]:>14.3f}" for key in keys))
    return "\n".join(lines)


def dump(report: dict[str, Any]) -> str:
    return json.dumps(report, indent=2)
