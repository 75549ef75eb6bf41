"""`homebot run`: one EQA episode against a simulated home, started here or joined."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from agent.app.cli.options import (INTERRUPTED, Commands, add_config_options, endpoint_option, load_settings,
                                   namespace_option, seed_option)

if TYPE_CHECKING:
    from agent.app.runtime.viewer import LiveViewer


def add_command(commands: Commands) -> None:
    """Add ``run`` and its options.

    Args:
        commands: the `homebot` parser's commands.
    """
    run = commands.add_parser("run", help="run one EQA episode against a simulated home")
    add_config_options(run)
    run.add_argument("--seed", type=seed_option, help="home and scenario seed (default 0)")
    run.add_argument("--suite", type=Path, help="a suite file (homebot suite make); with --scenario, run one of its "
                                                "scenarios in its home")
    run.add_argument("--scenario", metavar="ID", help="the id of the suite's scenario to run, e.g. test-0007")
    run.add_argument("--connect", metavar="ENDPOINT", type=endpoint_option,
                     help="join a running world instead of starting one")
    run.add_argument("--namespace", type=namespace_option,
                     help="key prefix of the world to join (default homebot/default with --connect)")
    run.add_argument("--out", type=Path, default=Path("runs"), help="where run folders go (default ./runs)")
    run.add_argument("--method", choices=("fbe", "semantic", "semantic-no-lsv", "semantic-no-gsv", "lfe"),
                     help="exploration method (default semantic; same as --set explore.method=…)")
    run.add_argument("--stop", choices=("cp", "entropy", "relevance", "budget"),
                     help="stopping rule (default cp: conformal prediction; same as --set stop.rule=…)")
    run.add_argument("--epsilon", type=float,
                     help="accepted miscoverage ε of the conformal set (default 0.3; --set stop.epsilon=…)")
    run.add_argument("--viewer", action="store_true",
                     help="show the episode's recording live in the Rerun viewer: spawned where a display "
                          "exists, else a web viewer served on a local address (printed)")
    run.set_defaults(handler=_run)


def shortcut_overrides(args: argparse.Namespace) -> list[str]:
    """The ``--set`` overrides that ``run``'s shortcut options stand for.

    Args:
        args: the parsed ``run`` command line.

    Returns:
        ``key=value`` overrides for the shortcuts given (--method, --stop, --epsilon), in that order.
    """
    shortcuts = {"explore.method": args.method, "stop.rule": args.stop, "stop.epsilon": args.epsilon}
    return [f"{key}={value}" for key, value in shortcuts.items() if value is not None]


def _run(args: argparse.Namespace) -> int:
    from agent.app.runtime.calibrations import stop_calibration
    from agent.app.runtime.episode_bus import EpisodeBus
    from agent.app.runtime.plugged import PlugError, make_plugged_skills
    from agent.app.runtime.request import RunRequest, new_run_id, process_started_at
    from agent.eqa.calibration import CalibrationError

    started_at = process_started_at()
    try:
        seed, scenario, what = _episode_choice(args)
    except ValueError as error:
        print(f"homebot run: {error}", file=sys.stderr)
        return 2
    args.set.extend(shortcut_overrides(args))
    config = load_settings(args)
    try:
        stop_calibration(config)  # a calibration missing, unreadable or made for other settings
    except CalibrationError as error:
        print(f"homebot run: {error}", file=sys.stderr)
        return 2
    request = RunRequest(seed=seed, config=config, out_root=args.out, connect=args.connect,
                         namespace=args.namespace, scenario=scenario, run_id=new_run_id(seed),
                         viewer=_started_viewer(args.viewer), started_at=started_at)
    print(f"homebot run: {what}, {'joining ' + args.connect if args.connect else 'starting a world'}; "
          f"watch with `homebot watch --run {request.run_id}`", flush=True)
    bus = EpisodeBus.open(request)
    try:
        make_plugged_skills(config.tree, bus.link)  # a skill or port misnamed: no world is started
        bus.start_world()  # now, to come up while the rest of the runtime loads
        from agent.app.runtime.progress import StepPrinter
        from agent.app.runtime.run import RunError, run_episode
    except PlugError as error:
        bus.close()
        print(f"homebot run: {error}", file=sys.stderr)
        return 2
    except BaseException:
        bus.close()
        raise
    try:
        result = run_episode(request, extra_sinks=[StepPrinter(sys.stdout)], bus=bus)
    except RunError as error:
        print(f"homebot run: {error}", file=sys.stderr)
        return 1
    if result["status"] == "interrupted":
        print(f"homebot run: {result['reason']}; run folder: {result['folder']}", file=sys.stderr)
        return INTERRUPTED
    verdict = "correct" if result["correct"] else "wrong"
    if result["status"] == "answered":
        print(f"answer {result['answer']} ({result['answer_text']}); truth {result['ground_truth']} "
              f"({result['ground_truth_text']}): {verdict}, {result['steps']} steps, {result['seconds']:.1f} s")
    else:
        print(f"episode failed: {result['reason']}", file=sys.stderr)
    if "startup_s" in result:
        print(f"first observation {result['startup_s']:.1f} s after `homebot run` started")
    print(f"run folder: {result['folder']}")
    return 0 if result["status"] == "answered" else 1


def _started_viewer(wanted: bool) -> LiveViewer | None:
    """The live viewer ``--viewer`` asks for, started, its address printed; None without it."""
    if not wanted:
        return None
    from agent.app.runtime.viewer import LiveViewer

    viewer = LiveViewer.for_this_machine()
    viewer.start()
    print(f"homebot run: {viewer.describe()}", flush=True)
    return viewer


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
