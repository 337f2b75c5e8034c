"""``gauged run``: the daemon's main job."""

from __future__ import annotations

import argparse
import logging
import sys

from gauged import __version__
from gauged.config import ConfigError, load_config, load_default_config
from gauged.config.summary import summarize

log = logging.getLogger(__name__)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "run", help="run the daemon (default: replay the bundled demo)",
        description="Run gauged with the given config. Without --config the embedded default is used, which "
        "replays recordings/demo.mcap.")
    parser.add_argument("-c", "--config", metavar="FILE", help="YAML config (default: the embedded demo config)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    try:
        config = load_config(args.config) if args.config else load_default_config()
    except ConfigError as exc:
        for issue in exc.issues:
            print(issue, file=sys.stderr)
        return 2
    print(f"gauged {__version__}")
    print(summarize(config))
    # The processing loop (sources -> reader -> tracking -> alarms -> sinks) is not wired yet
    # (issue 6); until then `run` validates and shows the config it would run.
    log.warning("the daemon loop is not implemented yet: printed the config it would run")
    return 0
