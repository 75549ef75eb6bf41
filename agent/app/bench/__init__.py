"""`homebot bench …`: figures to compare across runs, never assertions."""

from __future__ import annotations

import json
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from agent.app.config import Config, load_config
from agent.app.runtime.run import RunRequest, run_episode
from agent.timing import StageTimer
from worlds.home import generate_home
from worlds.spec import dump_spec

STAGES = ("render", "transport", "tsdf", "planning", "vlm", "tick")


def bench_step(config: Config, seed: int, area_m2: float | None = None) -> dict[str, Any]:
    """Run one fixed episode (the seed's home, or one of ``area_m2``) with per-stage timing.

    The episode explores to its budget whatever the stopping rule, so runs compare the same steps.

    Args:
        config: the settings (the stopping rule is set to the budget).
        seed: the home's and the episode's seed.
        area_m2: the home's floor area (the seed's own when None).

    Returns:
        The report: the home, the episode's time and status, the size of its snapshot log, and each
        stage's timing.
    """
    config = load_config(overrides=["stop.rule=budget"], base=config)
    timer = StageTimer()
    home = generate_home(seed, area_m2=area_m2)
    with tempfile.TemporaryDirectory(prefix="homebot-bench-") as scratch:
        request = RunRequest(seed=seed, config=config, out_root=Path(scratch), scene=dump_spec(home), save_map=False,
                             record=False)
        result = run_episode(request, timer=timer)
        snapshot_bytes = (Path(result["folder"]) / "snapshots.jsonl").stat().st_size
    summary = timer.summary()
    steps = max(1, result.get("steps", 0))
    return {"seed": seed, "area_m2": round(home.area_m2, 1), "rooms": len(home.rooms),
            "steps": result.get("steps", 0), "status": result["status"],
            "episode_s": result["seconds"], "per_step_ms": 1000.0 * result["seconds"] / steps,
            "ticks": result["ticks"], "snapshot_bytes": snapshot_bytes,
            "stages": {stage: summary[stage] for stage in STAGES if stage in summary}}


def format_step_table(report: dict[str, Any]) -> str:
    """The `bench_step` report as a table: one line for the episode, one per stage.

    Args:
        report: the report.

    Returns:
        The table's text.
    """
    lines = [
        f"bench step: seed {report['seed']}, {report['area_m2']} m², {report['rooms']} rooms, "
        f"{report['steps']} steps, episode {report['episode_s']:.2f} s "
        f"({report['per_step_ms']:.0f} ms per step), {report['status']}",
        f"snapshots: {report['snapshot_bytes'] / 1e6:.2f} MB for {report['ticks']} ticks",
        f"{'stage':<10} {'count':>6} {'median ms':>10} {'p95 ms':>9} {'max ms':>9}",
    ]
    for stage, figures in report["stages"].items():
        lines.append(f"{stage:<10} {figures['count']:>6} {figures['median_ms']:>10.2f} "
                     f"{figures['p95_ms']:>9.2f} {figures['max_ms']:>9.2f}")
    lines.append("tick counts every tick, including those that only poll a query in flight.")
    return "\n".join(lines)


def format_world_table(report: dict[str, Any]) -> str:
    """The world bench's report as a table: one row per floor area, one column per figure.

    Args:
        report: the report.

    Returns:
        The table's text.
    """
    lines = [f"bench world: camera {report['camera']}, median of {report['repeats']} homes per area"]
    rows = report["areas"]
    keys = list(next(iter(rows.values())))
    lines.append(f"{'area m²':>8} " + " ".join(f"{key:>14}" for key in keys))
    for area, figures in rows.items():
        lines.append(f"{area:>8} " + " ".join(f"{figures[key]:>14.3f}" for key in keys))
    return "\n".join(lines)


def dump(report: dict[str, Any]) -> str:
    """A report as indented JSON, for ``--json``.

    Args:
        report: the report.

    Returns:
        The JSON text.
    """
    return json.dumps(report, indent=2)


