"""`homebot bench`: speed of a step's stages, the arm's skills, LFE planning and the world; the
world's answers to malformed requests (fuzz); episodes side by side for a while (soak); how fast
faults are reported (faults); evaluation episodes per minute, process pool against Ray (eval)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from agent.app.cli.options import INTERRUPTED, Commands, add_config_options, count_option, load_settings


def add_command(commands: Commands) -> None:
    """Add ``bench`` and its benchmarks with their options.

    Args:
        commands: the `homebot` parser's commands.
    """
    bench = commands.add_parser("bench", help="measure speed")
    benches = bench.add_subparsers(dest="bench", required=True)
    step = benches.add_parser("step", help="per-stage time of each step over one fixed episode per home size, "
                                           "and the speed targets")
    add_config_options(step)
    step.add_argument("--seed", type=int, default=0)
    step.add_argument("--area", type=float, default=None,
                      help="run only a home of this floor area in m² (60..300; default: 60 and 300)")
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
    fuzz = benches.add_parser("fuzz", help="malformed requests to a world started for it: how each is refused, "
                                           "crashes, hangs, the world's memory and log")
    fuzz.add_argument("--messages", type=int, default=100_000, help="malformed requests to send (default 100000)")
    fuzz.add_argument("--seed", type=int, default=0, help="the requests' seed (default 0)")
    fuzz.add_argument("--json", action="store_true", help="print the figures as JSON")
    fuzz.set_defaults(handler=_bench_fuzz)

    soak = benches.add_parser("soak", help="episodes side by side, each against a world of its own, for a while: "
                                           "failures, crosstalk between the worlds, memory over time")
    add_config_options(soak)
    soak.add_argument("--runs", type=int, default=4, help="episodes at once, each with its own world (default 4)")
    soak.add_argument("--minutes", type=float, default=30.0,
                      help="how long lanes start new episodes (default 30; each lane runs at least one)")
    soak.add_argument("--episodes", type=int, default=None, help="at most this many episodes per lane")
    soak.add_argument("--seeds", type=int, default=5,
                      help="seeds each lane goes round, so memory is compared between episodes of one seed (default 5)")
    soak.add_argument("--sample-s", type=float, default=60.0, help="seconds between memory samples (default 60)")
    soak.add_argument("--out", type=Path, default=Path("runs/bench-soak.jsonl"),
                      help="episodes and memory samples, appended as they come (emptied first; default "
                           "runs/bench-soak.jsonl)")
    soak.add_argument("--json", action="store_true", help="print the report as JSON")
    soak.set_defaults(handler=_bench_soak)

    faults = benches.add_parser("faults", help="seconds until a killed or frozen world, a closed port, a namespace "
                                               "no world serves and Ctrl-C on homebot run are reported, and how")
    faults.add_argument("--repeats", type=int, default=3, help="times each fault is caused (default 3)")
    faults.add_argument("--json", action="store_true", help="print the figures as JSON")
    faults.set_defaults(handler=_bench_faults)

    evaluation = benches.add_parser("eval", help="evaluation episodes per minute in local worker processes and "
                                                 "on a local Ray cluster, with 1 and 2 workers (docs/scale.md)")
    evaluation.add_argument("--episodes", type=count_option, default=6, help="episodes per run (default 6)")
    evaluation.add_argument("--budget", type=count_option, default=8, help="steps per episode (default 8)")
    evaluation.add_argument("--workers", default="1,2", help="worker counts, comma separated (default 1,2)")
    evaluation.add_argument("--no-ray", action="store_true", help="the process pool alone")
    evaluation.add_argument("--json", action="store_true", help="print the figures as JSON")
    evaluation.set_defaults(handler=_bench_eval)


def _bench_fuzz(args: argparse.Namespace) -> int:
    from agent.app.bench import dump
    from agent.app.bench.fuzz import bench_fuzz, format_fuzz_report
    from agent.app.runtime.world_process import WorldStartError

    if args.messages < 1:
        print(f"homebot bench fuzz: --messages must be at least 1, got {args.messages}", file=sys.stderr)
        return 2
    if args.seed < 0:
        print(f"homebot bench fuzz: --seed {args.seed} must not be negative", file=sys.stderr)
        return 2
    try:
        report = bench_fuzz(args.messages, args.seed, progress=lambda line: print(line, file=sys.stderr, flush=True))
    except WorldStartError as error:
        print(f"homebot bench fuzz: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("homebot bench fuzz: interrupted", file=sys.stderr)
        return INTERRUPTED
    print(dump(report) if args.json else format_fuzz_report(report))
    return 0 if report["crashes"] == 0 and report["hangs"] == 0 else 1


def _bench_faults(args: argparse.Namespace) -> int:
    from agent.app.bench import dump
    from agent.app.bench.faults import bench_faults, format_faults_table

    if args.repeats < 1:
        print(f"homebot bench faults: --repeats must be at least 1, got {args.repeats}", file=sys.stderr)
        return 2
    report = bench_faults(args.repeats, lambda line: print(line, file=sys.stderr, flush=True))
    print(dump(report) if args.json else format_faults_table(report))
    return 0


def _bench_eval(args: argparse.Namespace) -> int:
    from agent.app.bench import dump
    from agent.app.bench.eval_speed import bench_eval, format_eval_table
    from agent.app.runtime.ray_backend import RayError, ray_module

    try:
        workers = [count_option(word) for word in args.workers.split(",") if word.strip()]
    except argparse.ArgumentTypeError as error:
        print(f"homebot bench eval: --workers: {error}", file=sys.stderr)
        return 2
    try:
        if not args.no_ray:
            ray_module()
        report = bench_eval(args.episodes, args.budget, workers or [1], not args.no_ray,
                            lambda line: print(line, file=sys.stderr, flush=True))
    except RayError as error:
        print(f"homebot bench eval: {error} (or --no-ray)", file=sys.stderr)
        return 2
    print(dump(report) if args.json else format_eval_table(report))
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
    from agent.app.bench import dump
    from agent.app.bench.step import AREAS, bench_step, format_step_report
    from agent.app.runtime.run import RunError
    from worlds.home import AREA_RANGE

    low, high = AREA_RANGE
    if args.area is not None and not low <= args.area <= high:
        print(f"homebot bench step: --area {args.area:g} is not in {low:g}..{high:g}", file=sys.stderr)
        return 2
    if args.seed < 0:
        print(f"homebot bench step: --seed {args.seed} must not be negative", file=sys.stderr)
        return 2
    areas = AREAS if args.area is None else (args.area,)
    try:
        report = bench_step(load_settings(args), args.seed, areas,
                            lambda line: print(line, file=sys.stderr, flush=True))
    except RunError as error:
        print(f"homebot bench step: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("homebot bench step: interrupted", file=sys.stderr)
        return INTERRUPTED
    print(dump(report) if args.json else format_step_report(report))
    return 0


def _bench_soak(args: argparse.Namespace) -> int:
    import math

    from agent.app.bench import dump
    from agent.app.bench.soak import format_soak_report, soak

    for name, value, least in (("--runs", args.runs, 1), ("--episodes", args.episodes, 1), ("--seeds", args.seeds, 1)):
        if value is not None and value < least:
            print(f"homebot bench soak: {name} must be at least {least}, got {value}", file=sys.stderr)
            return 2
    for name, value in (("--minutes", args.minutes), ("--sample-s", args.sample_s)):
        if not (math.isfinite(value) and value > 0):
            print(f"homebot bench soak: {name} must be a number above 0, got {value}", file=sys.stderr)
            return 2
    args.set.insert(0, "bus.listen=[]")  # agents connect to their worlds; --listen still applies
    report = soak(load_settings(args), args.runs, args.minutes, args.out, args.episodes, args.sample_s,
                  lambda line: print(line, file=sys.stderr, flush=True), args.seeds)
    print(dump(report) if args.json else format_soak_report(report))
    print(f"episodes and memory samples: {args.out}; world logs: {report['world_logs']}", file=sys.stderr)
    if report["interrupted"]:
        return INTERRUPTED
    return 1 if report["failures"] or report["crosstalk"]["problems"] else 0
