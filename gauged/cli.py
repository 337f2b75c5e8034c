"""The ``gauged`` command line: one sub-command per module in :mod:`gauged.commands`."""

from __future__ import annotations

import argparse
import importlib
import logging
import sys

from gauged import __version__
from gauged.logging_setup import configure_logging

# Each module exposes register(subparsers); the order here is the order in --help.
COMMAND_MODULES = (
    "gauged.commands.run",
    "gauged.commands.replay",
    "gauged.commands.read",
    "gauged.commands.commission",
    "gauged.commands.eval",
    "gauged.commands.synth",
    "gauged.commands.check_config",
    "gauged.commands.version",
)

EXIT_OK, EXIT_RUNTIME, EXIT_USAGE = 0, 1, 2

DESCRIPTION = """\
gauged reads analog gauges (pressure, temperature, level) from camera frames that arrive over
Eclipse Zenoh or from MCAP recordings, smooths the readings, raises alarms on out-of-range values,
and publishes everything to Zenoh, MCAP files and Prometheus.

examples:
  gauged run                              replay the bundled demo with the embedded default config
  gauged run --config /etc/gauged/gauged.yaml
  gauged check-config config/gauged.example.yaml
  gauged version

exit codes: 0 ok, 1 runtime failure, 2 usage or configuration error."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # argparse exits 2 on usage errors already; keep the hint short
        self.print_usage(sys.stderr)
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message}\n(see '{self.prog} --help')\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="gauged", description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--log-format", choices=("human", "json"), default="human",
                        help="stderr log lines: human-readable (default) or one JSON object per line (journald)")
    parser.add_argument("--log-level", choices=("debug", "info", "warning", "error"), default="info",
                        help="least severe level logged (default: info)")
    parser.add_argument("-V", "--version", action="version", version=f"gauged {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help(sys.stderr)
        return EXIT_USAGE
    configure_logging(args.log_format, args.log_level)
    try:
        return int(args.func(args))
    except KeyboardInterrupt:
        return EXIT_RUNTIME
    except Exception:  # a bug or an environment failure: say so once, with the trace in the log
        logging.getLogger("gauged").exception("gauged %s failed", args.command)
        return EXIT_RUNTIME
