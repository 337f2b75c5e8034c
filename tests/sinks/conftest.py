"""Fixtures of the sink tests: readings, and real Zenoh sessions on loopback."""

from __future__ import annotations

import json
import socket
import time
from collections.abc import Iterator

import pytest
import zenoh

from gauged.config.model import ZenohConfig
from gauged.sources.zenoh_session import open_session
from gauged.types import Quality, Reading, ScaleInfo, StageFailure

T0 = 1_700_000_000_000_000_000


def make_reading(i: int = 0, gauge: str = "boiler-pressure", value: float | None = 4.5,
                 quality: Quality = Quality.GOOD, unit: str | None = "bar", locked: bool = True) -> Reading:
    """A reading of frame ``i``: 100 ms of frame time apart."""
    failure = None if value is not None else StageFailure("needle", "no_needle", "no line found")
    return Reading(gauge=gauge, camera="cam1", stamp_ns=T0 + i * 100_000_000, value=value,
                   raw_value=value, unit=unit, quality=quality, confidence=0.9,
                   scale=ScaleInfo(0.0, 10.0, unit, locked), failure=failure)


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


@pytest.fixture
def zenoh_pair() -> Iterator[tuple[zenoh.Session, zenoh.Session]]:
    """(daemon session listening on loopback, client-side peer connected to it); both closed after."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    daemon = open_session(ZenohConfig(mode="peer", listen=[endpoint], multicast_scouting=False))
    conf = zenoh.Config()
    conf.insert_json5("mode", '"peer"')
    conf.insert_json5("scouting/multicast/enabled", "false")
    conf.insert_json5("listen/endpoints", "[]")
    conf.insert_json5("connect/endpoints", json.dumps([endpoint]))
    peer = zenoh.open(conf)
    try:
        deadline = time.monotonic() + 5
        while not peer.info.peers_zid() and time.monotonic() < deadline:
            time.sleep(0.02)
        assert peer.info.peers_zid(), "peer session did not connect on loopback"
        yield daemon, peer
    finally:
        peer.close()
        daemon.close()


@pytest.fixture
def reading():
    """``reading(i=0, gauge=..., value=4.5, quality=GOOD, unit="bar", locked=True) -> Reading``."""
    return make_reading
