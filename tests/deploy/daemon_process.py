"""Run the real ``gauged run`` daemon as a subprocess for the deployment tests, and listen to it.

The daemon replays the bundled demo recording (``recordings/demo.mcap``, four gauges) at real-time
pace in a loop, with Zenoh off, metrics on a free loopback port and every file it writes under the
test's tmp directory. :class:`NotifyListener` is the systemd side of ``sd_notify(3)``: an
``AF_UNIX`` datagram socket whose path goes into ``NOTIFY_SOCKET``.

Every process started here is terminated (then killed) when its context manager exits.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import socket
import struct
import subprocess
import tempfile
import time
import urllib.request
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

import pytest
import yaml

REPO = Path(__file__).resolve().parents[2]
PYTHON = REPO / ".venv" / "bin" / "python"
CROP_MODEL = REPO / "gauged" / "models" / "crop.onnx"
DEMO_MCAP = REPO / "recordings" / "demo.mcap"
DEMO_CONFIG = REPO / "recordings" / "demo.yaml"


def require_daemon_inputs() -> None:
    """Skip unless the daemon can start here: the crop model and the demo recording exist."""
    if not CROP_MODEL.is_file():
        pytest.skip(f"{CROP_MODEL.relative_to(REPO)} is missing: the reader cannot start without the crop model "
                    "(train and export it, see gauged/models/README.md)")
    if not DEMO_MCAP.is_file():
        pytest.skip(f"{DEMO_MCAP.relative_to(REPO)} is missing: regenerate it (see recordings/README.md)")
    if not PYTHON.is_file():
        pytest.skip(f"{PYTHON} not found: create the venv and pip install -e .")


_NO_PROXY = urllib.request.build_opener(urllib.request.ProxyHandler({}))


def http_get(url: str, timeout: float = 5.0) -> bytes:
    """GET a loopback URL, never through a proxy set in the environment."""
    with _NO_PROXY.open(url, timeout=timeout) as response:
        return response.read()


def free_port() -> int:
    """A TCP port free on 127.0.0.1 right now."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def demo_config(out_dir: Path, metrics_port: int) -> dict:
    """recordings/demo.yaml as a live daemon's config: realtime looping replay, outputs under out_dir."""
    config = yaml.safe_load(DEMO_CONFIG.read_text())
    (camera,) = config["cameras"]
    camera["source"].update(path=str(DEMO_MCAP), pace="realtime", loop=True)
    config["outputs"] = {
        "zenoh": {"enabled": False},
        "mcap": {"dir": str(out_dir / "mcap"), "images": "none"},
        "prometheus": {"listen": f"127.0.0.1:{metrics_port}"},
    }
    config["state"] = {"dir": str(out_dir / "state")}
    return config


def write_config(path: Path, config: dict) -> Path:
    path.write_text(yaml.safe_dump(config, sort_keys=False))
    return path


_UCRED = struct.Struct("3i")  # struct ucred: pid, uid, gid


@dataclass
class Notification:
    at: float  # time.monotonic() when received
    fields: dict[str, str]
    pid: int | None  # the sender's pid, as the kernel vouches for it (SCM_CREDENTIALS)

    def __getitem__(self, key: str) -> str:
        return self.fields[key]

    def get(self, key: str, default: str | None = None) -> str | None:
        return self.fields.get(key, default)


