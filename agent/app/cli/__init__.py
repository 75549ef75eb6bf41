"""The `homebot` command: world, run, watch, bench."""

from __future__ import annotations

import argparse
import json
import logging
import sys
from pathlib import Path
from typing import Any

from worlds.bus.session import EndpointError, open_session
from agent.app.config import Config, ConfigError, load_config
from agent.app.cli.skill import add_skill_commands

DEFAULT_AGENT_ENDPOINT = "tcp/127.0.0.1:7450"


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["world"]:
        from worlds.server import main as world_main

        return world_main(argv[1:])
    if argv[:1] == ["scene"]:
        from worlds.scene_cli import main as scene_main

        return scene_main(argv[1:])
    if argv[:1] == ["acsg"]:
        from agent.app.cli.acsg import main as acsg_main

        return acsg_main(argv[1:])
    if argv[:1] == ["lfe"]:
        from agent.app.cli.lfe import main as lfe_main

        return lfe_main(argv[1:])
    parser = _parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.DEBUG if args.verbose else logging.WARNING,
                        format="%(levelname)s %(name)s: %(message)s")
    try:
        return args.handler(args)
    except (ConfigError, EndpointError) as error:
        print(f"homebot: {error}", file=sys.stderr)
        return 2


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="homebot", description=__doc__)
    parser.add_argument("-v", "--verbose", action="store_true", help="log debug messages")
    commands = parser.add_subparsers(dest="command", required=True)
    commands.add_parser("world", help="serve a simulated home over Zenoh (see `homebot world --help`)")
    commands.add_parser("scene", help="make, draw and check scene specs (see `homebot scene --help`)")
    commands.add_parser("acsg", help="retrieval plans and pictures of scene graphs (see `homebot acsg --help`)")
    commands.add_parser("lfe", help="training data and training of the frontier-property network "
                                    "(see `homebot lfe --help`)")

    run = commands.add_parser("run", help="run one EQA episode against a simulated home")
    _config_options(run)
    run.add_argument("--seed", type=int, help="home and scenario seed (default 0)")
    run.add_argument("--suite", type=Path, help="a suite file (homebot suite make); with --scenario, run one of its "
                                                "scenarios in its home")
    run.add_argument("--scenario", metavar="ID", help="the id of the suite's scenario to run, e.g. test-0007")
    run.add_argument("--connect", metavar="ENDPOINT", help="join a running world instead of starting one")
    run.add_argument("--namespace", help="key prefix of the world to join (default homebot/default with --connect)")
    run.add_argument("--out", type=Path, default=Path("runs"), help="where run folders go (default ./runs)")
    run.add_argument("--method", choices=("fbe", "semantic", "semantic-no-lsv", "semantic-no-gsv", "lfe"),
                     help="exploration method (default semantic; same as --set explore.method=…)")
    run.add_argument("--stop", choices=("cp", "entropy", "relevance", "budget"),
                     help="stopping rule (default cp: conformal prediction; same as --set stop.rule=…)")
    run.add_argument("--epsilon", type=float,
                     help="accepted miscoverage ε of the conformal set (default 0.3; --set stop.epsilon=…)")
    run.set_defaults(handler=_run)

    add_skill_commands(commands)

    watch = commands.add_parser("watch", help="show a running agent's behaviour tree live")
    watch.add_argument("--connect", default=DEFAULT_AGENT_ENDPOINT, metavar="ENDPOINT",
                       help=f"the agent's listen endpoint (default {DEFAULT_AGENT_ENDPOINT})")
    watch.add_argument("--namespace", help="only this run's namespace (default: any run)")
    watch.add_argument("--once", action="store_true", help="print one snapshot and exit")
    watch.add_argument("--json", action="store_true", help="print snapshots as JSON")
    watch.add_argument("--timeout", type=float, default=30.0, help="seconds to wait for a snapshot (default 30)")
    watch.set_defaults(handler=_watch)

    suite = commands.add_parser("suite", help="make scenario suites")
    suites = suite.add_subparsers(dest="suite", required=True)
    make = suites.add_parser("make", help="write seeded scenarios as JSON lines, split in parts")
    make.add_argument("--n", type=int, required=True, help="how many scenarios in all")
    make.add_argument("--split", default=None, help="part sizes adding up to n, e.g. 300/200 (default: one part)")
    make.add_argument("--names", default="calib,test", help="part names, comma separated (default calib,test)")
    make.add_argument("--seed-base", type=int, default=0, help="first seed; parts take consecutive seeds")
    make.add_argument("--out", type=Path, default=Path("suites"), help="output folder (default ./suites)")
    make.add_argument("--hidden", choices=("any", "only", "never"), default="any",
                      help="hidden-evidence questions: mixed in (default), only those, or none")
    make.add_argument("--kinds", default=None,
                      help="question categories, comma separated (default: all five in the paper's shares)")
    make.set_defaults(handler=_suite_make)
    tabletop = suites.add_parser("tabletop", help="write the five tabletop suites of interactive exploration")
    tabletop.add_argument("--out", type=Path, default=Path("suites/tabletop"), help="output folder")
    tabletop.set_defaults(handler=_suite_tabletop)

    evaluate = commands.add_parser("eval", help="evaluate over a suite")
    evaluations = evaluate.add_subparsers(dest="eval", required=True)
    explore = evaluations.add_parser("explore", help="exploration methods: success rate against normalised time")
    _suite_run_options(explore, "runs/eval-explore", "results, curves.csv and curves.png go here; reruns resume")
    explore.add_argument("--methods", default="fbe,semantic,semantic-no-lsv,semantic-no-gsv",
                         help="comma separated (default: all four)")
    explore.set_defaults(handler=_eval_explore)
    stop = evaluations.add_parser("stop", help="stopping rules: CP against Entropy and Relevance (Fig. 9)")
    _suite_run_options(stop, "runs/eval-stop", "episodes, CSVs and stop-curves.png go here; reruns resume")
    stop.add_argument("--calibration", type=Path, required=True, help="a calibration file (homebot calibrate)")
    stop.set_defaults(handler=_eval_stop)

    interactive = evaluations.add_parser("interactive", help="interactive exploration: RoboEXP's Table I")
    interactive.add_argument("--suite", choices=("tabletop",), default="tabletop",
                             help="the five tabletop tasks, ten variants each (homebot suite tabletop)")
    interactive.add_argument("--tasks", default=None, help="comma separated (default: all five)")
    interactive.add_argument("--variants", type=int, default=10, help="variants per task (default 10)")
    interactive.add_argument("--executor", choices=("symbolic", "robot"), default="symbolic",
                             help="symbolic: perfect perception and skills (the decision logic alone); "
                                  "robot: the arm in PyBullet, perceiving with its cameras")
    interactive.add_argument("--workers", type=int, default=1,
                             help="scenes explored at once, each in its own process and world (default 1)")
    interactive.add_argument("--out", type=Path, default=Path("runs/eval-interactive"),
                             help="results go here; reruns resume")
    interactive.set_defaults(handler=_eval_interactive)

    coverage = evaluations.add_parser("coverage", help="learning-augmented exploration: coverage in 500 steps "
                                                       "(the paper's Table I)")
    coverage.add_argument("--homes", type=int, default=8, help="homes per size: small, medium, large (default 8)")
    coverage.add_argument("--methods", default="fbe-near,greedy,lfe,lfe-oracle",
                          help="comma separated (default: all four)")
    coverage.add_argument("--model", type=Path, default=None,
                          help="a trained model (homebot lfe train; default: the one shipped with homebot)")
    coverage.add_argument("--steps", type=int, default=500, help="step budget of an episode (default 500, the paper's)")
    coverage.add_argument("--workers", type=int, default=1, help="episodes at once, one process each (default 1)")
    coverage.add_argument("--out", type=Path, default=Path("runs/eval-coverage"),
                          help="results, table.md and coverage.png go here; reruns resume")
    coverage.set_defaults(handler=_eval_coverage)

    acts = evaluations.add_parser("acts", help="what the act branch did over an evaluation's episodes")
    acts.add_argument("results", type=Path, help="a results file (JSON lines), e.g. explore-results.jsonl")
    acts.add_argument("--method", help="only the episodes of this variant (e.g. semantic)")
    acts.set_defaults(handler=_eval_acts)

    calibrate = commands.add_parser("calibrate", help="calibrate conformal prediction on a suite")
    _suite_run_options(calibrate, "runs/calibration.json",
                       "the calibration file; episodes go beside it as .episodes.jsonl; reruns resume")
    calibrate.set_defaults(handler=_calibrate)

    bench = commands.add_parser("bench", help="measure speed")
    benches = bench.add_subparsers(dest="bench", required=True)
    step = benches.add_parser("step", help="per-stage time of each step over one fixed episode")
    _config_options(step)
    step.add_argument("--seed", type=int, default=0)
    step.add_argument("--area", type=float, default=None, help="floor area of the home in m² (60..300)")
    step.add_argument("--json", action="store_true", help="print the figures as JSON")
    step.set_defaults(handler=_bench_step)
    arm = benches.add_parser("skills", help="IK and trajectory computation times of the arm")
    arm.add_argument("--n", type=int, default=100, help="random target poses (default 100)")
    arm.add_argument("--seed", type=int, default=0)
    arm.add_argument("--scenes", default="door-only:0,drawer-only:0",
                     help="tabletop TASK:VARIANT explored by the robot to time every skill, comma separated "
                          "(default door-only:0,drawer-only:0; 'none' for kinematics only)")
    arm.add_argument("--json", action="store_true", help="print the figures as JSON")
    arm.set_defaults(handler=_bench_skills)
    plan = benches.add_parser("plan", help="LFE planning time per step against the number of frontiers")
    plan.add_argument("--steps", type=int, default=200, help="steps explored in each home (default 200)")
    plan.add_argument("--model", type=Path, default=None, help="a trained model (default: the shipped one)")
    plan.add_argument("--json", action="store_true", help="print the figures as JSON")
    plan.set_defaults(handler=_bench_plan)
    world = benches.add_parser("world", help="generation, build and render speed for homes of 60, 150, 300 m²")
    world.add_argument("--areas", default="60,150,300", help="floor areas in m², comma separated")
    world.add_argument("--repeats", type=int, default=3, help="homes per area (default 3)")
    world.add_argument("--json", action="store_true", help="print the figures as JSON")
    world.set_defaults(handler=_bench_world)
    return parser


