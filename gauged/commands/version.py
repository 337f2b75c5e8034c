"""``gauged version``: print the version of gauged and of the libraries it runs on."""

from __future__ import annotations

import argparse
import platform
from importlib import metadata

from gauged import __version__

LIBRARIES = ("numpy", "opencv-python-headless", "onnxruntime", "eclipse-zenoh", "mcap", "pydantic", "prometheus-client")


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("version", help="print versions", description="Print the gauged version; "
                                   "with --verbose also Python and the key libraries.")
    parser.add_argument("-v", "--verbose", action="store_true", help="also list library versions")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    print(f"gauged {__version__}")
    if args.verbose:
        print(f"python {platform.python_version()} ({platform.machine()})")
        for name in LIBRARIES:
            try:
                print(f"{name} {metadata.version(name)}")
            except metadata.PackageNotFoundError:
                print(f"{name} (not installed)")
    return 0
