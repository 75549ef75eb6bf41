"""How fast the arm's planning is: IK solves and trajectory computations over random targets.

Targets are the TCP poses of random in-limit configurations, so every one is reachable and the
success rate measures the solver, not the sampling. Each solve starts from the middle of the joint
ranges, as a fresh request would. Pure and seeded; it backs ``homebot bench skills``.
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from skills.arm.ik_solver import solve_ik
from skills.arm.kinematics import ArmKinematics
from skills.arm.trajectory import JointLimits, plan_trajectory


def bench_arm(urdf_xml: str, joints: Sequence[str], tcp_frame: str, n: int = 100, seed: int = 0, *,
              limits: JointLimits | None = None, dt: float = 0.01, waypoints: int = 5) -> dict[str, float | int]:
    """Median and 95th-percentile milliseconds of ``n`` IK solves and of the trajectories to them.

    Each trajectory runs from the start configuration to the IK solution through ``waypoints``
    evenly spaced joint waypoints (passing through them at speed), sampled every ``dt``. Without
    ``limits``: the URDF's velocity limits, accelerations 4× and jerks 40× those.

    Args:
        urdf_xml: the robot's URDF.
        joints: the arm's joints, in order.
        tcp_frame: the TCP's frame.
        n: how many IK solves.
        seed: the random targets' seed.
        limits: the joint limits (from the URDF when None).
        dt: the trajectories' sample time (s).
        waypoints: the joint waypoints of each trajectory, ends included.

    Returns:
        The figures.

    Raises:
        ValueError: n below 1 or fewer than two waypoints.
    """
    if n < 1:
        raise ValueError(f"n: {n!r} must be at least 1")
    if waypoints < 2:
        raise ValueError(f"waypoints: {waypoints!r} must be at least 2")
    kin = ArmKinematics(urdf_xml, joints, tcp_frame)
    if limits is None:
        limits = JointLimits(kin.velocity_limits, 4.0 * kin.velocity_limits, 40.0 * kin.velocity_limits)
    targets_rng, solver_rng = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(2))
    start = kin.home()
    ik_ms, trajectory_ms, durations = [], [], []
    successes = iterations = restarts = 0
    for _ in range(n):
        target = kin.forward(kin.random_configuration(targets_rng))
        began = time.perf_counter()
        result = solve_ik(kin, target, start, solver_rng)
        ik_ms.append(1e3 * (time.perf_counter() - began))
        successes += result.success
        iterations += result.iterations
        restarts += result.restarts
        if not result.success:
            continue
        path = start + np.linspace(0.0, 1.0, waypoints)[:, None] * (result.q - start)
        began = time.perf_counter()
        trajectory = plan_trajectory(path, limits, dt)
        trajectory_ms.append(1e3 * (time.perf_counter() - began))
        durations.append(trajectory.duration)
    return {
        "n": n,
        "seed": seed,
        "dof": kin.dof,
        "ik_success_rate": successes / n,
        "ik_ms_median": float(np.median(ik_ms)),
        "ik_ms_p95": float(np.percentile(ik_ms, 95)),
        "ik_iterations_mean": iterations / n,
        "ik_restarts_mean": restarts / n,
        "trajectory_ms_median": float(np.median(trajectory_ms)) if trajectory_ms else float("nan"),
        "trajectory_ms_p95": float(np.percentile(trajectory_ms, 95)) if trajectory_ms else float("nan"),
        "trajectory_s_median": float(np.median(durations)) if durations else float("nan"),
        "trajectory_waypoints": waypoints,
        "trajectory_dt": dt,
    }