def _config_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--config", type=Path, help="a TOML file of settings")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="override one setting, e.g. --set vlm.sim.skill=0.6 (repeatable)")
    parser.add_argument("--listen", action="append", metavar="ENDPOINT",
                        help=f"where `homebot watch` can reach this agent (default {DEFAULT_AGENT_ENDPOINT})")


def _suite_run_options(parser: argparse.ArgumentParser, out: str, out_help: str) -> None:
    """Options of the commands that run a suite's episodes to their full budget in workers."""
    _config_options(parser)
    parser.add_argument("--suite", type=Path, required=True, help="a suite file (homebot suite make)")
    parser.add_argument("--workers", type=int, default=2, help="parallel episodes, each with its own world")
    parser.add_argument("--limit", type=int, default=None, help="only the first N scenarios")
    parser.add_argument("--out", type=Path, default=Path(out), help=f"{out_help} (default {out})")
    parser.add_argument("--worlds", metavar="ENDPOINTS",
                        help="join running worlds instead of starting one per worker: comma-separated "
                             "[NAMESPACE@]ENDPOINT, e.g. tcp/10.0.0.2:7447,tcp/10.0.0.3:7447 (one worker each)")


def _suite_config(args: argparse.Namespace) -> Config | None:
    """The config of a suite run (workers need no watcher endpoint), or None after a clear message.

    Also checks ``--worlds`` and leaves the parsed addresses in ``args.world_addresses``.
    """
    from agent.app.eval.runner import WorldAddress

    if args.workers < 1:
        print(f"homebot: --workers must be at least 1, got {args.workers}", file=sys.stderr)
        return None
    try:
        args.world_addresses = [WorldAddress.parse(w) for w in args.worlds.split(",") if w.strip()] if args.worlds else None
    except ValueError as error:
        print(f"homebot: --worlds: {error}", file=sys.stderr)
        return None
    return load_config(args.config, [*args.set, "bus.listen=[]"])


