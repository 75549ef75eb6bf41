"""Options several `homebot` commands share, the settings they load, and the types of their values.

The commands that run episodes take settings (`--config`, `--set`, `--listen`); those that run a
suite's episodes in worker processes take the suite, the workers and where the worlds are as well.
The commands that hand out many episodes or homes can hand them to a Ray cluster (`add_ray_option`).
A number an option takes is checked as the command line is parsed (`seed_option`, `count_option`,
`seconds_option`), so a value no run could use is refused, naming the option, before any world starts.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from agent.app.config import Config, ConfigError, load_config
from agent.app.config_bounds import MAX_SEED
from worlds.bus.keys import check_namespace
from worlds.bus.session import check_endpoint

DEFAULT_AGENT_ENDPOINT = "tcp/127.0.0.1:7450"

#: The exit code of a command ended by Ctrl-C (SIGINT): 128 + the signal's number, as shells report it.
INTERRUPTED = 130

#: The sub-parser collection ``add_subparsers`` returns, to which each command adds its parser.
Commands = argparse._SubParsersAction


def add_config_options(parser: argparse.ArgumentParser) -> None:
    """Give a command the options of its settings: a TOML file, ``--set`` overrides, watch endpoints.

    Args:
        parser: the command's parser.
    """
    parser.add_argument("--config", type=Path, help="a TOML file of settings")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="override one setting, e.g. --set vlm.sim.skill=0.6 (repeatable)")
    parser.add_argument("--listen", action="append", metavar="ENDPOINT",
                        help=f"where `homebot watch` can reach this agent (default {DEFAULT_AGENT_ENDPOINT})")
    add_zenoh_config_option(parser)


def add_zenoh_config_option(parser: argparse.ArgumentParser) -> None:
    """Give a command that opens Zenoh sessions ``--zenoh-config FILE``, checked as it is parsed.

    Args:
        parser: the command's parser.
    """
    parser.add_argument("--zenoh-config", metavar="FILE", type=zenoh_config_file,
                        help="a Zenoh configuration file (JSON5) every session of the command, and every "
                             "world it starts, opens with: TLS with mutual authentication, access control "
                             "(docs/hosts.md); same as --set bus.zenoh_config=FILE")


def zenoh_config_file(text: str) -> str:
    """The argparse type of ``--zenoh-config``: a Zenoh configuration file Zenoh accepts.

    Args:
        text: the option's value.

    Returns:
        The file's absolute path (worlds started in other folders find it too).

    Raises:
        argparse.ArgumentTypeError: the file is missing or Zenoh refuses it, saying why.
    """
    from worlds.bus.session import ZenohConfigError, load_zenoh_config

    try:
        load_zenoh_config(text)
    except ZenohConfigError as error:
        raise argparse.ArgumentTypeError(str(error)) from None
    return str(Path(text).resolve())


def add_suite_run_options(parser: argparse.ArgumentParser, out: str, out_help: str) -> None:
    """Give a command that runs a suite's episodes to their full budget in workers its options.

    Args:
        parser: the command's parser.
        out: the default of ``--out``.
        out_help: what goes to ``--out``, for its help text.
    """
    add_config_options(parser)
    parser.add_argument("--suite", type=Path, required=True, help="a suite file (homebot suite make)")
    parser.add_argument("--workers", type=count_option, default=2, help="parallel episodes, each with its own world")
    parser.add_argument("--limit", type=count_option, default=None, help="only the first N scenarios")
    parser.add_argument("--out", type=Path, default=Path(out), help=f"{out_help} (default {out})")
    parser.add_argument("--worlds", metavar="ENDPOINTS",
                        help="join running worlds instead of starting one per worker: comma-separated "
                             "[NAMESPACE@]ENDPOINT, e.g. tcp/10.0.0.2:7447,tcp/10.0.0.3:7447 (one worker each; "
                             "with --ray, one Ray task at a time each)")
    add_ray_option(parser, "episode", "that starts its world on the node it lands on (with --worlds: that joins "
                                      "one no other task is using)")


def add_ray_option(parser: argparse.ArgumentParser, call: str, task: str = "") -> None:
    """Give a command that hands out many calls (episodes, scenes, homes) ``--ray [ADDRESS]``: each
    call a Ray task instead of a call in a local worker process. Given where Ray is not installed,
    the option is refused at once, saying how to install it.

    Args:
        parser: the command's parser.
        call: what one call is, for the help text ("episode", "home").
        task: what else a task does, for the help text ("that starts its world…"; "" for nothing).
    """
    from agent.app.runtime.ray_backend import LOCAL

    parser.add_argument("--ray", nargs="?", const=LOCAL, default=None, metavar="ADDRESS", action=_RayOption,
                        help=f"run each {call} as a Ray task{' ' + task if task else ''}: on a local Ray cluster "
                             "started for "
                             f"this command (--workers {call}s at once), or on the cluster at ADDRESS "
                             "(auto: the one this machine joined with `ray start`; HOST:6379: its head) "
                             "(docs/scale.md; pip install 'homebot[ray]')")


class _RayOption(argparse.Action):
    """``--ray [ADDRESS]``, refused as it is parsed when the ray package is missing."""

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: Any,
                 option_string: str | None = None) -> None:
        from agent.app.runtime.ray_backend import RayError, ray_module

        try:
            ray_module()
        except RayError as error:
            parser.error(str(error))
        setattr(namespace, self.dest, values)


def load_settings(args: argparse.Namespace) -> Config:
    """The settings of a command given `add_config_options`: defaults, file, ``--set``, ``--listen``.

    Args:
        args: the parsed command line.

    Returns:
        The configuration.

    Raises:
        ConfigError: a file or value that cannot be used, naming the key.
    """
    overrides = [*args.set, *_zenoh_override(args)]
    if args.listen:
        overrides.append("bus.listen=" + json.dumps(args.listen))
    return _zenoh_checked(load_config(args.config, overrides))


def _zenoh_checked(config: Config) -> Config:
    """``config``, once its ``bus.zenoh_config`` (from a file or ``--set`` too) proved usable.

    Raises:
        ConfigError: Zenoh cannot use the file, naming the key and saying why.
    """
    from worlds.bus.session import ZenohConfigError, load_zenoh_config

    if config.bus.zenoh_config:
        try:
            load_zenoh_config(config.bus.zenoh_config)
        except ZenohConfigError as error:
            raise ConfigError(f"config: bus.zenoh_config: {error}") from None
    return config


def _zenoh_override(args: argparse.Namespace) -> list[str]:
    """The ``bus.zenoh_config`` override ``--zenoh-config`` stands for, if given."""
    return [f"bus.zenoh_config={json.dumps(args.zenoh_config)}"] if args.zenoh_config else []


def suite_settings(args: argparse.Namespace) -> Config | None:
    """The settings of a suite run (workers need no watcher endpoint), or None after a clear message.

    Also checks ``--worlds``, leaving the parsed addresses in
    ``args.world_addresses`` (None without ``--worlds``).

    Args:
        args: the parsed command line of a command given `add_suite_run_options`.

    Returns:
        The configuration, or None when an option is wrong (the message is on stderr).

    Raises:
        ConfigError: a file or value that cannot be used, naming the key.
    """
    from agent.app.eval.runner import WorldAddress

    try:
        args.world_addresses = [WorldAddress.parse(w) for w in args.worlds.split(",") if w.strip()] if args.worlds else None
    except ValueError as error:
        print(f"homebot: --worlds: {error}", file=sys.stderr)
        return None
    return _zenoh_checked(load_config(args.config, [*args.set, *_zenoh_override(args), "bus.listen=[]"]))


def seed_option(text: str) -> int:
    """The argparse type of a seed: a whole number a world accepts, 0 to `MAX_SEED`.

    Args:
        text: the option's value.

    Returns:
        The seed.

    Raises:
        argparse.ArgumentTypeError: not a whole number, or out of that range.
    """
    return _whole(text, 0, MAX_SEED, f"is not a seed: seeds lie in 0..{MAX_SEED}")


def count_option(text: str) -> int:
    """The argparse type of how many of something (workers, episodes, homes): 1 or more.

    Args:
        text: the option's value.

    Returns:
        The count.

    Raises:
        argparse.ArgumentTypeError: not a whole number, or below 1.
    """
    return _whole(text, 1, None, "must be at least 1")


def seconds_option(text: str) -> float:
    """The argparse type of a time limit: a finite number of seconds above 0.

    Args:
        text: the option's value.

    Returns:
        The seconds.

    Raises:
        argparse.ArgumentTypeError: not a number, not finite, or not above 0.
    """
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text} must be a finite number of seconds above 0")
    return value


def endpoint_option(text: str) -> str:
    """The argparse type of a world's or an agent's Zenoh endpoint, e.g. ``tcp/127.0.0.1:7447``.

    Args:
        text: the option's value.

    Returns:
        The endpoint.

    Raises:
        argparse.ArgumentTypeError: not an endpoint Zenoh can use, saying why.
    """
    return _checked(check_endpoint, text)


def namespace_option(text: str) -> str:
    """The argparse type of a world's key prefix, e.g. ``homebot/default``.

    Args:
        text: the option's value.

    Returns:
        The namespace.

    Raises:
        argparse.ArgumentTypeError: not a namespace, saying why.
    """
    return _checked(check_namespace, text)


def _whole(text: str, least: int, most: int | None, refusal: str) -> int:
    """``text`` as a whole number from ``least`` to ``most`` (None: no most), else an error saying
    ``refusal`` of it; one of more than 40 digits is refused before it is converted."""
    digits = text.strip().removeprefix("-")
    if not digits.isdecimal():
        raise argparse.ArgumentTypeError(f"{text[:40]!r} is not a whole number")
    if len(digits) > 40:
        raise argparse.ArgumentTypeError(f"a whole number of {len(digits)} digits is far too large")
    value = int(text)
    if value < least or (most is not None and value > most):
        raise argparse.ArgumentTypeError(f"{value} {refusal}")
    return value


def _checked(check: Callable[[str], str], text: str) -> str:
    """``check(text)``, its ValueError made the argparse error that names the option."""
    try:
        return check(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None
