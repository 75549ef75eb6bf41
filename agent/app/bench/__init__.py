"""`homebot bench …`: figures to compare across runs, never assertions (the step bench is in `step`)."""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any

import numpy as np


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
