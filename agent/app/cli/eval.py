"""`homebot eval`: evaluations over a suite, each printing its table and writing its figures.

``explore`` (exploration methods), ``stop`` (stopping rules), ``interactive`` (RoboEXP's tabletop
tasks), ``coverage`` (learning-augmented exploration) and ``acts`` (what the act branch did over
an evaluation's episodes).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from agent.app.cli.options import (Commands, add_ray_option, add_suite_run_options, count_option, seed_option,
                                   suite_settings)
from worlds.tabletop_splits import SPLITS

RECORD_HELP = ("keep each episode's run folder with its Rerun recording under OUT/recordings "
               "(homebot replay opens one); without it evaluation episodes record nothing")


def add_command(commands: Commands) -> None:
    """Add ``eval`` and its five evaluations with their options.

    Args:
        commands: the `homebot` parser's commands.
    """
    evaluate = commands.add_parser("eval", help="evaluate over a suite")
    evaluations = evaluate.add_subparsers(dest="eval", required=True)
    explore = evaluations.add_parser("explore", help="exploration methods: success rate against normalised time")
    add_suite_run_options(explore, "runs/eval-explore", "results, curves.csv and curves.png go here; reruns resume")
    explore.add_argument("--methods", default="fbe,semantic,semantic-no-lsv,semantic-no-gsv",
                         help="comma separated (default: all four)")
    explore.add_argument("--record", action="store_true", help=RECORD_HELP)
    explore.set_defaults(handler=_eval_explore)
    stop = evaluations.add_parser("stop", help="stopping rules: CP against Entropy and Relevance (Fig. 9)")
    add_suite_run_options(stop, "runs/eval-stop", "episodes, CSVs and stop-curves.png go here; reruns resume")
    stop.add_argument("--calibration", type=Path, required=True, help="a calibration file (homebot calibrate)")
    stop.add_argument("--record", action="store_true", help=RECORD_HELP)
    stop.set_defaults(handler=_eval_stop)

    interactive = evaluations.add_parser("interactive", help="interactive exploration: RoboEXP's Table I")
    interactive.add_argument("--suite", choices=("tabletop",), default="tabletop",
                             help="the five tabletop tasks, any number of variants each (homebot suite tabletop)")
    interactive.add_argument("--tasks", default=None, help="comma separated (default: all five)")
    interactive.add_argument("--split", choices=tuple(SPLITS), default=None,
                             help="a fixed range of seeds: " + "; ".join(
                                 f"{s.name}: seeds {s.seeds().start}-{s.seeds().stop - 1}, {s.use}"
                                 for s in SPLITS.values()))
    interactive.add_argument("--variants", type=count_option, default=None,
                             help="variants per task (default: the split's, else 10); with a split, its first N")
    interactive.add_argument("--seed-base", type=seed_option, default=None,
                             help="the first variant's seed, without --split (default 0: the tuning seeds)")
    interactive.add_argument("--executor", choices=("symbolic", "robot"), default="symbolic",
                             help="symbolic: perfect perception and skills (the decision logic alone); "
                                  "robot: the arm in PyBullet, perceiving with its cameras")
    interactive.add_argument("--workers", type=count_option, default=1,
                             help="scenes explored at once, each in its own process and world (default 1)")
    interactive.add_argument("--out", type=Path, default=Path("runs/eval-interactive"),
                             help="results go here; reruns resume")
    interactive.add_argument("--record", action="store_true", help=RECORD_HELP.replace("episode", "scene"))
    add_ray_option(interactive, "scene")
    interactive.set_defaults(handler=_eval_interactive)

    coverage = evaluations.add_parser("coverage", help="learning-augmented exploration: coverage in 500 steps "
                                                       "(the paper's Table I)")
    coverage.add_argument("--homes", type=count_option, default=8,
                          help="homes per size: small, medium, large (default 8)")
    coverage.add_argument("--methods", default="fbe-near,greedy,lfe,lfe-oracle",
                          help="comma separated (default: all four)")
    coverage.add_argument("--model", type=Path, default=None,
                          help="a trained model (homebot lfe train; default: the one shipped with homebot)")
    coverage.add_argument("--steps", type=count_option, default=500,
                          help="step budget of an episode (default 500, the paper's)")
    coverage.add_argument("--workers", type=count_option, default=1,
                          help="episodes at once, one process each (default 1)")
    coverage.add_argument("--out", type=Path, default=Path("runs/eval-coverage"),
                          help="results, table.md and coverage.png go here; reruns resume")
    add_ray_option(coverage, "episode")
    coverage.set_defaults(handler=_eval_coverage)

    acts = evaluations.add_parser("acts", help="what the act branch did over an evaluation's episodes")
    acts.add_argument("results", type=Path, help="a results file (JSON lines), e.g. explore-results.jsonl")
    acts.add_argument("--method", help="only the episodes of this variant (e.g. semantic)")
    acts.set_defaults(handler=_eval_acts)


def _eval_explore(args: argparse.Namespace) -> int:
    from agent.app.eval.method_comparison import evaluate_explore
    from agent.app.runtime.ray_backend import RayError
    from worlds.suite import SuiteError

    config = suite_settings(args)
    if config is None:
        return 2
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    try:
        report = evaluate_explore(args.suite, methods, args.out, args.workers, config, args.limit,
                                  args.world_addresses, _recordings(args), args.ray)
    except (ValueError, SuiteError, RayError, OSError) as error:
        print(f"homebot eval explore: {error}", file=sys.stderr)
        return 2
    taus = report["taus"]
    marks = [i for i, tau in enumerate(taus) if round(tau, 2) in (0.25, 0.5, 0.75, 1.0)]
    for heading, curves, counts, unit in (("success", report["curves"], report["counts"], "%"),
                                          ("target seen", report["target_seen"], report["target_seen_counts"], "%"),
                                          ("floor seen", report["floor_seen"], report["reported_counts"], "%"),
                                          ("rooms entered", report["rooms_entered"], report["reported_counts"], "")):
        print(f"{heading:<18} {'n':>4} " + " ".join(f"{'τ=' + format(taus[i], '.2f'):>7}" for i in marks))
        scale = 100 if unit else 1
        for method, curve in curves.items():
            print(f"  {method:<16} {counts[method]:>4} "
                  + " ".join(f"{scale * curve[i]:>6.1f}{unit or ' '}" for i in marks))
    print(f"{report['failed']} failed episodes; results {report['results']}; curves in {args.out}/curves.png and .csv")
    return 0


def _eval_stop(args: argparse.Namespace) -> int:
    from agent.eqa.calibration import CalibrationError
    from agent.app.eval.stop import evaluate_stop
    from agent.app.runtime.ray_backend import RayError
    from worlds.suite import SuiteError

    config = suite_settings(args)
    if config is None:
        return 2
    try:
        report = evaluate_stop(args.suite, args.calibration, args.out, args.workers, config, args.limit,
                               args.world_addresses, _recordings(args), args.ray)
    except (CalibrationError, SuiteError, ValueError, RayError, OSError) as error:
        print(f"homebot eval stop: {error}", file=sys.stderr)
        return 2
    print(f"{report['n']} test episodes ({report['failed']} failed), calibrated on {report['calibration_n']}")
    print("normalised steps each rule needs to reach a success rate (— : never reached)")
    rules = ("cp", "relevance", "entropy")
    print(f"  {'success':>8} {'of full':>8}" + "".join(f"{rule:>11}" for rule in rules))
    for row in report["reach"]:
        cells = "".join(f"{'—' if row[r] is None else format(row[r], '.3f'):>11}" for r in rules)
        print(f"  {row['success']:>8.1%} {row['share_of_full_budget_success']:>8.0%}{cells}")
    print("coverage of the conformal set at the end of the budget")
    print(f"  {'ε':<6}{'1−ε':>6}{'q̂':>8}{'coverage':>10}{'± s.e.':>8}{'|C|':>6}")
    for row in report["coverage"]:
        q_hat = "inf" if row["q_hat"] == float("inf") else f"{row['q_hat']:.3f}"
        print(f"  {row['epsilon']:<6g}{row['promised']:>6.2f}{q_hat:>8}{row['coverage']:>10.3f}"
              f"{row['standard_error']:>8.3f}{row['mean_set_size']:>6.2f}")
    print(f"figures in {args.out}/stop-curves.png, stop-curves.csv, coverage.csv, steps-to-reach.csv")
    return 0


def _eval_interactive(args: argparse.Namespace) -> int:
    from agent.app.eval.failure_causes import format_cause_table
    from agent.app.eval.interactive import (COLUMNS, PAPER_SUCCESS, evaluate_interactive, scene_progress,
                                            split_seeds)
    from agent.app.runtime.ray_backend import RayError
    from worlds.tabletop import TASKS

    tasks = [t.strip() for t in args.tasks.split(",") if t.strip()] if args.tasks else list(TASKS)
    try:
        seed_base, variants = split_seeds(args.split, args.variants, args.seed_base, args.record)
        report = evaluate_interactive(args.out, tasks, variants, args.executor, scene_progress(), args.workers,
                                      _recordings(args), seed_base, args.ray)
    except (ValueError, RayError) as error:
        print(f"homebot eval interactive: {error}", file=sys.stderr)
        return 2
    first, last = report["seeds"]
    print(f"{report['n']} scenes (seeds {first}-{last}{f', {args.split} split' if args.split else ''}), "
          f"executor {args.executor}; mean ± s.e. over the variants")
    print(f"{'task':<12}" + "".join(f"{c.replace('_', ' '):>22}" for c in COLUMNS) + f"{'paper success':>15}")
    for task, row in report["table"].items():
        cells = "".join(f"{row[c][0]:>15.2f} ± {row[c][1]:<4.2f}" for c in COLUMNS)
        print(f"{task:<12}{cells}{PAPER_SUCCESS[task]:>15.0%}")
    print("\nfailures by cause")
    print(format_cause_table(report["causes"]))
    print(f"results {report['results']}")
    return 0


def _eval_acts(args: argparse.Namespace) -> int:
    from agent.app.eval.acts import default_stopping, format_summary, summarise
    from agent.app.eval.runner import read_results

    if not args.results.is_file():
        print(f"homebot eval acts: {args.results}: no such file", file=sys.stderr)
        return 2
    print(format_summary(summarise(read_results(args.results), args.method, default_stopping())))
    return 0


def _eval_coverage(args: argparse.Namespace) -> int:
    from agent.app.eval.coverage import episode_progress, evaluate_coverage, format_table, plot_curves
    from agent.app.runtime.ray_backend import RayError

    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    try:
        report = evaluate_coverage(args.out, args.homes, methods, args.workers, args.model, args.steps,
                                   episode_progress(), args.ray)
    except (ValueError, RayError) as error:
        print(f"homebot eval coverage: {error}", file=sys.stderr)
        return 2
    text = format_table(report["table"])
    (args.out / "table.md").write_text(text + "\n", encoding="utf-8")
    figure = plot_curves(report["rows"], methods, args.out / "coverage.png")
    print(f"{report['n']} episodes; coverage % in {args.steps} steps, mean ± s.e. over the homes")
    print(text)
    print(f"results {report['results']}, curves {figure}")
    return 0


def _recordings(args: argparse.Namespace) -> Path | None:
    """Where ``--record`` keeps the episodes' run folders (``OUT/recordings``), or None without it."""
    return args.out / "recordings" if args.record else None
