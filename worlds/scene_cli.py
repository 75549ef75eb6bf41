"""The `homebot scene` commands and the world benchmark, as functions the CLI calls.

- ``scene new --seed N [--rooms K] [--area M2] [--out FILE]`` writes a generated home's scene spec
  (stdout without ``--out``);
- ``scene show FILE [--out PNG]`` draws the spec's home from above (worlds.topdown);
- ``scene check FILE`` validates a spec: one summary line and exit 0, or its problems and exit 1.
`main(argv)` takes the words after ``scene`` and returns the exit code (2 for bad arguments).
`bench_world` measures generation, PyBullet build and rendering for homes of a few sizes.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from worlds.freespace import free_space
from worlds.home import AREA_RANGE, ROOM_COUNT, HomeSpec, generate_home
from worlds.robot import ROBOT_RADIUS, CameraConfig
from worlds.sim import World
from worlds.spec import SpecError, dump_spec, read_spec_file
from worlds.topdown import draw_home

log = logging.getLogger(__name__)

#: Headings rendered per home when measuring frames per second.
BENCH_VIEWS = 8


def summary(home: HomeSpec) -> str:
    """One line about a home: its size and what is in it.

    Args:
        home: the home.

    Returns:
        The line.
    """
    storage = sum(piece.storage is not None for piece in home.furniture)
    hidden = sum(item.relation in ("inside", "under") for item in home.objects)
    return (f"seed {home.seed}: {len(home.rooms)} rooms, {home.area_m2:.1f} m², {len(home.doorways)} doorways, "
            f"{len(home.furniture)} furniture ({storage} storage), "
            f"{len(home.objects)} objects ({hidden} inside or under)")


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="homebot scene", description="Make, draw and check scene specs.")
    commands = parser.add_subparsers(dest="command", required=True)
    new = commands.add_parser("new", help="generate a home and write its scene spec")
    new.add_argument("--seed", type=int, required=True, help="the home's seed (>= 0)")
    new.add_argument("--rooms", type=int, help=f"room count, {ROOM_COUNT[0]}..{ROOM_COUNT[1]} (drawn when left out)")
    new.add_argument("--area", type=float,
                     help=f"floor area in m², {AREA_RANGE[0]:g}..{AREA_RANGE[1]:g} (drawn when left out)")
    new.add_argument("--out", type=Path, help="the JSON file to write (stdout when left out)")
    show = commands.add_parser("show", help="draw a scene spec from above as a PNG")
    show.add_argument("file", type=Path)
    show.add_argument("--out", type=Path, help="the PNG to write (default: FILE with .png)")
    check = commands.add_parser("check", help="validate a scene spec")
    check.add_argument("file", type=Path)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run one scene command; 0 on success, 1 for an invalid spec, 2 for bad arguments.

    Args:
        argv: the command line's arguments (``sys.argv[1:]`` when None).

    Returns:
        The exit status.
    """
    try:
        args = _parser().parse_args(argv)
    except SystemExit as exit_:
        return int(exit_.code or 0)
    if args.command == "new":
        return _new(args.seed, args.rooms, args.area, args.out)
    try:
        home = read_spec_file(args.file)
    except SpecError as error:
        count = len(error.errors)
        print(f"{args.file}: invalid scene spec ({count} problem{'s' if count != 1 else ''})", file=sys.stderr)
        for line in error.errors:
            print(f"  {line}", file=sys.stderr)
        return 1
    if args.command == "check":
        print(f"{args.file}: ok, {summary(home)}")
        return 0
    out = draw_home(home, args.out or args.file.with_suffix(".png"))
    print(f"wrote {out}")
    return 0


def _new(seed: int, rooms: int | None, area: float | None, out: Path | None) -> int:
    try:
        home = generate_home(seed, rooms, area)
    except ValueError as error:
        print(f"homebot scene new: {error}", file=sys.stderr)
        return 2
    text = json.dumps(dump_spec(home), indent=1)
    if out is None:
        print(text)
    else:
        out.write_text(text + "\n", encoding="utf-8")
        print(f"wrote {out}: {summary(home)}", file=sys.stderr)
    return 0


def open_pose(home: HomeSpec) -> tuple[float, float]:
    """The most open spot the robot can reach: the free cell farthest from any obstacle.

    Args:
        home: the home.

    Returns:
        The spot (x, y).
    """
    space = free_space(home, ROBOT_RADIUS)
    clearance = np.where(space.components == space.main_component(), space.clearance_m, -1.0)
    row, col = np.unravel_index(int(np.argmax(clearance)), clearance.shape)
    return space.cell_centre(int(row), int(col))


def bench_world(areas: tuple[float, ...] = (60.0, 150.0, 300.0), repeats: int = 3) -> dict[str, Any]:
    """Generation time, PyBullet build time and 320x240 render rate for homes of each area.

    Each area is measured on seeds 0..repeats-1; the figures are medians over those homes.
    Rendering looks around from the most open reachable spot in `BENCH_VIEWS` headings.

    Args:
        areas: the floor areas (m²).
        repeats: the homes per area.

    Returns:
        The report: medians by area.
    """
    camera = CameraConfig(width=320, height=240)
    world = World(camera)
    results: dict[str, Any] = {"camera": f"{camera.width}x{camera.height}", "repeats": repeats, "areas": {}}
    try:
        for area in areas:
            rows = [_bench_one(world, seed, area) for seed in range(repeats)]
            results["areas"][f"{area:g}"] = {key: statistics.median(row[key] for row in rows) for key in rows[0]}
    finally:
        world.close()
    return results


def _bench_one(world: World, seed: int, area: float) -> dict[str, float]:
    started = time.perf_counter()
    home = generate_home(seed, area_m2=area)
    generated = time.perf_counter()
    world.build(home)
    built = time.perf_counter()
    x, y = open_pose(home)
    render_started = time.perf_counter()
    for k in range(BENCH_VIEWS):
        world.place((x, y, k * 2 * math.pi / BENCH_VIEWS))
        world.observe()
    rendered = time.perf_counter()
    return {
        "generate_s": generated - started,
        "build_s": built - generated,
        "render_fps": BENCH_VIEWS / (rendered - render_started),
        "rooms": len(home.rooms),
        "furniture": len(home.furniture),
        "objects": len(home.objects),
    }
