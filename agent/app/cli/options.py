"""Options several `homebot` commands share, and the settings they load.

The commands that run episodes take settings (`--config`, `--set`, `--listen`); those that run a
suite's episodes in worker processes take the suite, the workers and where the worlds are as well.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from agent.app.config import Config, ConfigError, load_config

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
    parser.add_argument("--workers", type=int, default=2, help="parallel episodes, each with its own world")
    parser.add_argument("--limit", type=int, default=None, help="only the first N scenarios")
    parser.add_argument("--out", type=Path, default=Path(out), help=f"{out_help} (default {out})")
    parser.add_argument("--worlds", metavar="ENDPOINTS",
                        help="join running worlds instead of starting one per worker: comma-separated "
                             "[NAMESPACE@]ENDPOINT, e.g. tcp/10.0.0.2:7447,tcp/10.0.0.3:7447 (one worker each)")


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

    Also checks ``--workers`` and ``--worlds``, leaving the parsed addresses in
    ``args.world_addresses`` (None without ``--worlds``).

    Args:
        args: the parsed command line of a command given `add_suite_run_options`.

    Returns:
        The configuration, or None when an option is wrong (the message is on stderr).

    Raises:
        ConfigError: a file or value that cannot be used, naming the key.
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
    return _zenoh_checked(load_config(args.config, [*args.set, *_zenoh_override(args), "bus.listen=[]"]))
