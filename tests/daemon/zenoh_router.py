"""A Zenoh router for the tests: the real ``zenohd`` when it is on PATH, else zenoh-python in router mode.

``zenohd`` is not a Python package and neither PyPI nor Debian ships it, so on a machine without
it the router is a zenoh-python session opened with ``mode: "router"`` in a process of its own: the
same routing code as ``zenohd`` (without its plugins, which gauged does not use). Either way the
router reads a JSON5 config file (e.g. ``deploy/zenoh/router.json5``) and listens on the endpoint
given, and the test talks to it over TCP only.

Run it by hand the same way::

    python -m tests.daemon.zenoh_router deploy/zenoh/router.json5 --listen tcp/127.0.0.1:7447
"""

from __future__ import annotations

import argparse
import json
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def router_argv(config: Path, listen: str) -> list[str]:
    """The command line of a router reading ``config`` and listening on ``listen`` (only)."""
    zenohd = shutil.which("zenohd")
    if zenohd is not None:
        return [zenohd, "-c", str(config), "-l", listen, "--no-multicast-scouting"]
    return [sys.executable, "-m", "tests.daemon.zenoh_router", str(config), "--listen", listen]


def wait_listening(host: str, port: int, proc: subprocess.Popen, timeout: float) -> bool:
    """True once ``host:port`` accepts TCP connections; False if ``proc`` exits or ``timeout`` passes."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and proc.poll() is None:
        with socket.socket() as sock:
            sock.settimeout(0.2)
            if sock.connect_ex((host, port)) == 0:
                return True
        time.sleep(0.05)
    return False


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("config", type=Path, help="a zenohd JSON5 config file")
    parser.add_argument("--listen", action="append", default=[], help="endpoint(s) to listen on, instead of the file's")
    args = parser.parse_args(argv)

    import zenoh

    config = zenoh.Config.from_file(str(args.config))
    config.insert_json5("mode", '"router"')
    config.insert_json5("scouting/multicast/enabled", "false")
    if args.listen:
        config.insert_json5("listen/endpoints", json.dumps(args.listen))
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    session = zenoh.open(config)
    print(f"zenoh router {session.zid()} listening on {args.listen or 'the configured endpoints'}", flush=True)
    stop.wait()
    session.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
