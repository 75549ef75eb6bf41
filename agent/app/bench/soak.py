"""`homebot bench soak`: episodes side by side for a while, each lane an agent process with a world
of its own (its own namespace and port), checked for failures, for crosstalk between the worlds,
and for memory that grows.

Lane i of R runs seeds i, i + R, … i + (K − 1)R one after the other, round after round (K seeds a
lane), so no two worlds hold the same home at once and memory is compared like for like; it checks
each result against what its own world must have answered (`crosstalk_problems`):
the reset's scenario is the seed's, the evaluator's record is of that scenario's target and saw at
least a head frame per step (a world reset by another lane mid-episode would have started over),
and where replies name their namespace, it is the lane's. Every minute (``sample_s``) the resident
memory of each agent and world process is sampled; each episode's line also carries its agent's and
its world's right after it, and growth is measured between episodes of one seed: after the lane's
last episode against after the same seed's episode in the first round (the models loaded, the
homes built once) and in the middle round (is it still growing once warm). Episodes and samples
are appended to a JSON-lines file as they come; progress goes to stderr.
"""

from __future__ import annotations

import json
import multiprocessing
import queue
import shutil
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

from agent.app.bench.step import resident_mb
from agent.app.config import Config
from agent.app.runtime.pool import quiet_worker
from agent.app.runtime.world_process import WorldProcess
from worlds.bus.session import free_tcp_endpoint

Progress = Callable[[str], None]


@dataclass(frozen=True)
class Lane:
    """One lane of the soak: its number, and the namespace and endpoint of its world."""

    index: int
    namespace: str
    endpoint: str


def crosstalk_problems(result: dict[str, Any], namespace: str, seed: int) -> list[str]:
    """What in an episode's result shows it met another lane's world, one sentence each.

    Args:
        result: the episode's result (`agent.app.runtime.run.run_episode`).
        namespace: the lane's namespace.
        seed: the seed the lane asked for.

    Returns:
        The problems; empty when the result is its own world's.
    """
    problems = []
    if result.get("namespace") != namespace:
        problems.append(f"the agent ran under {result.get('namespace')!r}, not {namespace!r}")
    question, answer, target = _expected(seed)
    if "question" in result and (result["question"], result["ground_truth"]) != (question, answer):
        problems.append(f"the reset was answered with another home's scenario {result['question']!r} "
                        f"(seed {seed} asks {question!r})")
    evaluation = result.get("evaluation") or {}
    if "namespace" in evaluation and evaluation["namespace"] != namespace:
        problems.append(f"the evaluator's record came from {evaluation['namespace']!r}")
    if "target" in evaluation and evaluation["target"] != target:
        problems.append(f"the evaluator's record is of another target: {evaluation['target']} (seed {seed}: {target})")
    if "head_frames" in evaluation and evaluation["head_frames"] < result.get("steps", 0):
        problems.append(f"the evaluator saw {evaluation['head_frames']} head frames in {result['steps']} steps: "
                        "the world was reset during the episode")
    return problems


@lru_cache(maxsize=64)
def _expected(seed: int) -> tuple[str, str, dict[str, Any]]:
    """(question, answer letter, the evaluator's target as JSON carries it) of the seed's scenario."""
    from worlds.home import generate_home
    from worlds.scenario import make_scenario
    from worlds.targets import question_target

    home = generate_home(seed)
    scenario = make_scenario(home, seed)
    return scenario.question, scenario.answer, json.loads(json.dumps(question_target(home, scenario.target).to_dict()))