def _load(args: argparse.Namespace) -> Config:
    overrides = list(args.set)
    if args.listen:
        overrides.append("bus.listen=" + json.dumps(args.listen))
    return load_config(args.config, overrides)


def _run(args: argparse.Namespace) -> int:
    from agent.app.runtime.run import RunError, RunRequest, run_episode
    from agent.app.runtime.progress import StepPrinter

    try:
        seed, scenario, what = _episode_choice(args)
    except ValueError as error:
        print(f"homebot run: {error}", file=sys.stderr)
        return 2
    args.set.extend(shortcut_overrides(args))
    config = _load(args)
    request = RunRequest(seed=seed, config=config, out_root=args.out, connect=args.connect,
                         namespace=args.namespace, scenario=scenario)
    print(f"homebot run: {what}, {'joining ' + args.connect if args.connect else 'starting a world'}; "
          f"watch with `homebot watch --connect {config.bus.listen[0]}`", flush=True)
    try:
        result = run_episode(request, extra_sinks=[StepPrinter(sys.stdout)])
    except RunError as error:
        print(f"homebot run: {error}", file=sys.stderr)
        return 1
    verdict = "correct" if result["correct"] else "wrong"
    if result["status"] == "answered":
        print(f"answer {result['answer']} ({result['answer_text']}); truth {result['ground_truth']} "
              f"({result['ground_truth_text']}): {verdict}, {result['steps']} steps, {result['seconds']:.1f} s")
    else:
        print(f"episode failed: {result['reason']}", file=sys.stderr)
    print(f"run folder: {result['folder']}")
    return 0 if result["status"] == "answered" else 1


