"""``gauged check-config FILE``: validate a config file and print a one-screen summary."""

from __future__ import annotations

import argparse
import sys

from gauged.config import ConfigError, load_config
from gauged.config.summary import summarize


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "check-config", help="validate a config file and summarise it",
        description="Validate FILE fully (types, unknown keys, cross references, alarm limit order) and "
        "print a summary. Every problem is reported as FILE:LINE key.path: message. Exit 0 if valid, 2 if not.")
    parser.add_argument("file", metavar="FILE", help="YAML config, e.g. config/gauged.example.yaml")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    try:
        config = load_config(args.file)
    except ConfigError as exc:
        for issue in exc.issues:
            print(issue, file=sys.stderr)
        print(f"{args.file}: {len(exc.issues)} problem(s); the config is not valid", file=sys.stderr)
        return 2
    print(summarize(config))
    print(f"{args.file}: valid")
    return 0
