"""``gauged run``: the daemon. Signals, systemd notifications, reload, and the live terminal table."""

from __future__ import annotations

import argparse
import logging
import signal
import sys
import threading
import time
from pathlib import Path

from gauged import __version__
from gauged.daemon.app import Daemon
from gauged.daemon.malloc_arenas import limit_malloc_arenas
from gauged.config import ConfigError, load_config, load_default_config
from gauged.config.model import GaugedConfig
from gauged.config.summary import summarize
from gauged.reader.onnx_model import ModelNotAvailable
from gauged.systemd_notify import SystemdNotifier

log = logging.getLogger(__name__)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "run", help="run the daemon (default: replay the bundled demo)",
        description="Run gauged until stopped (Ctrl-C or SIGTERM). Without --config the embedded default is "
        "used: it replays recordings/demo.mcap, prints a live table, writes MCAP under ./gauged-out/ and "
        "serves metrics on 127.0.0.1:9464. SIGHUP reloads the config file (an invalid new config is refused "
        "and the running one kept). Under systemd (Type=notify) it sends READY=1, WATCHDOG=1, RELOADING=1 "
        "and STOPPING=1.")
    parser.add_argument("-c", "--config", metavar="FILE", help="YAML config (default: the embedded demo config)")
    parser.add_argument("--table", choices=("auto", "always", "never"), default="auto",
                        help="live table of readings on stdout (auto: only when stdout is a terminal)")
    parser.add_argument("--seconds", type=float, default=None,
                        help="stop by itself after this many seconds (for demos and tests)")
    parser.set_defaults(func=run)


def _load(path: str | None) -> GaugedConfig:
    return load_config(path) if path else load_default_config()


def _check_inputs(config: GaugedConfig) -> str | None:
    for camera in config.cameras:
        if camera.source.type == "mcap" and not Path(camera.source.path).is_file():
            return (f"camera {camera.id}: recording {camera.source.path} not found "
                    f"(run from the repository root, or regenerate it: see recordings/README.md)")
    return None


def _table(daemon: Daemon) -> str:
    lines = [f"{'gauge':<20} {'value':>10} {'unit':<7} {'quality':<10} {'scale':<7} alarm"]
    for gauge in daemon.runners:
        reading = daemon.status.readings.get(gauge)
        alarms = [s.level for s in daemon.runners[gauge].tracker.alarm_status() if s.active]
        value = "-" if reading is None or reading.value is None else f"{reading.value:.3g}"
        unit = (reading.unit or "") if reading else ""
        quality = reading.quality.value if reading else "waiting"
        locked = "locked" if daemon.status.locked.get(gauge) else "reading"
        lines.append(f"{gauge:<20} {value:>10} {unit:<7} {quality:<10} {locked:<7} {','.join(alarms) or '-'}")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    try:
        config = _load(args.config)
    except ConfigError as exc:
        for issue in exc.issues:
            print(issue, file=sys.stderr)
        return 2
    problem = _check_inputs(config)
    if problem:
        print(problem, file=sys.stderr)
        return 2
    limit_malloc_arenas()  # before the daemon starts its threads
    notifier = SystemdNotifier()
    if args.log_format == "json":  # keep journald lines machine-readable
        log.info("gauged %s starting: %s", __version__, summarize(config).replace("\n", "; "))
    else:
        print(f"gauged {__version__}\n{summarize(config)}", flush=True)
    reload_requested, stop_requested = threading.Event(), threading.Event()
    signal.signal(signal.SIGHUP, lambda *_: reload_requested.set())
    signal.signal(signal.SIGTERM, lambda *_: stop_requested.set())
    signal.signal(signal.SIGINT, lambda *_: stop_requested.set())
    try:
        daemon = Daemon(config)
        daemon.start()
    except ModelNotAvailable as exc:  # an installation problem: exit 2 so systemd does not restart-loop
        log.error("%s", exc)
        return 2
    notifier.ready(f"reading {len(config.gauges)} gauge(s)")
    watchdog_s = notifier.watchdog_interval_s()
    show_table = args.table == "always" or (args.table == "auto" and sys.stdout.isatty())
    started = time.monotonic()
    last_table = 0.0
    try:
        while not stop_requested.wait(0.5 if watchdog_s is None else min(0.5, watchdog_s / 2)):
            if watchdog_s is not None and daemon.healthy(max_silence_s=watchdog_s / 2):
                notifier.watchdog()
            if reload_requested.is_set():
                reload_requested.clear()
                daemon = _reload(daemon, args.config, notifier)
            if show_table and time.monotonic() - last_table >= 1.0:
                print("\x1b[2J\x1b[H" + _table(daemon), flush=True)
                last_table = time.monotonic()
            if args.seconds is not None and time.monotonic() - started >= args.seconds:
                break
            if daemon.workers and all(w.finished for w in daemon.workers):
                log.info("every source has ended")
                break
    finally:
        notifier.stopping()
        daemon.stop()
    if not show_table and args.log_format != "json":
        print(_table(daemon))
    return 0


def _reload(daemon: Daemon, path: str | None, notifier: SystemdNotifier) -> Daemon:
    """Validate the config file again; swap daemons only when it is valid and starts."""
    notifier.reloading()
    try:
        config = _load(path)
        problem = _check_inputs(config)
        if problem:
            raise ValueError(problem)
    except (ConfigError, ValueError) as exc:
        log.error("reload refused, keeping the running config:\n%s", exc)
        notifier.ready("reload refused; running the previous config")
        return daemon
    daemon.stop()
    fresh = Daemon(config)
    try:
        fresh.start()
    except Exception as exc:
        log.error("the new config failed to start (%s); restarting the previous one", exc)
        fresh = Daemon(daemon.config)
        fresh.start()
    notifier.ready("reloaded")
    log.info("config reloaded")
    return fresh