def _episode_choice(args: argparse.Namespace) -> tuple[int, dict[str, Any] | None, str]:
    """(seed, scenario or None, a few words saying which) for `homebot run`: the seed's own
    scenario, or with ``--suite`` and ``--scenario`` that suite line's scenario and seed. Raises
    ValueError (a SuiteError for the file) naming the option at fault."""
    from worlds.suite import suite_entry

    if (args.suite is None) != (args.scenario is None):
        raise ValueError("--suite and --scenario go together: the suite file and the id of one of its scenarios")
    if args.suite is None:
        seed = 0 if args.seed is None else args.seed
        return seed, None, f"seed {seed}"
    if args.seed is not None:
        raise ValueError("--seed: cannot be combined with --suite (the suite's line gives the seed)")
    try:
        entry = suite_entry(args.suite, args.scenario)
    except OSError as error:
        raise ValueError(f"--suite: {error}") from None
    return entry["seed"], entry["scenario"], f"{args.suite} {entry['id']} (seed {entry['seed']})"


def shortcut_overrides(args: argparse.Namespace) -> list[str]:
    """The ``--set`` overrides that ``run``'s shortcut options (--method, --stop, --epsilon) stand for."""
    shortcuts = {"explore.method": args.method, "stop.rule": args.stop, "stop.epsilon": args.epsilon}
    return [f"{key}={value}" for key, value in shortcuts.items() if value is not None]


