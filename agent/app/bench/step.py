"""`homebot bench step`: one fixed episode per home size, its stages timed, and the speed targets.

Each episode explores to its budget whatever the stopping rule, so runs compare the same steps. By
default the seed's episode runs in a home of 60 m² and one of 300 m², and the report holds, per
home, each stage's median and what the agent spends besides rendering and the VLM; then the
targets, each with its goal and whether it is met:

- agent overhead ÷ render: the episode's wall time less the time the world spends rendering and
  driving the base and the time spent asking the VLM, over the time spent rendering (totals over
  the episode). What remains is transport, fusing frames (tsdf), planning, and the rest: the rest
  of each tick's work and what passes between ticks (waits, snapshots).
- per-step total and render time, 300 m² ÷ 60 m²;
- the map stage's median at steps 35–44 over steps 3–7 (the largest home's episode);
- start-up to the first observation (``startup_s`` of the episode's result, when it has one);
- the agent's resident memory at the end over at step 10, sampled as each step's frame is fused.
"""

from __future__ import annotations

import os
import statistics
import tempfile
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from agent.app.config import Config, load_config
from agent.app.runtime.run import RunRequest, run_episode
from agent.timing import StageTimer
from worlds.home import generate_home
from worlds.spec import dump_spec

STAGES = ("render", "transport", "tsdf", "planning", "drive", "vlm", "vlm_directions", "tick")
#: The home sizes compared by default (m²): the ratios are the second over the first.
AREAS = (60.0, 300.0)
#: The map stage's early and late steps (1-based, inclusive).
EARLY_STEPS, LATE_STEPS = (3, 7), (35, 44)
#: The step whose memory the end's is compared with.
MEMORY_STEP = 10
GOALS = {"overhead": 0.25, "per_step": 1.5, "render": 1.3, "map_late": 1.2, "startup_s": 3.0, "memory": 1.10}
OVERHEAD_COUNTS = ("the episode's wall time less the world's rendering and driving and the VLM's time: transport, "
                   "tsdf, planning, and the rest (the rest of each tick's work, waits between ticks, snapshots)")

Progress = Callable[[str], None]


class MemoryTimer(StageTimer):
    """A `StageTimer` that also samples the process's resident memory whenever a frame has been
    fused into the map (the ``tsdf`` stage: once a step)."""

    def __init__(self) -> None:
        super().__init__()
        self.rss_mb: list[float] = []

    def record(self, stage: str, milliseconds: float) -> None:
        """Add one sample of a stage's time; after the map stage, one of resident memory.

        Args:
            stage: the stage's name.
            milliseconds: how long it took.
        """
        super().record(stage, milliseconds)
        if stage == "tsdf":
            rss = resident_mb()
            if rss is not None:
                self.rss_mb.append(rss)


def resident_mb(pid: int | None = None) -> float | None:
    """A process's resident memory, from ``/proc/<pid>/statm``.

    Args:
        pid: the process; None for this one.

    Returns:
        Megabytes (10⁶ bytes), or None where there is no ``/proc`` or no such process.
    """
    try:
        pages = int(Path(f"/proc/{pid or 'self'}/statm").read_text().split()[1])
    except (OSError, IndexError, ValueError):
        return None
    return pages * os.sysconf("SC_PAGE_SIZE") / 1e6


def bench_step(config: Config, seed: int, areas: Sequence[float] = AREAS,
               progress: Progress | None = None) -> dict[str, Any]:
    """Run the seed's episode in a home of each area, one after the other in this process, and
    measure it against the targets.

    Args:
        config: the settings (the stopping rule is set to the budget).
        seed: the homes' and the episodes' seed.
        areas: the homes' floor areas (m²).
        progress: told a line as each episode starts and ends.

    Returns:
        The report: ``episodes`` (one per area, `episode_report`) and ``targets`` (`step_targets`).

    Raises:
        RunError: an episode could not start.
        KeyboardInterrupt: Ctrl-C during an episode.
    """
    config = load_config(overrides=["stop.rule=budget"], base=config)
    episodes = []
    for area in areas:
        home = generate_home(seed, area_m2=area)
        if progress:
            progress(f"bench step: seed {seed}, {area:g} m² ({home.area_m2:.1f} m², {len(home.rooms)} rooms) …")
        timer = MemoryTimer()
        with tempfile.TemporaryDirectory(prefix="homebot-bench-") as scratch:
            request = RunRequest(seed=seed, config=config, out_root=Path(scratch), scene=dump_spec(home),
                                 save_map=False, record=False)
            result = run_episode(request, timer=timer)
            if result["status"] == "interrupted":  # Ctrl-C ends the bench, not just this episode
                raise KeyboardInterrupt
            snapshot_bytes = (Path(result["folder"]) / "snapshots.jsonl").stat().st_size
        episode = episode_report(timer, result, timer.rss_mb)
        episode.update(area_m2=area, floor_m2=round(home.area_m2, 1), rooms=len(home.rooms),
                       snapshot_bytes=snapshot_bytes)
        episodes.append(episode)
        if progress:
            progress(f"bench step: {area:g} m² done, {episode['steps']} steps in {episode['episode_s']:.1f} s, "
                     f"{episode['status']}")
    return {"seed": seed, "overhead_counts": OVERHEAD_COUNTS, "episodes": episodes, "targets": step_targets(episodes)}


