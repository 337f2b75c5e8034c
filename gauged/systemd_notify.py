"""The systemd notify protocol (``sd_notify(3)``) in a few lines of the standard library.

systemd passes ``NOTIFY_SOCKET`` to a ``Type=notify`` service: a path of an ``AF_UNIX`` datagram
socket, or an abstract-namespace name written with a leading ``@``. Each notification is one
datagram of newline-separated ``KEY=VALUE`` lines. Without ``NOTIFY_SOCKET`` (run by hand, in
tests, in a container) every call is a no-op that returns False.

Example::

    notifier = SystemdNotifier()
    notifier.ready("reading 3 gauges")
    interval = notifier.watchdog_interval_s()   # ping at least this often, None if not asked
    notifier.watchdog()
    notifier.reloading()                        # on SIGHUP, then ready() again
    notifier.stopping()                         # on SIGTERM
"""

from __future__ import annotations

import logging
import os
import socket
import time
from collections.abc import Mapping

log = logging.getLogger(__name__)


def _address(notify_socket: str) -> str | bytes:
    # '@name' is Linux's abstract namespace: the address starts with a NUL byte.
    if notify_socket.startswith("@"):
        return b"\0" + notify_socket[1:].encode()
    return notify_socket


class SystemdNotifier:
    """Sends notifications to systemd; a no-op when the service was not started by it.

    ``environ`` defaults to ``os.environ``; pass a mapping to point it elsewhere (tests).
    """

    def __init__(self, environ: Mapping[str, str] | None = None) -> None:
        env = os.environ if environ is None else environ
        self._socket_path = env.get("NOTIFY_SOCKET") or None
        self._watchdog_usec = env.get("WATCHDOG_USEC")
        self._watchdog_pid = env.get("WATCHDOG_PID")

    @property
    def enabled(self) -> bool:
        """True when a notify socket was given (the service runs under systemd with Type=notify)."""
        return self._socket_path is not None

    def notify(self, *lines: str) -> bool:
        """Send one datagram with the given ``KEY=VALUE`` lines; True if it was sent.

        A failure to send is logged and returned as False, never raised: the daemon must keep
        reading gauges even when the supervisor went away.
        """
        if self._socket_path is None:
            return False
        payload = "\n".join(lines).encode()
        try:
            with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM | socket.SOCK_CLOEXEC) as sock:
                sock.connect(_address(self._socket_path))
                sock.sendall(payload)
        except OSError as err:
            log.warning("sd_notify to %s failed: %s", self._socket_path, err)
            return False
        return True

    def ready(self, status: str | None = None) -> bool:
        """READY=1: start-up is complete (sources and sinks are up)."""
        return self.notify("READY=1", *self._status(status))

    def watchdog(self) -> bool:
        """WATCHDOG=1: the loop that proves frames are processed is alive."""
        return self.notify("WATCHDOG=1")

    def stopping(self, status: str | None = None) -> bool:
        """STOPPING=1: shutdown has begun."""
        return self.notify("STOPPING=1", *self._status(status))

    def reloading(self, status: str | None = None) -> bool:
        """RELOADING=1 with MONOTONIC_USEC (required by ``Type=notify-reload``); send ready() after."""
        usec = time.clock_gettime_ns(time.CLOCK_MONOTONIC) // 1000
        return self.notify("RELOADING=1", f"MONOTONIC_USEC={usec}", *self._status(status))

    def status(self, text: str) -> bool:
        """STATUS=...: one line shown by ``systemctl status``."""
        return self.notify(*self._status(text))

    def watchdog_interval_s(self) -> float | None:
        """How often to send WATCHDOG=1: half of ``WATCHDOG_USEC``, or None if no watchdog is set.

        ``WATCHDOG_PID``, when present, must be this process (systemd's rule for forked helpers).
        """
        if not self._watchdog_usec:
            return None
        if self._watchdog_pid and self._watchdog_pid != str(os.getpid()):
            return None
        try:
            usec = int(self._watchdog_usec)
        except ValueError:
            log.warning("ignoring WATCHDOG_USEC=%r: not an integer", self._watchdog_usec)
            return None
        return usec / 2e6 if usec > 0 else None

    @staticmethod
    def _status(text: str | None) -> tuple[str, ...]:
        return () if text is None else ("STATUS=" + text.replace("\n", " "),)