def _watch(args: argparse.Namespace) -> int:
    from agent.app.watch import watch

    session = open_session(connect=[args.connect])
    try:
        return watch(session, args.namespace, args.once, args.json, args.timeout)
    finally:
        session.close()


def _suite_make(args: argparse.Namespace) -> int:
    from worlds.suite import SuiteError, plan_split, write_suite

    try:
        split = [int(k) for k in args.split.split("/")] if args.split else [args.n]
    except ValueError:
        print(f"homebot suite make: --split {args.split!r}: expected sizes like 300/200", file=sys.stderr)
        return 2
    names = tuple(n.strip() for n in args.names.split(",") if n.strip()) if len(split) > 1 else ("suite",)
    try:
        parts = plan_split(args.n, split, args.seed_base, names)
    except SuiteError as error:
        print(f"homebot suite make: {error}", file=sys.stderr)
        return 2

    def progress(part: str, done: int, total: int) -> None:
        end = "\n" if done == total else ""
        print(f"\r  {part}: {done}/{total} scenarios", end=end, file=sys.stderr, flush=True)

    kinds = tuple(k.strip() for k in args.kinds.split(",")) if args.kinds else None
    hidden = {"any": None, "only": True, "never": False}[args.hidden]
    try:
        paths = write_suite(args.out, parts, progress, kinds=kinds, hidden=hidden)
    except SuiteError as error:
        print(f"\nhomebot suite make: {error}", file=sys.stderr)
        return 2
    for part in parts:
        print(f"{paths[part.name]}: seeds {part.seeds.start}..{part.seeds.stop - 1}")
    return 0


def _eval_explore(args: argparse.Namespace) -> int:
    from agent.app.eval.method_comparison import evaluate_explore
    from worlds.suite import SuiteError

    config = _suite_config(args)
    if config is None:
        return 2
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    try:
        report = evaluate_explore(args.suite, methods, args.out, args.workers, config, args.limit,
                                  args.world_addresses)
    except (ValueError, SuiteError, OSError) as error:
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


def _calibrate(args: argparse.Namespace) -> int:
    from agent.eqa.calibration import CalibrationError
    from agent.app.eval.calibrate import calibrate, episodes_path
    from worlds.suite import SuiteError

    config = _suite_config(args)
    if config is None:
        return 2
    try:
        calibration = calibrate(args.suite, args.out, args.workers, config, args.limit, args.world_addresses)
    except (CalibrationError, SuiteError, OSError) as error:
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


def _eval_stop(args: argparse.Namespace) -> int:
    from agent.eqa.calibration import CalibrationError
    from agent.app.eval.stop import evaluate_stop
    from worlds.suite import SuiteError

    config = _suite_config(args)
    if config is None:
        return 2
    try:
        report = evaluate_stop(args.suite, args.calibration, args.out, args.workers, config, args.limit,
                               args.world_addresses)
    except (CalibrationError, SuiteError, ValueError, OSError) as error:
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
    from agent.app.eval.interactive import COLUMNS, PAPER_SUCCESS, evaluate_interactive, print_progress
    from worlds.tabletop import TASKS

    tasks = [t.strip() for t in args.tasks.split(",") if t.strip()] if args.tasks else list(TASKS)
    try:
        report = evaluate_interactive(args.out, tasks, args.variants, args.executor, print_progress, args.workers)
    except ValueError as error:
        print(f"homebot eval interactive: {error}", file=sys.stderr)
        return 2
    print(f"{report['n']} scenes, executor {args.executor}; mean ± s.e. over the variants")
    print(f"{'task':<12}" + "".join(f"{c.replace('_', ' '):>22}" for c in COLUMNS) + f"{'paper success':>15}")
    for task, row in report["table"].items():
        cells = "".join(f"{row[c][0]:>15.2f} ± {row[c][1]:<4.2f}" for c in COLUMNS)
        print(f"{task:<12}{cells}{PAPER_SUCCESS[task]:>15.0%}")
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
    from agent.app.eval.coverage import evaluate_coverage, format_table, plot_curves, print_progress

    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    try:
        report = evaluate_coverage(args.out, args.homes, methods, args.workers, args.model, args.steps,
                                   print_progress)
    except ValueError as error:
        print(f"homebot eval coverage: {error}", file=sys.stderr)
        return 2
    text = format_table(report["table"])
    (args.out / "table.md").write_text(text + "\n", encoding="utf-8")
    figure = plot_curves(report["rows"], methods, args.out / "coverage.png")
    print(f"{report['n']} episodes; coverage % in {args.steps} steps, mean ± s.e. over the homes")
    print(text)
    print(f"results {report['results']}, curves {figure}")
    return 0