def bench_skills(n: int = 100, seed: int = 0, scenes: Sequence[tuple[str, int]] = ()) -> dict[str, Any]:
    """IK solve and trajectory computation times on the robot's own URDF and joint limits; with
    ``scenes`` (tabletop task, variant), the robot explores each and every skill run is timed.

    Args:
        n: the IK solves to time.
        seed: the random poses' seed.
        scenes: the tabletop (task, variant) pairs the robot explores.

    Returns:
        The report.
    """
    report = _bench_kinematics(n, seed)
    if scenes:
        from agent.app.eval.robot_tabletop import run_robot

        runs = []
        for task, variant in scenes:
            runs += run_robot(task, variant)["skill_times"]
        report["scenes"] = [f"{task}:{variant}" for task, variant in scenes]
        report["per_skill"] = {
            name: {"runs": len(rows), "ok": sum(r["ok"] for r in rows),
                   "planning_ms_median": float(np.median([r["planning_ms"] for r in rows])),
                   "execution_s_median": float(np.median([r["execution_s"] for r in rows])),
                   "wall_s_median": float(np.median([r["wall_s"] for r in rows])),
                   "wall_s_max": float(np.max([r["wall_s"] for r in rows]))}
            for name in sorted({r["skill"] for r in runs}) for rows in [[r for r in runs if r["skill"] == name]]
        }
    return report


def _bench_kinematics(n: int, seed: int) -> dict[str, Any]:
    from agent.app.bench.arm import bench_arm
    from skills.arm.trajectory import JointLimits
    from worlds.robot import CameraConfig
    from worlds.robot_arm import arm_spec, homebot_urdf

    spec = arm_spec()
    limits = JointLimits(tuple(j.velocity for j in spec.joints), tuple(j.acceleration for j in spec.joints),
                         tuple(j.jerk for j in spec.joints))
    return bench_arm(homebot_urdf(CameraConfig()), [j.name for j in spec.joints], spec.tcp_frame, n, seed,
                     limits=limits)


def format_skills_table(report: dict[str, Any]) -> str:
    """The `bench_skills` report as lines: IK and trajectory timing, then each skill's runs.

    Args:
        report: the report.

    Returns:
        The table's text.
    """
    return "\n".join([
        f"bench skills: {report['n']} random reachable TCP poses, seed {report['seed']}, {report['dof']} joints "
        "(lift + Panda)",
        f"IK (damped least squares)  median {report['ik_ms_median']:.2f} ms, p95 {report['ik_ms_p95']:.2f} ms, "
        f"success {report['ik_success_rate']:.0%}, {report['ik_iterations_mean']:.1f} iterations, "
        f"{report['ik_restarts_mean']:.2f} restarts on average",
        f"trajectory (Ruckig, {report['trajectory_waypoints']} waypoints, dt {report['trajectory_dt']} s)  "
        f"median {report['trajectory_ms_median']:.2f} ms, p95 {report['trajectory_ms_p95']:.2f} ms to compute; "
        f"{report['trajectory_s_median']:.2f} s to run",
        *_per_skill_lines(report),
    ])


def _per_skill_lines(report: dict[str, Any]) -> list[str]:
    if "per_skill" not in report:
        return []
    lines = [f"skills while exploring {', '.join(report['scenes'])} (median; wall = planning + running + checks)",
             f"{'skill':<14}{'runs':>6}{'ok':>5}{'planning ms':>13}{'running s':>11}{'wall s':>9}{'max wall s':>12}"]
    for name, row in report["per_skill"].items():
        lines.append(f"{name:<14}{row['runs']:>6}{row['ok']:>5}{row['planning_ms_median']:>13.0f}"
                     f"{row['execution_s_median']:>11.2f}{row['wall_s_median']:>9.2f}{row['wall_s_max']:>12.2f}")
    return lines