class NotifyListener:
    """The systemd end of the notify protocol: records every datagram the daemon sends."""

    def __init__(self) -> None:
        # A short path of its own: AF_UNIX paths are limited to 107 bytes, pytest's tmp_path can be longer.
        self._dir = tempfile.mkdtemp(prefix="gauged-notify-")
        self.path = os.path.join(self._dir, "notify")
        self._sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM | socket.SOCK_CLOEXEC)
        # systemd reads the sender's pid the same way to apply NotifyAccess=main.
        self._sock.setsockopt(socket.SOL_SOCKET, socket.SO_PASSCRED, 1)
        self._sock.bind(self.path)
        self.received: list[Notification] = []
        self._seen = 0  # index of the first notification not yet consumed by wait_for

    def close(self) -> None:
        self._sock.close()
        shutil.rmtree(self._dir, ignore_errors=True)

    def _receive(self, timeout: float) -> Notification | None:
        self._sock.settimeout(max(timeout, 0.001))
        try:
            data, ancillary, _, _ = self._sock.recvmsg(65536, socket.CMSG_SPACE(_UCRED.size))
        except (TimeoutError, socket.timeout):
            return None
        pid = next((_UCRED.unpack_from(cdata)[0] for level, kind, cdata in ancillary
                    if level == socket.SOL_SOCKET and kind == socket.SCM_CREDENTIALS), None)
        fields = dict(line.split("=", 1) for line in data.decode().splitlines() if "=" in line)
        note = Notification(time.monotonic(), fields, pid)
        self.received.append(note)
        return note

    def wait_for(self, predicate: Callable[[Notification], bool], timeout: float, *,
                 alive: Callable[[], bool] = lambda: True) -> Notification:
        """The next notification (after the last one consumed) matching ``predicate``; fails after ``timeout``."""
        deadline = time.monotonic() + timeout
        while True:
            while self._seen < len(self.received):
                note = self.received[self._seen]
                self._seen += 1
                if predicate(note):
                    return note
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise AssertionError(f"no matching notification within {timeout:.0f} s; got {self.summary()}")
            if not alive():
                # Drain what a dead process left in the socket, then give up.
                if self._receive(0.05) is None:
                    raise AssertionError(f"the daemon exited; notifications: {self.summary()}")
                continue
            self._receive(min(remaining, 0.25))

    def wait_key(self, key: str, timeout: float, **kwargs) -> Notification:
        return self.wait_for(lambda n: key in n.fields, timeout, **kwargs)

    def collect(self, seconds: float) -> list[Notification]:
        """Everything received during the next ``seconds`` (and marks it consumed)."""
        deadline = time.monotonic() + seconds
        while (remaining := deadline - time.monotonic()) > 0:
            self._receive(min(remaining, 0.25))
        fresh = self.received[self._seen:]
        self._seen = len(self.received)
        return fresh

    def summary(self) -> str:
        if not self.received:
            return "nothing"
        t0 = self.received[0].at
        return ", ".join(f"+{n.at - t0:.2f}s {'|'.join(f'{k}={v}' for k, v in n.fields.items())}"
                         for n in self.received[-30:])


class DaemonProcess:
    """A running ``python -m gauged --log-format json run --config FILE --table never``."""

    def __init__(self, config: Path, workdir: Path, env: Mapping[str, str] | None = None,
                 watchdog_pid: str | None = None) -> None:
        self.config = config
        self.stdout_path = workdir / "daemon.stdout"
        self.stderr_path = workdir / "daemon.stderr"
        full_env = {k: v for k, v in os.environ.items()
                    if k not in ("NOTIFY_SOCKET", "WATCHDOG_USEC", "WATCHDOG_PID")}
        # As the unit sets them (deploy/systemd/gauged.service).
        full_env.update(PYTHONDONTWRITEBYTECODE="1", ORT_DISABLE_TELEMETRY="1", PYTHONUNBUFFERED="1")
        full_env.update(env or {})
        argv = [str(PYTHON), "-m", "gauged", "--log-format", "json", "run", "--config", str(config),
                "--table", "never"]
        if watchdog_pid == "self":
            # systemd sets WATCHDOG_PID to the main process; exec keeps the shell's pid for Python.
            argv = ["/bin/sh", "-c", 'WATCHDOG_PID=$$ exec "$@"', "sh", *argv]
        elif watchdog_pid is not None:
            full_env["WATCHDOG_PID"] = watchdog_pid
        self.started = time.monotonic()
        with open(self.stdout_path, "wb") as out, open(self.stderr_path, "wb") as err:
            self.proc = subprocess.Popen(argv, cwd=workdir, env=full_env, stdin=subprocess.DEVNULL,
                                         stdout=out, stderr=err, start_new_session=True)

    @property
    def pid(self) -> int:
        return self.proc.pid

    def alive(self) -> bool:
        return self.proc.poll() is None

    def signal(self, sig: int) -> None:
        self.proc.send_signal(sig)

    def stderr(self) -> str:
        return self.stderr_path.read_text(errors="replace")

    def stop(self, timeout: float = 20.0) -> int:
        """SIGTERM, wait; SIGKILL if it does not exit in time. Returns the exit code."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                return self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(5)
        return self.proc.returncode

    def describe(self) -> str:
        return f"exit code {self.proc.poll()}; stderr (tail):\n" + "\n".join(self.stderr().splitlines()[-25:])


@contextlib.contextmanager
def running_daemon(config: Path, workdir: Path, env: Mapping[str, str] | None = None,
                   watchdog_pid: str | None = None) -> Iterator[DaemonProcess]:
    daemon = DaemonProcess(config, workdir, env, watchdog_pid)
    try:
        yield daemon
    finally:
        if daemon.alive():
            daemon.stop(timeout=15)