def episode_report(timer: StageTimer, result: dict[str, Any], rss_mb: Sequence[float]) -> dict[str, Any]:
    """One episode's figures: its stages, the agent's overhead, the map stage early and late, memory.

    Args:
        timer: the episode's stages, each stage's samples in order (the map stage's one per step).
        result: the episode's result (``steps``, ``seconds``, ``status``, ``ticks``, maybe ``startup_s``).
        rss_mb: the agent's resident memory after each step's map stage (MB).

    Returns:
        The figures; the overhead's are totals over the episode divided by its steps. A ratio that
        cannot be had (too few steps) is None.
    """
    steps = max(1, int(result.get("steps", 0)))
    total = {stage: sum(values) for stage, values in timer.samples.items()}
    render = total.get("render", 0.0)
    vlm = sum(ms for stage, ms in total.items() if stage.startswith("vlm"))
    drive = total.get("drive", 0.0)
    overhead = 1000.0 * result["seconds"] - render - vlm - drive
    parts = {stage: total.get(stage, 0.0) for stage in ("transport", "tsdf", "planning")}
    parts["the rest"] = overhead - sum(parts.values())
    summary = timer.summary()
    tsdf = timer.samples.get("tsdf", [])
    early, late = _window(tsdf, EARLY_STEPS), _window(tsdf, LATE_STEPS)
    at_step, end = (rss_mb[MEMORY_STEP - 1], rss_mb[-1]) if len(rss_mb) >= MEMORY_STEP else (None, None)
    return {
        "steps": result.get("steps", 0), "status": result["status"], "episode_s": result["seconds"],
        "per_step_ms": 1000.0 * result["seconds"] / steps, "ticks": result["ticks"],
        "startup_s": result.get("startup_s"),
        "stages": {stage: summary[stage] for stage in STAGES if stage in summary},
        "overhead": {"per_step_ms": overhead / steps, "render_per_step_ms": render / steps,
                     "vlm_per_step_ms": vlm / steps, "drive_per_step_ms": drive / steps,
                     "parts_per_step_ms": {k: v / steps for k, v in parts.items()},
                     "over_render": overhead / render if render else None},
        "map_stage": {"early_ms": early, "late_ms": late,
                      "late_over_early": late / early if early and late is not None else None},
        "memory": {f"step_{MEMORY_STEP}_mb": at_step, "end_mb": end,
                   "end_over_step": end / at_step if at_step and end is not None else None},
        "tsdf_ms": list(tsdf), "rss_mb": list(rss_mb),
    }


def _window(samples: Sequence[float], steps: tuple[int, int]) -> float | None:
    """The median of the samples of steps ``first..last`` (1-based), or None with fewer samples."""
    first, last = steps
    return statistics.median(samples[first - 1:last]) if len(samples) >= last else None