def soak(config: Config, runs: int, minutes: float, out: Path, episodes: int | None = None,
         sample_s: float = 60.0, progress: Progress | None = None, seeds: int = 5) -> dict[str, Any]:
    """Run ``runs`` lanes side by side until ``minutes`` have passed (or each ran ``episodes``),
    every lane at least one episode, and report.

    Args:
        config: the episodes' settings (its camera and Zenoh configuration file go to the worlds).
        runs: how many lanes (agent processes, worlds) at once.
        minutes: how long lanes start new episodes.
        out: the JSON-lines file episodes and memory samples are appended to (emptied first); the
            worlds' logs go beside it, in ``<out stem>-worlds/``.
        episodes: the most episodes per lane, or None for as many as fit.
        sample_s: seconds between memory samples.
        progress: told a line as each episode ends and each sample is taken.
        seeds: the seeds each lane goes round.

    Returns:
        The report (`format_soak_report`); ``interrupted`` when Ctrl-C ended it.
    """
    say = progress or (lambda line: None)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("")
    logs = out.parent / f"{out.stem}-worlds"
    logs.mkdir(exist_ok=True)
    lanes = [Lane(i, f"homebot/soak-{i}", free_tcp_endpoint()) for i in range(runs)]
    worlds = [WorldProcess(lane.namespace, lane.endpoint, config.camera, logs / f"world-{lane.index}.log",
                           zenoh_config=config.bus.zenoh_config) for lane in lanes]
    context = multiprocessing.get_context("spawn")
    inbox = context.Queue()
    until = time.time() + minutes * 60.0
    agents = [context.Process(target=_lane, args=(lane, config, runs, seeds, until, episodes, inbox),
                              name=f"agent-{lane.index}") for lane in lanes]
    for agent in agents:
        agent.start()
    state = _Soak(out, time.monotonic(), {f"agent-{i}": a.pid for i, a in enumerate(agents)}
                  | {f"world-{i}": w.process.pid for i, w in enumerate(worlds)}, say)
    interrupted = False
    try:
        _gather(state, inbox, agents, worlds, sample_s, runs)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        for agent in agents:
            agent.terminate()
        for agent in agents:
            agent.join(10.0)
        state.sample("end")
        for world in worlds:
            world.stop()
    report = state.report(lanes, runs, minutes, episodes, sample_s, seeds)
    report.update(interrupted=interrupted, world_logs=str(logs))
    state.append({"kind": "report", **report})
    return report


def _lane(lane: Lane, config: Config, runs: int, seeds: int, until: float, episodes: int | None,
          outbox: Any) -> None:
    """A lane's agent process: episodes one after the other against the lane's world, each result
    (with its crosstalk check) put on ``outbox``, then ``done``."""
    quiet_worker()
    from agent.app.runtime.request import RunRequest
    from agent.app.runtime.run import RunError, run_episode

    scratch = Path(tempfile.mkdtemp(prefix=f"homebot-soak-agent-{lane.index}-"))
    n = 0
    try:
        while n == 0 or (time.time() < until and (episodes is None or n < episodes)):
            seed = lane.index + runs * (n % seeds)
            request = RunRequest(seed=seed, config=config, out_root=scratch, connect=lane.endpoint,
                                 namespace=lane.namespace, run_id=f"soak-{lane.index}-{n}", save_map=False,
                                 record=False)
            try:
                result = run_episode(request)
            except RunError as error:
                result = {"status": "failed", "reason": str(error), "namespace": lane.namespace}
            outbox.put({"kind": "episode", "lane": lane.index, "namespace": lane.namespace, "episode": n,
                        "seed": seed, "status": result["status"], "reason": result.get("reason"),
                        "steps": result.get("steps", 0), "seconds": result.get("seconds"),
                        "crosstalk": crosstalk_problems(result, lane.namespace, seed),
                        "agent_rss_mb": _rounded(resident_mb())})
            shutil.rmtree(scratch / request.run_id, ignore_errors=True)
            n += 1
    finally:
        outbox.put({"kind": "done", "lane": lane.index})
        shutil.rmtree(scratch, ignore_errors=True)


