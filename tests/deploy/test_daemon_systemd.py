"""The real daemon speaks systemd's notify protocol as deploy/systemd/gauged.service expects.

``gauged --log-format json run`` (the unit's ExecStart) replays the demo recording with
``NOTIFY_SOCKET``, ``WATCHDOG_USEC`` and ``WATCHDOG_PID`` set as systemd sets them, and this test
plays systemd: READY=1 once it is up, WATCHDOG=1 well within the watchdog timeout, RELOADING=1
(with MONOTONIC_USEC) then READY=1 on SIGHUP, an invalid new config refused with its file:line while
the running one is kept, and on SIGTERM STOPPING=1, exit 0 and finished MCAP files. Every datagram
comes from the main process (the kernel's SCM_CREDENTIALS), as NotifyAccess=main requires. A config
error at start exits 2 (RestartPreventExitStatus=2) without READY=1.
"""

from __future__ import annotations

import json
import signal
import statistics
import time
from pathlib import Path

import pytest
import yaml
from mcap.reader import make_reader

from tests.deploy.daemon_process import (
    NotifyListener,
    demo_config,
    free_port,
    http_get,
    require_daemon_inputs,
    running_daemon,
    write_config,
)

WATCHDOG_USEC = 2_000_000  # systemd's WatchdogSec=2s; the unit has 30 s, shorter here to keep the test short
START_TIMEOUT_S = 60.0  # models load in ~2 s here; generous for a loaded CI machine
RELOAD_TIMEOUT_S = 60.0
DEMO_GAUGES = {"boiler-pressure", "steam-line", "feed-tank-temp", "header-pressure"}

pytestmark = [pytest.mark.slow, pytest.mark.timeout(240)]


def monotonic_usec() -> int:
    return time.clock_gettime_ns(time.CLOCK_MONOTONIC) // 1000


def configured_gauges(port: int, timeout: float = 10.0) -> set[str]:
    """The gauges the daemon serving metrics on ``port`` runs (``gauged_scale_locked`` has one series each)."""
    deadline = time.monotonic() + timeout
    while True:
        try:
            text = http_get(f"http://127.0.0.1:{port}/metrics", timeout=2).decode()
            break
        except OSError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.2)
    return {line.split('gauge="', 1)[1].split('"', 1)[0]
            for line in text.splitlines() if line.startswith("gauged_scale_locked{")}


def json_log(stderr: str) -> list[dict]:
    lines = []
    for line in stderr.splitlines():
        try:
            entry = json.loads(line)
        except ValueError:
            continue
        if isinstance(entry, dict):
            lines.append(entry)
    return lines


def watchdog_pings(notes) -> list[float]:
    return [n.at for n in notes if n.get("WATCHDOG") == "1"]


def line_of(text: str, needle: str) -> int:
    """1-based number of the first line of ``text`` equal to ``needle`` once stripped."""
    return next(i for i, line in enumerate(text.splitlines(), 1) if line.strip() == needle)