def _suite_tabletop(args: argparse.Namespace) -> int:
    from worlds.tabletop import write_tabletop_suites

    for path in write_tabletop_suites(args.out):
        print(path)
    return 0


def _bench_world(args: argparse.Namespace) -> int:
    from agent.app.bench import dump, format_world_table
    from worlds.scene_cli import bench_world

    try:
        areas = tuple(float(a) for a in args.areas.split(","))
    except ValueError:
        print(f"homebot bench world: --areas {args.areas!r}: expected numbers like 60,150,300", file=sys.stderr)
        return 2
    report = bench_world(areas, args.repeats)
    print(dump(report) if args.json else format_world_table(report))
    return 0


def _bench_skills(args: argparse.Namespace) -> int:
    from agent.app.bench import bench_skills, dump, format_skills_table

    if args.n < 1:
        print(f"homebot bench skills: --n must be at least 1, got {args.n}", file=sys.stderr)
        return 2
    try:
        scenes = _tabletop_scenes(args.scenes)
    except ValueError as error:
        print(f"homebot bench skills: --scenes: {error}", file=sys.stderr)
        return 2
    report = bench_skills(args.n, args.seed, scenes)
    print(dump(report) if args.json else format_skills_table(report))
    return 0


def _bench_plan(args: argparse.Namespace) -> int:
    from agent.app.bench import dump
    from agent.app.eval.coverage import SEED_BASE, SIZES, home_area
    from agent.app.bench.lfe import bench_plan, format_plan_table

    if args.steps < 1:
        print(f"homebot bench plan: --steps must be at least 1, got {args.steps}", file=sys.stderr)
        return 2
    homes = [(SEED_BASE + 1000 * band, home_area(size, SEED_BASE + 1000 * band)) for band, size in enumerate(SIZES)]

    def progress(done: int, total: int, plans: int) -> None:
        print(f"  home {done}/{total}: {plans} planning steps timed", file=sys.stderr, flush=True)

    report = bench_plan(homes, args.model, args.steps, progress)
    print(dump(report) if args.json else format_plan_table(report))
    return 0


def _tabletop_scenes(text: str) -> list[tuple[str, int]]:
    """``"door-only:0,drawer-only:3"`` -> [("door-only", 0), ("drawer-only", 3)]; ``"none"`` -> []."""
    from worlds.tabletop import TASKS, VARIANTS

    if text.strip() == "none":
        return []
    scenes = []
    for item in (part.strip() for part in text.split(",") if part.strip()):
        task, _, variant = item.partition(":")
        if task not in TASKS:
            raise ValueError(f"{item!r}: unknown task {task!r} (known: {', '.join(TASKS)})")
        if not variant.isdigit() or not 0 <= int(variant) < VARIANTS:
            raise ValueError(f"{item!r}: the variant must be a number 0..{VARIANTS - 1}")
        scenes.append((task, int(variant)))
    return scenes


def _bench_step(args: argparse.Namespace) -> int:
    from agent.app.bench import bench_step, dump, format_step_table

    report = bench_step(_load(args), args.seed, args.area)
    print(dump(report) if args.json else format_step_table(report))
    return 0