class _Soak:
    """What the soak has seen so far: episodes, memory samples; each appended to ``out`` as it comes."""

    def __init__(self, out: Path, started: float, pids: dict[str, int | None], say: Progress) -> None:
        self.out, self.started, self.pids, self.say = out, started, pids, say
        self.episodes: list[dict[str, Any]] = []
        self.samples: list[dict[str, Any]] = []

    def append(self, line: dict[str, Any]) -> None:
        with open(self.out, "a", encoding="utf-8") as file:
            file.write(json.dumps(line, ensure_ascii=False) + "\n")

    def minutes(self) -> float:
        return (time.monotonic() - self.started) / 60.0

    def episode(self, line: dict[str, Any]) -> None:
        pid = self.pids.get(f"world-{line['lane']}")
        line["world_rss_mb"] = None if pid is None else _rounded(resident_mb(pid))
        self.episodes.append(line)
        self.append(line)
        failed = sum(e["status"] != "answered" for e in self.episodes)
        crossed = sum(bool(e["crosstalk"]) for e in self.episodes)
        self.say(f"  [{self.minutes():5.1f} min] lane {line['lane']} episode {line['episode']} (seed {line['seed']}): "
                 f"{line['status']}, {line['steps']} steps; {len(self.episodes)} done, {failed} failed, "
                 f"{crossed} with crosstalk")

    def sample(self, mark: str) -> None:
        rss = {name: None if pid is None else _rounded(resident_mb(pid)) for name, pid in self.pids.items()}
        line = {"kind": "memory", "mark": mark, "t_min": round(self.minutes(), 3), "rss_mb": rss}
        self.samples.append(line)
        self.append(line)
        self.say(f"  [{self.minutes():5.1f} min] memory ({mark}): "
                 + ", ".join(f"{name} {mb if mb is not None else '-'} MB" for name, mb in rss.items()))

    def report(self, lanes: list[Lane], runs: int, minutes: float, episodes: int | None,
               sample_s: float, seeds: int) -> dict[str, Any]:
        failures = [{key: e[key] for key in ("lane", "episode", "seed", "status", "reason")}
                    for e in self.episodes if e["status"] != "answered"]
        crosstalk = [{"lane": e["lane"], "episode": e["episode"], "seed": e["seed"], "problem": problem}
                     for e in self.episodes for problem in e["crosstalk"]]
        return {
            "runs": runs, "minutes": minutes, "episodes_per_lane": episodes, "seeds_per_lane": seeds,
            "elapsed_min": round(self.minutes(), 2),
            "episodes": len(self.episodes), "failures": failures,
            "crosstalk": {"checked": len(self.episodes), "problems": crosstalk},
            "lanes": [_lane_row(lane, [e for e in self.episodes if e["lane"] == lane.index]) for lane in lanes],
            "memory": {"sample_s": sample_s, "samples": self.samples,
                       "processes": _memory_rows(self.samples, self.episodes, runs, seeds)},
        }


def _gather(state: _Soak, inbox: Any, agents: list[Any], worlds: list[WorldProcess], sample_s: float,
            runs: int) -> None:
    """Take the lanes' episodes as they come and sample memory on time, until every lane is done."""
    done: set[int] = set()
    next_sample = time.monotonic() + sample_s
    while len(done) < runs:
        try:
            line = inbox.get(timeout=max(0.05, min(1.0, next_sample - time.monotonic())))
        except queue.Empty:
            line = None
        if line is not None and line["kind"] == "done":
            done.add(line["lane"])
            agents[line["lane"]].join(10.0)  # reaped, so that no sample reads a finished process
            state.pids[f"agent-{line['lane']}"] = None
        elif line is not None:
            state.episode(line)
        if time.monotonic() >= next_sample:
            state.sample("minute")
            next_sample += sample_s
        for index, agent in enumerate(agents):
            if index not in done and agent.exitcode is not None and inbox.empty():
                done.add(index)
                state.episode({"kind": "episode", "lane": index, "namespace": f"homebot/soak-{index}", "episode": -1,
                               "seed": -1, "status": "failed", "steps": 0, "seconds": None, "crosstalk": [],
                               "reason": f"the lane's agent process exited with code {agent.exitcode}",
                               "agent_rss_mb": None})
        for index, world in enumerate(worlds):
            if world.process.poll() is not None and state.pids.get(f"world-{index}") is not None:
                state.pids[f"world-{index}"] = None
                state.say(f"  world {index} exited with code {world.process.returncode}")


def _lane_row(lane: Lane, episodes: list[dict[str, Any]]) -> dict[str, Any]:
    seconds = [e["seconds"] for e in episodes if e.get("seconds") is not None]
    return {"lane": lane.index, "namespace": lane.namespace, "endpoint": lane.endpoint, "episodes": len(episodes),
            "failures": sum(e["status"] != "answered" for e in episodes),
            "seconds_per_episode": round(sum(seconds) / len(seconds), 1) if seconds else None}


