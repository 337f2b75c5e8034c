"""sd_notify over a real AF_UNIX datagram socket, path and abstract namespace."""

from __future__ import annotations

import os
import socket
import time
import uuid

import pytest

from gauged.systemd_notify import SystemdNotifier


@pytest.fixture(params=["path", "abstract"])
def listener(request, tmp_path):
    """(NOTIFY_SOCKET value, receiving socket) like systemd's."""
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    if request.param == "path":
        address = str(tmp_path / "notify.sock")
        sock.bind(address)
        name = address
    else:
        name = f"@gauged-test-{uuid.uuid4().hex}"
        sock.bind(b"\0" + name[1:].encode())
    sock.settimeout(2.0)
    yield name, sock
    sock.close()


def receive(sock: socket.socket) -> list[str]:
    return sock.recv(4096).decode().split("\n")


def test_ready_watchdog_stopping_and_status(listener):
    name, sock = listener
    notifier = SystemdNotifier({"NOTIFY_SOCKET": name})
    assert notifier.enabled
    assert notifier.ready("reading 2 gauges")
    assert receive(sock) == ["READY=1", "STATUS=reading 2 gauges"]
    assert notifier.watchdog()
    assert receive(sock) == ["WATCHDOG=1"]
    assert notifier.status("line one\nline two")
    assert receive(sock) == ["STATUS=line one line two"]
    assert notifier.stopping()
    assert receive(sock) == ["STOPPING=1"]


def test_reloading_carries_monotonic_usec(listener):
    name, sock = listener
    before = time.clock_gettime_ns(time.CLOCK_MONOTONIC) // 1000
    assert SystemdNotifier({"NOTIFY_SOCKET": name}).reloading()
    after = time.clock_gettime_ns(time.CLOCK_MONOTONIC) // 1000
    lines = receive(sock)
    assert lines[0] == "RELOADING=1" and lines[1].startswith("MONOTONIC_USEC=")
    assert before <= int(lines[1].split("=")[1]) <= after


def test_without_notify_socket_everything_is_a_no_op():
    notifier = SystemdNotifier({})
    assert not notifier.enabled
    assert notifier.ready() is False and notifier.watchdog() is False and notifier.stopping() is False
    assert notifier.watchdog_interval_s() is None


def test_a_vanished_socket_is_logged_not_raised(tmp_path, caplog):
    notifier = SystemdNotifier({"NOTIFY_SOCKET": str(tmp_path / "gone.sock")})
    assert notifier.ready() is False
    assert any("sd_notify" in r.getMessage() for r in caplog.records)


def test_watchdog_interval_is_half_of_watchdog_usec():
    assert SystemdNotifier({"WATCHDOG_USEC": "20000000"}).watchdog_interval_s() == 10.0
    pid = str(os.getpid())
    assert SystemdNotifier({"WATCHDOG_USEC": "3000000", "WATCHDOG_PID": pid}).watchdog_interval_s() == 1.5
    assert SystemdNotifier({"WATCHDOG_USEC": "3000000", "WATCHDOG_PID": "1"}).watchdog_interval_s() is None
    assert SystemdNotifier({"WATCHDOG_USEC": "soon"}).watchdog_interval_s() is None
