"""`homebot calibrate`: conformal prediction calibrated on a suite's full-budget episodes."""

from __future__ import annotations

import argparse
import sys

from agent.app.cli.options import Commands, add_suite_run_options, suite_settings


def add_command(commands: Commands) -> None:
    """Add ``calibrate`` and its options.

    Args:
        commands: the `homebot` parser's commands.
    """
    calibrate = commands.add_parser("calibrate", help="calibrate conformal prediction on a suite")
    add_suite_run_options(calibrate, "runs/calibration.json",
                          "the calibration file; episodes go beside it as .episodes.jsonl; reruns resume")
    calibrate.set_defaults(handler=_calibrate)


def _calibrate(args: argparse.Namespace) -> int:
    from agent.eqa.calibration import CalibrationError
    from agent.app.eval.calibrate import calibrate, episodes_path
    from agent.app.runtime.ray_backend import RayError
    from worlds.suite import SuiteError

    config = suite_settings(args)
    if config is None:
        return 2
    try:
        calibration = calibrate(args.suite, args.out, args.workers, config, args.limit, args.world_addresses,
                                args.ray)
    except (CalibrationError, SuiteError, RayError, OSError) as error:
        print(f"homebot calibrate: {error}", file=sys.stderr)
        return 2
    n = len(calibration.episodes)
    print(f"{n} calibration episodes ({len(calibration.failed)} failed), policy {config.explore.method}, "
          f"VLM {config.vlm.backend}")
    print("  ε      1−ε    q̂")
    for epsilon in (0.05, 0.1, 0.2, 0.3, 0.4, 0.5):
        q_hat = calibration.q_hat(epsilon)
        print(f"  {epsilon:<6g} {1 - epsilon:<6.2f} {q_hat:.4f}" if q_hat != float("inf") else
              f"  {epsilon:<6g} {1 - epsilon:<6.2f} +inf (needs more than {n} episodes)")
    print(f"calibration file {args.out}; episodes {episodes_path(args.out)}")
    return 0