def step_targets(episodes: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """The targets over the episodes (`episode_report`'s, each with ``area_m2``), smallest home first:
    each with its goal, its values by home (or pair of homes) and whether they all meet it.

    Ratios between homes are the last episode's over the first's; the map stage's is the largest
    home's. A value that cannot be had is None, and ``note`` says why.

    Args:
        episodes: the episodes.

    Returns:
        The targets: ``name``, ``key``, ``goal``, ``values`` (label -> value or None), ``note`` and
        ``met`` (None when no value could be had).
    """
    homes = {f"{e['area_m2']:g} m²": e for e in episodes}
    small, big = episodes[0], episodes[-1]
    largest = max(episodes, key=lambda e: e["area_m2"])
    pair = f"{big['area_m2']:g}÷{small['area_m2']:g}"
    two = "" if len(episodes) > 1 else "needs two homes (leave out --area)"

    def between(value: Callable[[dict[str, Any]], float]) -> dict[str, float | None]:
        return {pair: value(big) / value(small) if not two else None}

    map_stage = largest["map_stage"]["late_over_early"]
    rows = [
        ("agent overhead ÷ render", "overhead", {k: e["overhead"]["over_render"] for k, e in homes.items()}, ""),
        (f"per-step total {pair}", "per_step", between(lambda e: e["per_step_ms"]), two),
        (f"render {pair} (medians)", "render", between(lambda e: e["stages"]["render"]["median_ms"]), two),
        (f"map stage at steps {LATE_STEPS[0]}–{LATE_STEPS[1]} ÷ {EARLY_STEPS[0]}–{EARLY_STEPS[1]}", "map_late",
         {f"{largest['area_m2']:g} m²": map_stage},
         "" if map_stage is not None else f"{largest['steps']} steps, fewer than {LATE_STEPS[1]}"),
        ("start-up to first observation (s)", "startup_s", {k: e["startup_s"] for k, e in homes.items()},
         "" if all(e["startup_s"] is not None for e in episodes) else "no startup_s in the result"),
        (f"memory at the end ÷ at step {MEMORY_STEP}", "memory",
         {k: e["memory"]["end_over_step"] for k, e in homes.items()},
         "" if all(e["memory"]["end_over_step"] for e in episodes) else f"fewer than {MEMORY_STEP} steps, or no /proc"),
    ]
    targets = []
    for name, key, values, note in rows:
        known = [v for v in values.values() if v is not None]
        targets.append({"name": name, "key": key, "goal": GOALS[key], "values": values, "note": note,
                        "met": all(v <= GOALS[key] for v in known) if known else None})
    return targets


def format_step_report(report: dict[str, Any]) -> str:
    """The `bench_step` report as text: per home its episode, stages, overhead, map stage and
    memory; then each target with its goal, its values and whether it is met.

    Args:
        report: the report.

    Returns:
        The text.
    """
    lines = [f"bench step: seed {report['seed']}, each episode explores its whole budget",
             f"agent overhead = {report['overhead_counts']}"]
    for episode in report["episodes"]:
        lines += _episode_lines(episode)
    lines.append(f"targets{'':<46}{'goal':<8}value")
    for target in report["targets"]:
        values = ", ".join(f"{label} {_figure(value)}" if label not in target["name"] else _figure(value)
                           for label, value in target["values"].items())
        note = f" ({target['note']})" if target["note"] else ""
        verdict = {True: "met", False: "NOT met", None: "n/a"}[target["met"]]
        lines.append(f"  {target['name']:<51}≤ {target['goal']:<6g}{values}{note}: {verdict}")
    lines.append("tick counts every tick, including those that only poll a query in flight. One process runs "
                 "the episodes one after the other: a later one's memory starts where the earlier left it.")
    return "\n".join(lines)


def _episode_lines(episode: dict[str, Any]) -> list[str]:
    overhead, map_stage, memory = episode["overhead"], episode["map_stage"], episode["memory"]
    parts = " + ".join(f"{name} {ms:.1f}" for name, ms in overhead["parts_per_step_ms"].items())
    lines = [
        f"{episode['area_m2']:g} m² ({episode['floor_m2']:g} m², {episode['rooms']} rooms): {episode['steps']} steps, episode "
        f"{episode['episode_s']:.2f} s ({episode['per_step_ms']:.0f} ms per step), {episode['status']}; "
        f"snapshots {episode['snapshot_bytes'] / 1e6:.2f} MB for {episode['ticks']} ticks",
        f"  {'stage':<15}{'count':>6}{'median ms':>11}{'p95 ms':>9}{'max ms':>9}",
        *(f"  {stage:<15}{f['count']:>6}{f['median_ms']:>11.2f}{f['p95_ms']:>9.2f}{f['max_ms']:>9.2f}"
          for stage, f in episode["stages"].items()),
        f"  agent overhead {overhead['per_step_ms']:.1f} ms per step = {parts}",
        f"  render {overhead['render_per_step_ms']:.1f}, drive {overhead['drive_per_step_ms']:.1f}, "
        f"VLM {overhead['vlm_per_step_ms']:.1f} ms per step; "
        f"overhead ÷ render {_figure(overhead['over_render'])}",
        f"  map stage median {_figure(map_stage['early_ms'], ' ms')} at steps {EARLY_STEPS[0]}–{EARLY_STEPS[1]}, "
        f"{_figure(map_stage['late_ms'], ' ms')} at {LATE_STEPS[0]}–{LATE_STEPS[1]}",
        f"  agent memory (resident, after each step's map stage) {_figure(memory[f'step_{MEMORY_STEP}_mb'], ' MB')} "
        f"at step {MEMORY_STEP}, {_figure(memory['end_mb'], ' MB')} at the end",
    ]
    if episode["startup_s"] is not None:
        lines.append(f"  start-up to first observation {episode['startup_s']:.2f} s")
    return lines


def _figure(value: float | None, unit: str = "") -> str:
    return "n/a" if value is None else f"{value:.2f}{unit}"