def _memory_rows(samples: list[dict[str, Any]], episodes: list[dict[str, Any]], runs: int, seeds: int
                 ) -> dict[str, dict[str, Any]]:
    """Per process: resident memory after its lane's last episode, and after the same seed's episode
    in the lane's first round and in its middle round; the most seen (episode ends and timed
    samples); the growth from first to last and from middle to last (fractions)."""
    rows = {}
    for kind, index in ((kind, index) for kind in ("agent", "world") for index in range(runs)):
        name = f"{kind}-{index}"
        after = {e["episode"]: e[f"{kind}_rss_mb"] for e in episodes
                 if e["lane"] == index and e["episode"] >= 0 and e.get(f"{kind}_rss_mb") is not None}
        seen = list(after.values()) + [s["rss_mb"][name] for s in samples if s["rss_mb"].get(name) is not None]
        last = max(after, default=None)
        first, middle = (None, None) if last is None else (last % seeds, last % seeds + seeds * (last // seeds // 2))
        mb = {key: after.get(n) for key, n in (("first_mb", first), ("middle_mb", middle), ("last_mb", last))}
        rows[name] = {**mb, "max_mb": max(seen) if seen else None, "episodes": len(after), "rounds": len(after) / seeds,
                      "growth": _growth(mb["first_mb"], mb["last_mb"]),
                      "late_growth": _growth(mb["middle_mb"], mb["last_mb"])}
    return rows


def _growth(before: float | None, after: float | None) -> float | None:
    return round(after / before - 1.0, 4) if before and after else None


def _rounded(mb: float | None) -> float | None:
    return None if mb is None else round(mb, 1)


def format_soak_report(report: dict[str, Any]) -> str:
    """The soak's report as tables: the verdict, the lanes, memory per process and its samples.

    Args:
        report: the report of `soak`.

    Returns:
        The text.
    """
    crosstalk = report["crosstalk"]
    lines = [f"bench soak: {report['runs']} lanes for {report['minutes']:g} min ({report['elapsed_min']:.1f} min "
             f"elapsed{', interrupted' if report['interrupted'] else ''}): {report['episodes']} episodes, "
             f"{len(report['failures'])} failures, {len(crosstalk['problems'])} crosstalk problems in "
             f"{crosstalk['checked']} checked"]
    lines += [f"  failure: lane {f['lane']} episode {f['episode']} (seed {f['seed']}): {f['status']}: {f['reason']}"
              for f in report["failures"]]
    lines += [f"  crosstalk: lane {c['lane']} episode {c['episode']} (seed {c['seed']}): {c['problem']}"
              for c in crosstalk["problems"]]
    lines.append(f"{'lane':>4}  {'namespace':<16} {'endpoint':<22} {'episodes':>8} {'failures':>8} {'s/episode':>9}")
    for lane in report["lanes"]:
        per = "-" if lane["seconds_per_episode"] is None else f"{lane['seconds_per_episode']:.1f}"
        lines.append(f"{lane['lane']:>4}  {lane['namespace']:<16} {lane['endpoint']:<22} {lane['episodes']:>8} "
                     f"{lane['failures']:>8} {per:>9}")
    memory = report["memory"]
    lines.append(f"memory (MB)  {'first':>7} {'middle':>7} {'last':>7} {'max':>7} {'growth':>7} {'late':>7}  "
                 f"(after the lane's last episode and its seed's in the first and middle round of "
                 f"{report['seeds_per_lane']}; growth first→last, late middle→last)")
    for name, row in memory["processes"].items():
        cells = [_cell(row[key]) for key in ("first_mb", "middle_mb", "last_mb", "max_mb")]
        cells += ["-" if row[key] is None else f"{100 * row[key]:+.1f}%" for key in ("growth", "late_growth")]
        lines.append(f"{name:<12} " + " ".join(f"{cell:>7}" for cell in cells))
    samples = memory["samples"]
    lines.append("samples (MB) at minute " + " ".join(f"{s['t_min']:>6.1f}" for s in samples))
    for name in memory["processes"]:
        lines.append(f"{name:<22} " + " ".join(f"{_cell(s['rss_mb'].get(name)):>6}" for s in samples))
    return "\n".join(lines)


def _cell(mb: float | None) -> str:
    return "-" if mb is None else f"{mb:.0f}"