def test_daemon_notifies_ready_watchdog_reload_and_stopping(tmp_path: Path) -> None:
    require_daemon_inputs()
    port = free_port()
    out = tmp_path / "out"
    original = demo_config(out, port)
    config_path = write_config(tmp_path / "gauged.yaml", original)
    listener = NotifyListener()
    figures: dict[str, float] = {}
    try:
        env = {"NOTIFY_SOCKET": listener.path, "WATCHDOG_USEC": str(WATCHDOG_USEC)}
        with running_daemon(config_path, tmp_path, env, watchdog_pid="self") as daemon:
            fail = daemon.describe

            # -- start: READY=1 once sources and sinks are up ------------------------------------
            ready = listener.wait_for(lambda n: "READY" in n.fields or "WATCHDOG" in n.fields,
                                      START_TIMEOUT_S, alive=daemon.alive)
            assert ready.get("READY") == "1", f"WATCHDOG=1 before READY=1: {listener.summary()}"
            assert ready.get("STATUS") == "reading 4 gauge(s)"
            figures["time_to_ready_s"] = ready.at - daemon.started
            assert configured_gauges(port) == DEMO_GAUGES, fail()

            # -- watchdog: WATCHDOG=1 again and again, never WATCHDOG_USEC apart ----------------
            pings = watchdog_pings(listener.collect(4.0))
            assert len(pings) >= 2, f"{listener.summary()}\n{fail()}"
            gaps = [b - a for a, b in zip(pings, pings[1:])]
            figures["watchdog_pings_in_4s"] = len(pings)
            figures["watchdog_median_gap_s"] = statistics.median(gaps)
            figures["watchdog_max_gap_s"] = max(gaps)
            assert max(gaps) < WATCHDOG_USEC / 1e6, f"systemd would have killed it: gaps {gaps}"

            # -- SIGHUP with a valid, changed config: RELOADING=1 + MONOTONIC_USEC, READY=1, swapped --
            changed = yaml.safe_load(yaml.safe_dump(original))
            changed["gauges"] = [g for g in changed["gauges"] if g["id"] != "header-pressure"]
            changed["gauges"][0]["alarms"]["high"] = 7.5
            write_config(config_path, changed)
            before = monotonic_usec()
            daemon.signal(signal.SIGHUP)
            reloading = listener.wait_key("RELOADING", 10, alive=daemon.alive)
            assert reloading["RELOADING"] == "1"
            stamp = int(reloading["MONOTONIC_USEC"])  # an integer, on the CLOCK_MONOTONIC systemd compares with
            assert before <= stamp <= monotonic_usec(), (before, stamp)
            ready = listener.wait_key("READY", RELOAD_TIMEOUT_S, alive=daemon.alive)
            assert ready["READY"] == "1" and ready.get("STATUS") == "reloaded", listener.summary()
            figures["valid_reload_s"] = ready.at - reloading.at
            assert configured_gauges(port) == DEMO_GAUGES - {"header-pressure"}, "the new config is not running"
            assert len(watchdog_pings(listener.collect(3.0))) >= 2, f"no watchdog after reload: {listener.summary()}"

            # -- SIGHUP with an invalid config: refused with file:line, old config kept, still alive --
            broken = yaml.safe_load(yaml.safe_dump(changed))
            broken["gauges"][0]["scale"]["max"] = -1  # below scale.min (0)
            write_config(config_path, broken)
            bad_line = line_of(config_path.read_text(), "max: -1")
            daemon.signal(signal.SIGHUP)
            reloading = listener.wait_key("RELOADING", 10, alive=daemon.alive)
            int(reloading["MONOTONIC_USEC"])
            ready = listener.wait_key("READY", RELOAD_TIMEOUT_S, alive=daemon.alive)
            assert ready.get("STATUS") == "reload refused; running the previous config"
            figures["refused_reload_s"] = ready.at - reloading.at
            pings = watchdog_pings(listener.collect(3.0))
            assert daemon.alive(), fail()
            assert len(pings) >= 2, f"no watchdog after a refused reload: {listener.summary()}"
            assert configured_gauges(port) == DEMO_GAUGES - {"header-pressure"}, "the running config was not kept"
            refused = [e["msg"] for e in json_log(daemon.stderr()) if e["msg"].startswith("reload refused")]
            assert refused, fail()
            print("refused reload logged:", refused[0].replace("\n", " | "))
            assert f"{config_path}:{bad_line} gauges[0].scale.max: must be greater than scale.min" in refused[0]

            # -- SIGTERM: STOPPING=1, exit 0 --------------------------------------------------------
            term_at = time.monotonic()
            daemon.signal(signal.SIGTERM)
            listener.wait_key("STOPPING", 20, alive=daemon.alive)
            code = daemon.proc.wait(30)
            figures["stop_s"] = time.monotonic() - term_at
            assert code == 0, fail()
            # NotifyAccess=main: systemd drops datagrams from any other pid than the main process.
            assert {n.pid for n in listener.received} == {daemon.pid}, listener.summary()
            assert not [e for e in json_log(daemon.stderr()) if e.get("level") == "error"
                        and not e["msg"].startswith("reload refused")], fail()
    finally:
        listener.close()
        print("measured:", ", ".join(f"{k}={v:.2f}" for k, v in figures.items()))

    # -- the MCAP files are finished: a summary (footer, statistics) that the reader finds ----------
    files = sorted((out / "mcap").glob("*.mcap"))
    assert len(files) == 2, files  # one per running config: the start and the valid reload
    for path in files:
        with path.open("rb") as stream:
            summary = make_reader(stream).get_summary()
        assert summary is not None, f"{path.name} was not finished (no summary section)"
        topics = {channel.topic for channel in summary.channels.values()}
        assert "/gauged/readings" in topics, (path.name, topics)
        assert summary.statistics is not None and summary.statistics.message_count > 0, path.name


def test_invalid_config_at_start_exits_2_without_ready(tmp_path: Path) -> None:
    """A config error at start is exit status 2 (RestartPreventExitStatus=2) and never READY=1."""
    require_daemon_inputs()
    config = demo_config(tmp_path / "out", free_port())
    config["gauges"][1]["camera"] = "cam9"
    config_path = write_config(tmp_path / "gauged.yaml", config)
    bad_line = line_of(config_path.read_text(), "camera: cam9")
    listener = NotifyListener()
    try:
        env = {"NOTIFY_SOCKET": listener.path, "WATCHDOG_USEC": str(WATCHDOG_USEC)}
        with running_daemon(config_path, tmp_path, env, watchdog_pid="self") as daemon:
            code = daemon.proc.wait(60)
            assert code == 2, daemon.describe()
            assert f"{config_path}:{bad_line} gauges[1].camera: names camera 'cam9'" in daemon.stderr()
        assert not [n for n in listener.collect(0.2) if "READY" in n.fields], listener.summary()
    finally:
        listener.close()
